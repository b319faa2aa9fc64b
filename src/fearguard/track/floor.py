"""The track's floor: the colours the car drives on, and where the picture usually shows them (docs/learning.md).

A wall close ahead, the car pointing off the course, a person or a box on the track, the camera knocked down: each
hides floor that normal driving showed in that part of the picture. Learnt from the recordings:

- the floor's colours: ``FLOOR_COLOURS`` Lab colours (k-means) of the patch just ahead of the car's nose (the bottom
  middle of the picture, ``NOSE_ROWS`` × ``NOSE_COLUMNS``), where a car driving its course sees its own floor, and a
  match radius (the ``MATCH_PERCENTILE``-th percentile of the patch pixels' distance to their nearest colour);
- ``usual``: per cell of a ``FLOOR_PX`` thumbnail, the share of learnt frames in which it showed floor;
- ``texture_low``: per cell, how fine-grained the floor there is at the least (the ``TEXTURE_PERCENTILE``-th percentile,
  over the learnt frames in which the cell showed a floor colour, of its mean grey-level gradient at ``TEXTURE_PX``).

A cell **shows floor** when its colour is within the radius of a floor colour and it is not much smoother than the floor
there ever was (texture at least ``SMOOTH_RATIO`` × ``texture_low``): a box of the floor's own colour — an orange box on
an orange wooden floor, a black one on dark concrete — has the colour and none of the grain (issue 34's boxes: by colour
alone, none of 23 such frames on the wood floor of ``deeppicar-tape`` read as heavily hidden; with the grain, all). A
floor that was smooth on the recordings (a plain mat, ``texture_low`` ≈ 0) asks nothing of the texture.

A frame's **hidden floor** is the share of the cells that usually show floor (``usual`` ≥ ``USUAL_SHARE``, weighted by
it) that do not now. It is read against the recordings' own median (``hidden_usual``: contaminated recordings — a few
laps that also face a wall now and then — move a median least): up to the typical frame's share is calm, the rest
counts linearly up to all hidden (``as_occlusion``).

Written by hand (a few array operations on a 32×24 thumbnail): a colour-class membership map is not a library call.
The texture is OpenCV's Sobel gradient, area-averaged per cell.
"""

from __future__ import annotations

import math
import warnings
from collections.abc import Sequence
from dataclasses import dataclass, replace
from functools import cached_property

import cv2
import numpy as np

FLOOR_PX = (32, 24)  # [px] (width, height) of the thumbnail: coarse enough to ignore carpet texture and tape edges
NOSE_ROWS = (0.8, 1.0)  # [-] of the height: the patch just ahead of the car's nose ...
NOSE_COLUMNS = (0.25, 0.75)  # [-] ... of the width: the floor the car is driving on
FLOOR_COLOURS = 20  # k-means colours of the floor (a track's floor, its tape and its patches of light)
MATCH_PERCENTILE = 90.0  # [%] of the nose patch's distances to its nearest colour: the match radius ...
MIN_RADIUS_LAB = 12.0  # [Lab units] ... at least this: on a plain floor the colours crowd and their spacing is no
#   measure of how much the floor's own colour varies (with 12 colours and no minimum, a plain mat read half "hidden"
#   once the sunlight moved on it)
USUAL_SHARE = 0.7  # [-] a cell that showed floor in at least this share of the learnt frames usually shows floor
TEXTURE_PX = (4 * FLOOR_PX[0], 4 * FLOOR_PX[1])  # [px] the grey picture whose gradient is averaged per cell: 4×4 px each
TEXTURE_PERCENTILE = 10.0  # [%] of a cell's texture over the learnt frames that showed floor colour there: its floor at
#   the least (frames with motion blur, dimmer light, a reflection — the low end of normal, not its middle)
SMOOTH_RATIO = 0.25  # [-] a cell smoother than this share of that is no floor, whatever its colour: a flat surface
MIN_TEXTURE_FRAMES = 5  # [frames] a cell that showed floor colour in fewer learnt frames asks nothing of its texture
# FLOOR_COLOURS, MATCH_PERCENTILE, USUAL_SHARE and MIN_RADIUS_LAB chosen on the 11 model-car sources of the development
# corpus, each left out in turn (benchmarks/eval_floor.py; docs/learning.md, "The floor"); TEXTURE_PERCENTILE and
# SMOOTH_RATIO on the same sources, as the most lenient pair that still reads a flat box as no floor (docs/learning.md,
# "The grain": eval_floor.py grids the test on and off)


