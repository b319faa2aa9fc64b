"""Anything standing in the ego lane, seen by the camera: a toy duck, a cone, a box, a car — and its ground-plane range.

Inside the lane interior (the expected boundaries, inset by ``INSET`` of the lane width, so the lane's own paint is not
in it) a pixel is *foreign* when its 3-row patch (``occlusion.SurfaceMaps``) does not look like the road
(``occlusion.RoadAppearance``, the model of recent frames): strongly coloured or of another saturation (any hue — paint
is not inside the lane), darker than any shadow, brighter and smoother, or smooth where the road is rough. A row whose
foreign pixels cover ``MIN_SHARE`` of the interior width is an object row; the nearest stretch of ``MIN_ROWS`` such rows
is the object, standing on its lowest row. Its range is the flat-ground range of that row,
D = H / tan(α + arctan((v − v0) / f_y)) (``CameraModel.ground_range_m``), so it needs the camera's mounting height.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from fearguard.camera import CameraModel
from fearguard.vision.lanes import LaneLine, RoadRegion
from fearguard.vision.occlusion import (
    BRIGHTER,
    COLOUR_SAT_MIN,
    DARKER,
    FOREIGN_DEV_MIN,
    ROUGH_MIN,
    SAT_DEV,
    SMOOTH_SHARE,
    SMOOTHER_SHARE,
    RoadAppearance,
    SurfaceMaps,
)

INSET = 0.15  # [-] of the lane width on each side: the interior searched (the boundaries' paint stays out)
MIN_SHARE = 0.2  # [-] of the interior width: foreign pixels on a row that make it an object row ...
MIN_PX = 3  # [px] ... and at least this many
SHADE_SAT_GATE = 0.6  # [-] of the road's grey: darker patches are not judged by their saturation
MIN_ROWS = 4  # [rows] consecutive object rows that make an object (one row is noise)
CONFIRM_FRAMES = 3  # [frames] over time an object counts once seen this many frames in a row (0.1 s at 30 Hz): a single
#   frame's foreign patch — a tile seam beside a boundary the lane model placed a little off — is no object
CONFIRM_AGREE = 0.25  # [-] ... each sighting's range within this share of the one before (the same object, approaching)


@dataclass(frozen=True)
class Obstacle:
    """An object in the ego lane: its columns and the row it stands on (frame pixels), bearing and range."""

    u_left_px: float
    u_right_px: float
    v_bottom_px: float
    bearing_deg: float
    range_m: float | None  # None without the camera's mounting height


def foreign_mask(maps: SurfaceMaps, road: RoadAppearance, columns: slice = slice(None), *, smooth_objects: bool = True) -> np.ndarray:
    """bool over the maps' band (those columns): patches that do not look like the road (any colour, any size).

    ``smooth_objects=False``: a patch smoother than the road but of its grey and colour is not foreign. On a tiled
    floor (Duckietown's curve tiles are ~3× rougher than its straight ones) that is the next tile, not an object; the
    objects there are coloured (ducks, cones), dark or pale. A smooth object of the road's own grey is then missed:
    it is the range sensor's to see."""
    grey, sat, rough = maps.grey[:, columns], maps.saturation[:, columns], maps.roughness[:, columns]
    ref = max(road.grey, 1.0)
    off = np.abs(grey - ref) >= FOREIGN_DEV_MIN
    lit = grey >= SHADE_SAT_GATE * ref  # HLS saturation of dark pixels is unstable: a shadow is no coloured object
    coloured = lit & ((sat >= COLOUR_SAT_MIN) | (np.abs(sat - road.saturation) >= SAT_DEV))
    foreign = coloured | (off & (grey < DARKER * ref))
    if road.roughness >= ROUGH_MIN:
        if smooth_objects:
            foreign |= rough < SMOOTH_SHARE * road.roughness
        foreign |= off & (grey > BRIGHTER * ref) & (rough < SMOOTHER_SHARE * road.roughness)
    return foreign


def detect_obstacle(
    maps: SurfaceMaps, road: RoadAppearance, region: RoadRegion, left: LaneLine, right: LaneLine, camera: CameraModel,
    scale: float, *, interior: np.ndarray | None = None, smooth_objects: bool = True,
) -> Obstacle | None:
    """The nearest object in the ego lane of a working image (None when the lane interior looks like road).

    The interior lies between the straight boundaries, inset by INSET of the lane width — or, when the lane model bends,
    is given: ``interior``, bool over the road rows (``ground_lanes.lane_interior``). ``smooth_objects``: see
    ``foreign_mask``."""
    rows = np.arange(region.top_v_px, region.bottom_v_px + 1)
    if interior is None:
        a, b = left.u_at(rows.astype(float)), right.u_at(rows.astype(float))
        inset = INSET * (b - a)
        lo = np.clip(np.ceil(a + inset), 0, region.width_px).astype(np.int64)
        hi = np.clip(np.floor(b - inset), 0, region.width_px).astype(np.int64)
        c0, c1 = int(lo.min()), int(max(hi.max(), lo.min()))  # only the columns some row's interior covers are judged
        cols = np.arange(c0, c1)[None, :]
        inside = (cols >= lo[:, None]) & (cols < hi[:, None])
        width = np.maximum(hi - lo, 0)
    else:
        spans = np.flatnonzero(interior.any(axis=0))
        c0, c1 = (int(spans[0]), int(spans[-1]) + 1) if len(spans) else (0, 0)  # only the columns the interior covers
        inside = interior[:, c0:c1]
        width = inside.sum(axis=1)
    foreign = foreign_mask(maps, road, slice(c0, c1), smooth_objects=smooth_objects) & inside
    count = foreign.sum(axis=1)
    hit = (width > 0) & (count >= np.maximum(MIN_PX, MIN_SHARE * width))
    bottom = _lowest_stretch_end(hit, MIN_ROWS)
    if bottom is None:
        return None
    u = c0 + np.flatnonzero(foreign[bottom - MIN_ROWS + 1 : bottom + 1].any(axis=0))
    v_frame = (rows[bottom] + 1.0) * scale  # the object stands on the lower edge of its lowest row
    u_left, u_right = u.min() * scale, (u.max() + 1.0) * scale
    range_m = camera.ground_range_m(v_frame)
    return Obstacle(float(u_left), float(u_right), float(v_frame), camera.bearing_deg(0.5 * (u_left + u_right)),
                    range_m if range_m is not None and math.isfinite(range_m) else None)


def _lowest_stretch_end(hit: np.ndarray, min_rows: int) -> int | None:
    """Index of the last row of the lowest stretch of ≥ min_rows consecutive True rows, or None."""
    change = np.diff(np.concatenate([[0], hit.astype(np.int8), [0]]))
    first, after = np.flatnonzero(change == 1), np.flatnonzero(change == -1)  # each stretch's first row, one past its last
    long = after[after - first >= min_rows]
    return int(long[-1]) - 1 if len(long) else None


class ObstacleTrack:
    """An object in the lane is believed once CONFIRM_FRAMES consecutive frames saw it at consistent ranges."""

    def __init__(self) -> None:
        self._last: Obstacle | None = None
        self._run = 0

    def update(self, seen: Obstacle | None) -> Obstacle | None:
        last = self._last
        same = seen is not None and last is not None and (
            seen.range_m is None or last.range_m is None or abs(seen.range_m - last.range_m) <= CONFIRM_AGREE * last.range_m)
        self._run = 0 if seen is None else (self._run + 1 if same else 1)
        self._last = seen
        return seen if self._run >= CONFIRM_FRAMES else None
