"""track.png: one page that shows what a profile learnt — typical frames, marking colours, where the floor usually is,
the light band and the distance histogram with its thresholds — so a user can see whether it learnt their track
(docs/learning.md)."""

from __future__ import annotations

from pathlib import Path

import cv2
import numpy as np

from fearguard.track.floor import USUAL_SHARE
from fearguard.track.learn import Learnt
from fearguard.track.profile import FAMILIAR_AT_REFERENCE, UNFAMILIAR_RATIO, ratio_at


def draw_track(learnt: Learnt, path: str | Path) -> Path:
    """Write the page; returns its path."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    p = learnt.profile
    fig = plt.figure(figsize=(10, 7.5))
    frames = learnt.typical_frames
    for i, img in enumerate(frames[:6]):
        ax = fig.add_subplot(3, 6, i + 1)
        ax.imshow(cv2.cvtColor(img, cv2.COLOR_BGR2RGB))
        ax.set_axis_off()
    fig.text(0.5, 0.97, f"track profile: {p.frames_learnt} frames learnt from {p.source}", ha="center", fontsize=9, wrap=True)
    ax = fig.add_subplot(3, 3, 4)
    colours = p.marking_colours_bgr
    if len(colours):
        ax.imshow(np.clip(colours[None, :, ::-1] / 255.0, 0, 1), aspect="auto")
        ax.set_xticks(range(len(colours)), [f"BGR {tuple(int(v) for v in c)}" for c in colours], fontsize=6, rotation=25)
    else:
        ax.text(0.5, 0.5, "no marking colour seen in most frames", ha="center", va="center", fontsize=8)
        ax.set_xticks([])
    ax.set_yticks([])
    ax.set_title("high-contrast floor colours\nseen in most frames (markings)", fontsize=8)
    ax = fig.add_subplot(3, 3, 5)
    if p.floor is not None:
        ax.imshow(p.floor.usual, cmap="Greens", vmin=0.0, vmax=1.0)
        ax.contour(p.floor.usual, levels=[USUAL_SHARE], colors="crimson", linewidths=0.8)
        ax.set_title(f"where the floor usually is (inside red: read for\nwhat hides it); typical frame {p.floor.hidden_usual:.2f} hidden",
                     fontsize=8)
    else:
        ax.text(0.5, 0.5, "no floor learnt", ha="center", va="center", fontsize=8)
    ax.set_axis_off()
    ax = fig.add_subplot(3, 3, 6)
    b = learnt.brightness[np.isfinite(learnt.brightness)]
    ax.hist(b, bins=40, range=(0, 255), color="grey")
    for v in p.brightness_band:
        ax.axvline(v, color="crimson")
    ax.set_title(f"brightness of the road region:\nlearnt band {p.brightness_band[0]:.0f}–{p.brightness_band[1]:.0f}", fontsize=8)
    ax.set_xlabel("grey level", fontsize=8)
    ax = fig.add_subplot(3, 1, 3)
    ref = p.reference_distance
    c = p.calibration_distances
    ax.hist(c / ref, bins=60, color="steelblue", range=(0, max(UNFAMILIAR_RATIO * 1.2, float(c.max() / ref))))
    ax.axvline(p.typical_distance / ref, color="green", label="fully familiar up to here (the typical recorded frame)")
    ax.axvline(1.0, color="orange", label=f"familiarity {FAMILIAR_AT_REFERENCE:.1f} (reference percentile)")
    ax.axvline(ratio_at(0.5), color="darkorange", ls="--", label="half-familiar (0.5)")
    ax.axvline(UNFAMILIAR_RATIO, color="crimson", label="unfamiliar (0)")
    ax.set_xlabel("distance to the learnt frames / reference distance (the recordings' own, more than 2 s apart)", fontsize=8)
    ax.legend(fontsize=7)
    fig.tight_layout(rect=(0, 0, 1, 0.95))
    out = Path(path)
    fig.savefig(out, dpi=80)
    plt.close(fig)
    return out
