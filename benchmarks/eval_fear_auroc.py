"""Does fear rank the road pictures the way a person does? AUROC of fear on a labelled set from the real footage.

    python benchmarks/eval_fear_auroc.py [--half eval|tune|all] [--sheet out.png]

The labels (``benchmarks/data/vision_labels.csv``, written by looking at every frame) cover every 25th frame of
project_video.mp4, the 14 stills, darkened / over-exposed / occluded versions of 25 of them, noise and random textures,
and the 20 chessboard photos. Each row says which boundaries a person sees (both/one/none), the exposure, the
markings' contrast, shadows and occluders; *lost* = no boundary seen, bad exposure or a heavy occluder; *degraded* =
lost, or one boundary, weak contrast, heavy shadows or a partial occluder. Every item is shown to a fresh supervisor
(Hough-lane steering, no range sensor, no QR) after 5 frames of its clean base frame (an occluder, darkness or glare
arrives while driving), fear read on the 3rd frame of the item. Half the rows ("tune") were used for tuning; the
others ("eval") are held out. Prints AUROC of fear for lost vs the rest and for degraded vs clean (lost rows left out).
"""

from __future__ import annotations

import argparse
import csv
import sys
from dataclasses import dataclass
from pathlib import Path

import cv2
import numpy as np

import fearguard as fg

ROOT = Path(__file__).resolve().parents[1]
DATA = ROOT.parent / "shared" / "data"
LABELS = ROOT / "benchmarks" / "data" / "vision_labels.csv"
WARM_FRAMES = 5
ITEM_FRAMES = 3

sys.path.insert(0, str(ROOT))
from tests.perturb import darkened, garbage_frames, over_exposed, with_box  # noqa: E402  (one home for the perturbations)

BOXES = {"box middle grey": ((0.25, 0.60, 0.78, 0.86), (110, 110, 110)), "box right white": ((0.55, 0.66, 0.95, 0.90), (240, 240, 240)),
         "box bottom black": ((0.10, 0.72, 0.90, 1.00), (12, 12, 12))}


@dataclass(frozen=True)
class Scored:
    row: dict[str, str]
    fear: float


def video_frames(name: str, wanted: set[int]) -> dict[int, np.ndarray]:
    cap, out, i = cv2.VideoCapture(str(DATA / "road" / "video" / name)), {}, 0
    while len(out) < len(wanted):
        ok, frame = cap.read()
        if not ok:
            break
        if i in wanted:
            out[i] = frame
        i += 1
    cap.release()
    return out


def base_frames(rows: list[dict[str, str]]) -> dict[tuple[str, str], np.ndarray]:
    """The clean frame of every row (source, frame)."""
    wanted = {int(r["frame"]) for r in rows if r["source"] == "project_video.mp4"}
    video = video_frames("project_video.mp4", wanted)
    garbage = garbage_frames()
    out: dict[tuple[str, str], np.ndarray] = {}
    for r in rows:
        key = (r["source"], r["frame"])
        if key in out:
            continue
        if r["source"] == "project_video.mp4":
            out[key] = video[int(r["frame"])]
        elif r["source"] == "garbage":
            out[key] = garbage[r["frame"]]
        elif r["source"].startswith("calibration"):
            out[key] = cv2.imread(str(DATA / "camera_cal" / r["source"]))
        else:
            out[key] = cv2.imread(str(DATA / "road" / "images" / r["source"]))
    return out


def perturbed(frame: np.ndarray, perturbation: str) -> np.ndarray:
    if perturbation == "none":
        return frame
    if perturbation == "dark":
        return darkened(frame, gain=0.12)
    if perturbation == "glare":
        return over_exposed(frame)
    box, colour = BOXES[perturbation]
    return with_box(frame, box, colour)


def fear_of(base: np.ndarray, item: np.ndarray) -> float:
    guard = fg.FearGuard(fg.HoughLaneSteering(), vehicle=fg.VehicleLimits(has_ultrasonic=False, has_qr_localisation=False))
    cmd = None
    for i, frame in enumerate([base] * WARM_FRAMES + [item] * ITEM_FRAMES):
        frame = frame.copy()
        frame[0, 0] = i  # a real camera never repeats itself byte for byte (the frozen-camera check)
        cmd = guard.step(fg.Observation(t_s=0.05 * i, speed_mps=1.0, frame=frame))
    assert cmd is not None
    return cmd.fear


