"""What a frame looks like, in a few numbers: the features a track profile compares (docs/learning.md).

Pure functions of the pixels. Four blocks, each cheap at any resolution: three read the frame shrunk to ``WORK_PX`` by
area averaging, the fourth its green channel subsampled to about ``DETAIL_WIDTH_PX``:

- **layout**: the grey thumbnail itself (``THUMB_PX``), 0..1. Where things are: the course ahead, a wall, a box over
  the lane, the camera knocked down. Not normalised: darkness moves it as a whole.
- **colour**: mean and spread of each Lab channel over the lower half (the road or floor ahead), 0..1. A new floor,
  coloured tape, sodium or blue light.
- **edges**: the share of the lower half's gradient energy in each of ``ORIENTATIONS`` directions, and the edge
  density. The track's line directions, the texture of carpet or tarmac, motion blur (few, weak edges).
- **detail**: the lower half's mean gradient at about ``DETAIL_WIDTH_PX`` (log) and its log ratio to the gradient at
  ``WORK_PX``. The grain shrinking loses (a rubber mat's pattern, carpet, a smooth printed mat), and motion blur, which
  takes it away first.

The blocks are concatenated; the profile weighs them so that each counts about equally (``profile.py``).
"""

from __future__ import annotations

import cv2
import numpy as np

THUMB_PX = (16, 12)  # [px] (width, height) of the layout thumbnail: coarse enough to ignore texture and noise
WORK_PX = (64, 48)  # [px] the frame is shrunk to this first: every feature costs the same at any camera resolution
ORIENTATIONS = 8  # [bins] of gradient direction over 0..180 deg
BLOCKS = ("layout", "colour", "edges", "detail")
BLOCK_SIZES = (THUMB_PX[0] * THUMB_PX[1], 6, ORIENTATIONS + 1, 2)
DETAIL_WIDTH_PX = 160  # [px] the detail block reads the frame's green channel subsampled to about this width
EDGE_SCALE = 64.0  # [grey levels / px] a gradient this strong counts as one full edge in the density


def as_bgr(frame: object) -> np.ndarray | None:
    """A frame as a uint8 H×W×3 BGR image, or None when it is not a picture (wrong type, shape, empty)."""
    if not isinstance(frame, np.ndarray) or frame.dtype.hasobject or frame.ndim not in (2, 3) or frame.size == 0:
        return None
    if frame.ndim == 3 and frame.shape[2] not in (1, 3, 4):
        return None
    if min(frame.shape[:2]) < 2:
        return None
    img = frame
    if img.dtype != np.uint8:
        with np.errstate(invalid="ignore", over="ignore"):
            img = np.nan_to_num(img.astype(np.float64), nan=0.0, posinf=255.0, neginf=0.0).clip(0, 255).astype(np.uint8)
    if img.ndim == 2 or img.shape[2] == 1:
        return cv2.cvtColor(np.ascontiguousarray(img.reshape(img.shape[:2])), cv2.COLOR_GRAY2BGR)
    if img.shape[2] == 4:
        return cv2.cvtColor(np.ascontiguousarray(img), cv2.COLOR_BGRA2BGR)
    return np.ascontiguousarray(img)


def shrink(frame: object) -> tuple[np.ndarray, np.ndarray, np.ndarray] | None:
    """The frame at ``WORK_PX`` (BGR), its grey, and the lower half's green channel subsampled to about
    ``DETAIL_WIDTH_PX`` (strided, not resized: the grain is what it must keep), or None when it is not a picture.
    Shrunk once per frame: the area resize is most of a frame's cost (120 µs of 160×120 on the slow test machine), and
    the light reads the same grey."""
    bgr = as_bgr(frame)
    if bgr is None:
        return None
    small = cv2.resize(bgr, WORK_PX, interpolation=cv2.INTER_AREA)
    step = max(1, bgr.shape[1] // DETAIL_WIDTH_PX)
    fine = np.ascontiguousarray(bgr[bgr.shape[0] // 2 :: step, ::step, 1])
    return small, cv2.cvtColor(small, cv2.COLOR_BGR2GRAY), fine


def frame_features(frame: object) -> np.ndarray | None:
    """The feature vector of one frame (``sum(BLOCK_SIZES)`` floats), or None when the frame is not a picture."""
    shrunk = shrink(frame)
    return None if shrunk is None else features_of(*shrunk)


def features_of(small: np.ndarray, grey: np.ndarray, fine: np.ndarray) -> np.ndarray:
    """The feature vector of a frame already shrunk (``shrink``): its parts, in ``shrink``'s order."""
    layout = cv2.resize(grey, THUMB_PX, interpolation=cv2.INTER_AREA).astype(np.float64).ravel() / 255.0
    lower = small[WORK_PX[1] // 2:]
    lab = cv2.cvtColor(lower, cv2.COLOR_BGR2LAB).reshape(-1, 3).astype(np.float64) / 255.0
    colour = np.concatenate([lab.mean(axis=0), lab.std(axis=0)])
    g = grey[WORK_PX[1] // 2:].astype(np.float32)
    gx, gy = cv2.Sobel(g, cv2.CV_32F, 1, 0, ksize=3), cv2.Sobel(g, cv2.CV_32F, 0, 1, ksize=3)
    mag, ang = cv2.cartToPolar(gx, gy)
    bins = (np.mod(ang, np.pi) / np.pi * ORIENTATIONS).astype(np.int64).ravel() % ORIENTATIONS
    energy = np.bincount(bins, weights=mag.ravel().astype(np.float64), minlength=ORIENTATIONS)
    total = float(energy.sum())
    shares = energy / total if total > 0 else np.full(ORIENTATIONS, 1.0 / ORIENTATIONS)
    density = min(1.0, float(mag.mean()) / EDGE_SCALE)
    return np.concatenate([layout, colour, shares, [density], detail(fine, float(mag.mean()))])


def detail(fine: np.ndarray, coarse_gradient: float) -> list[float]:
    """The lower half's fine detail: its mean gradient at about DETAIL_WIDTH_PX (log scale, ~0..1) and the log ratio of
    that to the gradient at WORK_PX (the texture a shrunk picture loses: carpet, a rubber mat's grain; motion blur lowers
    it)."""
    if fine.shape[0] < 3 or fine.shape[1] < 3:
        return [0.0, 0.0]
    f = fine.astype(np.float32)
    g = float(np.abs(cv2.Sobel(f, cv2.CV_32F, 1, 0, ksize=3)).mean() + np.abs(cv2.Sobel(f, cv2.CV_32F, 0, 1, ksize=3)).mean())
    return [float(np.log1p(g)) / 8.0, float(np.log((g + 1.0) / (coarse_gradient + 1.0)))]


def block_slices() -> tuple[slice, ...]:
    """Where each block sits in the feature vector, in ``BLOCKS`` order."""
    ends = np.cumsum(BLOCK_SIZES)
    return tuple(slice(int(e - n), int(e)) for e, n in zip(ends, BLOCK_SIZES, strict=True))
