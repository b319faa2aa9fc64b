"""The light's colour, read off the paint: per-channel gains that turn the white tape grey again.

Under a coloured light (a warm lamp, a tinted window, gym-duckietown's domain randomisation) white tape is no longer
unsaturated and yellow paint's hue moves, so fixed colour thresholds find neither. Each channel is scaled by the
light (von Kries); dividing by the colour of the white tape — the light's colour — gives the paint its own colours back.

Which pixels are the white tape: among the bright marking-like pixels (ridges) the two paints differ most in blue
against red and green — yellow reflects almost no blue, white all of it — and their ratio is the paints' own whatever
the light. So the log-chroma b = log(B / √(G·R)) of those pixels is split in two by Otsu's threshold, and the bluer
class is the white tape when the split is clear: classes at least SPLIT_MIN apart, each a plausible share, the bluer
class's median colour no darker than the other's (white paint reflects every channel at least as yellow does; the
mat beside a dark tile seam is a ridge too, and under a tint as blue as the tape it can outnumber it in the bluer
class). A split that is not clear is taken when its own consequence bears it out: under the light it gives, YELLOW_EXPLAINED of the
other class reads as yellow paint (``looks_yellow``). A tinted scene is not lit by one multiplicative light alone
(gym-duckietown's domain randomisation adds light and colours each tile): there the yellow keeps more blue than the
white tape's light would leave it, and the two paints lie only ~0.5 apart in plain view of both. The gains
are kept only if they leave the plain road no less grey than it was (a mat or asphalt is near grey under the same
light): that rejects a split of yellow into pale and saturated dashes with no white tape in view. The gains are 1
when the plain colours already call WHITE_EXPLAINED of the white class white: then the light is white enough, and a
lighter tile or pale dashes taken for the white class tint nothing. Otherwise even a faint tint is the light: on tape
as bright as gym-duckietown's near tape (lightness ~215) a few per cent of green lift the HLS saturation past the white
test and turn the yellow's hue out of its band (gains of 0.93-1.07, once rounded to 1, left a randomised town map
without either paint for 20 s). A frame
that cannot tell (one paint in view) keeps the light measured before (ground_lanes.GroundMemory). Under a tint
measured (or held), a ridge on the white tape's side of the split (``Light.white_b_min``) is white tape too, though
still saturated under the light: domain randomisation gives each tile its own tint, and the next tile's tape, divided
by the light of the near one's, is too saturated for the plain white test (ground_lanes.marking_masks).

Written by hand (a 64-bin histogram and a few sums): OpenCV's white balance (xphoto) is not in the opencv-python
wheels, and it balances on the whole picture (grass, sky, walls) rather than on the paint.
"""

from __future__ import annotations

from collections.abc import Callable
from typing import NamedTuple

import cv2
import numpy as np

from fearguard.vision.medians import median

MIN_PIXELS = 50  # [-] fewer bright ridge pixels than this (of every 4th pixel): no estimate (nothing painted in view)
SPLIT_MIN = 0.6  # [log-chroma] the two paints' classes must be this far apart (Duckietown's: 0.9-1.4; one paint: < 0.5)
YELLOW_EXPLAINED = 0.5  # [-] a split that is not clear: this share of the other class must read as yellow under its light
SHARE_RANGE = (0.1, 0.9)  # [-] the white class's share of the bright ridge pixels (both paints in view)
GREY_TOLERANCE = 0.05  # [-] the gains may raise the road's channel spread by at most this
WHITE_EXPLAINED = 0.5  # [-] the plain colours call this share of the white class white: the light is white enough
BINS, B_RANGE = 64, (-3.0, 1.5)  # histogram of b (Duckietown's yellow: -2 ... -1.2, white: -0.9 ... -0.3)


def _spread(bgr: np.ndarray) -> float:
    """Channel spread of a colour, (max − min) / mean: 0 for grey."""
    return float((bgr.max() - bgr.min()) / max(float(bgr.mean()), 1e-9))