def auroc(positive: list[float], negative: list[float]) -> float:
    """P(a positive scores above a negative), ties half (Mann-Whitney U / n·m): one formula, no dependency."""
    if not positive or not negative:
        return float("nan")
    p, n = np.asarray(positive)[:, None], np.asarray(negative)[None, :]
    return float(((p > n).sum() + 0.5 * (p == n).sum()) / (p.size * n.size))


def load(half: str = "all") -> list[dict[str, str]]:
    with LABELS.open(newline="") as f:
        rows = list(csv.DictReader(f))
    return [r for r in rows if half == "all" or r["half"] == half]


def score(rows: list[dict[str, str]]) -> list[Scored]:
    bases = base_frames(rows)
    out = []
    for r in rows:
        base = bases[(r["source"], r["frame"])]
        out.append(Scored(r, fear_of(base, perturbed(base, r["perturbation"]))))
    return out


def aurocs(scored: list[Scored]) -> tuple[float, float]:
    """(AUROC lost vs the rest, AUROC degraded vs clean among the rows not lost)."""
    lost = [s.fear for s in scored if s.row["lost"] == "1"]
    rest = [s.fear for s in scored if s.row["lost"] == "0"]
    degraded = [s.fear for s in scored if s.row["lost"] == "0" and s.row["degraded"] == "1"]
    clean = [s.fear for s in scored if s.row["degraded"] == "0"]
    return auroc(lost, rest), auroc(degraded, clean)


def contact_sheet(rows: list[dict[str, str]], path: Path, width: int = 320, cols: int = 6) -> None:
    """The items as a person sees them (for checking the labels)."""
    bases = base_frames(rows)
    tiles = []
    for r in rows:
        img = perturbed(bases[(r["source"], r["frame"])], r["perturbation"])
        tile = cv2.resize(img, (width, width * 9 // 16), interpolation=cv2.INTER_AREA)
        cv2.putText(tile, f"{r['item']} {r['visible']}", (6, 22), cv2.FONT_HERSHEY_SIMPLEX, 0.7, (0, 0, 255), 2)
        tiles.append(tile)
    while len(tiles) % cols:
        tiles.append(np.zeros_like(tiles[0]))
    cv2.imwrite(str(path), np.vstack([np.hstack(tiles[k : k + cols]) for k in range(0, len(tiles), cols)]))


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--half", choices=("eval", "tune", "all"), default="eval")
    parser.add_argument("--sheet", type=Path, help="write a contact sheet of the items instead")
    parser.add_argument("--sheet-items", type=int, default=36, help="how many items the sheet shows")
    args = parser.parse_args()
    rows = load(args.half)
    if args.sheet is not None:
        contact_sheet(rows[: args.sheet_items], args.sheet)
        return
    scored = score(rows)
    lost, degraded = aurocs(scored)
    n_lost = sum(s.row["lost"] == "1" for s in scored)
    n_deg = sum(s.row["lost"] == "0" and s.row["degraded"] == "1" for s in scored)
    print(f"{args.half}: {len(scored)} items ({n_lost} lost, {n_deg} degraded, {len(scored) - n_lost - n_deg} clean): "
          f"AUROC lost {lost:.3f} (goal ≥ 0.85), degraded vs clean {degraded:.3f} (goal ≥ 0.75)")
    for s in sorted(scored, key=lambda s: s.fear):
        if (s.row["lost"] == "1" and s.fear < 0.5) or (s.row["degraded"] == "0" and s.fear > 0.3):
            print(f"   {s.row['item']:>4} {s.row['source']} {s.row['frame']} {s.row['perturbation']}: fear {s.fear:.2f} "
                  f"(lost {s.row['lost']}, degraded {s.row['degraded']})")


if __name__ == "__main__":
    main()