@dataclass(frozen=True, eq=False)  # eq=False: holds arrays
class FloorView:
    """One picture as the floor model reads it: the Lab thumbnail and each cell's texture."""

    lab: np.ndarray  # (FLOOR_PX[1], FLOOR_PX[0], 3) float32 OpenCV 8-bit Lab, area-averaged
    texture: np.ndarray  # (FLOOR_PX[1], FLOOR_PX[0]) float32 mean |∂x| + |∂y| of the grey picture [grey levels / px]


@dataclass(frozen=True, eq=False)  # eq=False: holds arrays
class FloorModel:
    """What the floor looks like and where it usually is. Arrays are read-only."""

    colours_lab: np.ndarray  # (k, 3) OpenCV 8-bit Lab colours of the floor
    radius_lab: float  # [Lab units] a cell within this distance of a floor colour shows floor
    usual: np.ndarray  # (FLOOR_PX[1], FLOOR_PX[0]) share of learnt frames in which the cell showed floor, 0..1
    hidden_usual: float  # [0..1] median hidden-floor share on the recordings
    texture_low: np.ndarray | None = None  # (FLOOR_PX[1], FLOOR_PX[0]) [grey levels / px]; None: no texture test (a
    #   profile learnt before it)

    def hidden(self, bgr: np.ndarray) -> float:
        """Share of the usual floor that this picture (uint8 BGR) does not show as floor, 0..1."""
        return self.hidden_in(floor_view(bgr))

    def hidden_in(self, view: FloorView) -> float:
        """The same for a ``floor_view``."""
        seen = self.shows_floor(view)
        return float((self._weight * ~seen).sum() / self._weight_sum)

    def shows_floor(self, view: FloorView) -> np.ndarray:
        """bool (H, W): the cells of a view that show floor — its colour, and not much smoother than it ever was."""
        seen = floor_cells(self.colours_lab, self.radius_lab, view.lab)
        if self.texture_low is not None:
            seen &= view.texture >= SMOOTH_RATIO * self.texture_low
        return seen

    @cached_property
    def _weight(self) -> np.ndarray:
        """The cells read: those that usually show floor, weighted by how usually (fixed per model, not per frame)."""
        return np.where(self.usual >= USUAL_SHARE, self.usual, 0.0)

    @cached_property
    def _weight_sum(self) -> float:
        return max(float(self._weight.sum()), 1e-9)


def as_occlusion(hidden: float, usual: float, calm_top: float) -> float:
    """A hidden-floor share as the occlusion cue: 0..usual maps onto the rule file's calm term (0..``calm_top``), the
    rest linearly up to 1 (monotone, 0 and 1 fixed, NaN stays NaN). Even where the typical frame hides less than the
    calm term's top, what hides more than it is read as more than calm: on a plain floor a wall hides a few per cent
    of the usual floor more, and that must show in the fear."""
    if not math.isfinite(hidden):
        return hidden
    usual = min(max(usual, 1e-3), 1.0 - 1e-3) if math.isfinite(usual) else 1e-3
    return float(np.interp(hidden, [0.0, usual, 1.0], [0.0, calm_top, 1.0]))


def floor_lab(bgr: np.ndarray) -> np.ndarray:
    """The picture as a FLOOR_PX thumbnail in Lab (float32, H×W×3), area-averaged."""
    small = cv2.resize(bgr, FLOOR_PX, interpolation=cv2.INTER_AREA)
    return cv2.cvtColor(small, cv2.COLOR_BGR2LAB).astype(np.float32)


def floor_texture(bgr: np.ndarray) -> np.ndarray:
    """Each cell's texture: the grey picture at TEXTURE_PX, its mean |∂x| + |∂y| (Sobel, per pixel) per FLOOR_PX cell."""
    grey = cv2.resize(cv2.cvtColor(bgr, cv2.COLOR_BGR2GRAY), TEXTURE_PX, interpolation=cv2.INTER_AREA).astype(np.float32)
    gx, gy = cv2.Sobel(grey, cv2.CV_32F, 1, 0, ksize=3), cv2.Sobel(grey, cv2.CV_32F, 0, 1, ksize=3)
    gradient = cv2.absdiff(gx, 0.0) + cv2.absdiff(gy, 0.0)  # OpenCV's |x|: half numpy's cost at this size
    return cv2.resize(gradient, FLOOR_PX, interpolation=cv2.INTER_AREA)