def _otsu(values: np.ndarray) -> tuple[float, float, float]:
    """Otsu's split of values (binned over B_RANGE, outliers in the end bins): (threshold, distance between the two
    class means, share above the threshold)."""
    lo, hi = B_RANGE
    width = (hi - lo) / BINS
    hist = np.bincount(np.clip(((values - lo) / width).astype(np.int64), 0, BINS - 1), minlength=BINS).astype(np.float64)
    centres = lo + width * (np.arange(BINS) + 0.5)
    below = np.cumsum(hist)[:-1]
    total = float(hist.sum())
    above = total - below
    sums = np.cumsum(hist * centres)[:-1]
    mean_below = sums / np.maximum(below, 1)
    mean_above = (float((hist * centres).sum()) - sums) / np.maximum(above, 1)
    k = int(np.argmax(below * above * (mean_above - mean_below) ** 2))
    return lo + width * (k + 1), float(mean_above[k] - mean_below[k]), float(above[k] / max(total, 1.0))


class Light(NamedTuple):
    """The light measured off one frame's paint."""

    gains: np.ndarray  # (B, G, R): ones for white light
    white_b_min: float | None  # the split between the paints in b (a ridge bluer than this is on the white tape's side)


def blue_chroma(bgr: np.ndarray, dtype: type = np.float32) -> np.ndarray:
    """b = log(B / √(G·R)) of every pixel (channels + 1: black has a chroma), BGR (..., 3) → (...)."""
    px = bgr.astype(dtype) + 1.0
    return np.log(px[..., 0] / np.sqrt(px[..., 1] * px[..., 2]))


def measure_light(
    bgr: np.ndarray, paint: np.ndarray, on_road: np.ndarray, looks_white: np.ndarray,
    looks_yellow: Callable[[np.ndarray], np.ndarray] | None = None,
) -> Light | None:
    """The light: (B, G, R) gains that make the white paint grey, and the split between the paints in b, from the
    bright marking-like pixels ``paint`` and the rest of the road ``on_road`` (bool masks over the BGR image; every
    4th pixel is used); ones (no split) when the plain colours already call most of the white class white
    (``looks_white``: unsaturated as it is); None when this frame cannot tell (one paint, too few pixels, a split that
    would tint the road, or one that is not clear and not borne out by ``looks_yellow``: an HLS image → bool, yellow
    paint by colour)."""
    bgr, paint, on_road, looks_white = bgr[::2, ::2], paint[::2, ::2], on_road[::2, ::2], looks_white[::2, ::2]
    px = bgr[paint].astype(np.float64) + 1.0
    if len(px) < MIN_PIXELS:
        return None
    b = blue_chroma(bgr[paint], np.float64)
    threshold, split, share = _otsu(b)
    clear = split >= SPLIT_MIN
    if (not clear and looks_yellow is None) or not SHARE_RANGE[0] <= share <= SHARE_RANGE[1]:
        return None
    whites = b > threshold
    light = median(px[whites], axis=0)  # the white tape's colour: the light's
    if float(light.sum()) < float(median(px[~whites], axis=0).sum()):
        return None  # white paint reflects every channel at least as yellow does: a darker bluer class is the mat
    if np.count_nonzero(looks_white[paint][whites]) >= WHITE_EXPLAINED * np.count_nonzero(whites):
        return Light(np.ones(3), None) if clear else None  # white light explains the white class (of a clear split)
    ground = bgr[on_road & ~paint]
    if len(ground) < MIN_PIXELS:
        return None
    gains = light.mean() / light
    road_colour = median(ground, axis=0).astype(np.float64) + 1.0
    if _spread(road_colour * gains) > _spread(road_colour) + GREY_TOLERANCE:
        return None
    if not clear and looks_yellow is not None:  # the other class must be the yellow paint under this light
        others = bgr[paint][~whites].reshape(-1, 1, 3)
        if np.count_nonzero(looks_yellow(balanced_hls(others, gains))) < YELLOW_EXPLAINED * len(others):
            return None
    return Light(gains, threshold)


def is_neutral(gains: np.ndarray | None) -> bool:
    """True when the gains change nothing (none estimated, or all 1)."""
    return gains is None or bool(np.all(gains == 1.0))


def balanced_hls(bgr: np.ndarray, gains: np.ndarray) -> np.ndarray:
    """HLS of the BGR image under white light: each channel scaled by its gain (clipped to 255)."""
    scaled = cv2.multiply(bgr, (*(float(g) for g in gains), 1.0), dtype=cv2.CV_8U)  # rounds, saturates at 255
    return cv2.cvtColor(scaled, cv2.COLOR_BGR2HLS)