def floor_view(bgr: np.ndarray) -> FloorView:
    """A picture (uint8 BGR) as the floor model reads it."""
    return FloorView(floor_lab(bgr), floor_texture(bgr))


def floor_cells(colours_lab: np.ndarray, radius_lab: float, lab: np.ndarray) -> np.ndarray:
    """bool (H, W): cells within the radius of a floor colour."""
    return (_nearest_d2(lab.reshape(-1, 3), colours_lab) <= radius_lab * radius_lab).reshape(lab.shape[:2])


def _nearest_d2(points: np.ndarray, colours: np.ndarray) -> np.ndarray:
    """Squared Lab distance of each point (N, 3) to its nearest colour, as |x|² − 2x·c + |c|²: one small matrix product
    instead of an (N, k, 3) array of differences (~10× faster per frame); clipped at 0 against rounding."""
    x = np.asarray(points, dtype=np.float64)
    c = np.asarray(colours, dtype=np.float64)
    d2 = (x * x).sum(axis=1)[:, None] - 2.0 * (x @ c.T) + (c * c).sum(axis=1)[None, :]
    return np.maximum(d2.min(axis=1), 0.0)


def learn_floor(views: Sequence[FloorView], *, colours: int = FLOOR_COLOURS, percentile: float = MATCH_PERCENTILE,
                min_radius_lab: float = MIN_RADIUS_LAB, texture_percentile: float | None = TEXTURE_PERCENTILE) -> FloorModel | None:
    """The floor model of learnt frames (``floor_view`` each); None from fewer than two. The keywords are for
    ``benchmarks/eval_floor.py``, which chose them (``texture_percentile`` None: no texture test)."""
    if len(views) < 2:
        return None
    labs = np.stack([v.lab for v in views])
    h, w = labs.shape[1:3]
    patch = labs[:, int(NOSE_ROWS[0] * h): int(NOSE_ROWS[1] * h), int(NOSE_COLUMNS[0] * w): int(NOSE_COLUMNS[1] * w)]
    pixels = np.ascontiguousarray(patch.reshape(-1, 3))
    k = min(colours, len(pixels))
    criteria = (cv2.TERM_CRITERIA_EPS + cv2.TERM_CRITERIA_MAX_ITER, 30, 0.5)
    cv2.setRNGSeed(0)  # the same recordings give the same profile
    _, _, centres = cv2.kmeans(pixels, k, None, criteria, 2, cv2.KMEANS_PP_CENTERS)
    radius = max(float(np.percentile(np.sqrt(_nearest_d2(pixels, centres)), percentile)), min_radius_lab)
    matched = np.stack([floor_cells(centres, radius, lab) for lab in labs])
    usual = matched.mean(axis=0)
    colours = centres.astype(np.float64)
    low = None if texture_percentile is None else _texture_low(np.stack([v.texture for v in views]), matched, texture_percentile)
    for a in (colours, usual, low):
        if a is not None:
            a.setflags(write=False)
    model = FloorModel(colours, radius, usual, math.nan, low)
    return replace(model, hidden_usual=float(np.median([model.hidden_in(v) for v in views])))


def _texture_low(textures: np.ndarray, matched: np.ndarray, percentile: float) -> np.ndarray:
    """Per cell, the percentile of its texture over the frames in which it showed a floor colour (0 where fewer than
    MIN_TEXTURE_FRAMES did: nothing asked of it)."""
    masked = np.where(matched, textures.astype(np.float64), np.nan)
    enough = matched.sum(axis=0) >= MIN_TEXTURE_FRAMES
    with np.errstate(all="ignore"), warnings.catch_warnings():
        warnings.simplefilter("ignore", RuntimeWarning)  # all-NaN cells: never floor-coloured
        low = np.nanpercentile(masked, percentile, axis=0)
    return np.where(enough & np.isfinite(low), low, 0.0)

