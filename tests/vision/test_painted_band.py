"""Paint lying across the lane (a stop line) is no object (vision/obstacle.py ``_painted_band``, ``_painted_strip``): a stretch of object
rows that fills the interior's width and is shallow on the ground plane. Its first and last rows are where its edges
cross the pixel rows; seen a few degrees askew they cover only part of the width (gym-duckietown's TTIC_ripltown: a red
line 0.14 m ahead, 6 of its 8 rows full, read as an object the robot stood before for the rest of the drive)."""

from __future__ import annotations

import cv2
import numpy as np
from hypothesis import assume, given, settings
from hypothesis import strategies as st

from fearguard.vision.lanes import road_region
from fearguard.vision.obstacle import BAND_COVER, _painted_band, _painted_strip
from fearguard.worlds.duckietown.preset import duckiebot_camera

W, H = 160, 120
CAM = duckiebot_camera(W, H)
REGION = road_region(W, H, CAM)
ROWS = np.arange(REGION.top_v_px, REGION.bottom_v_px + 1)


def _band(n: int, bottom_gap: int, width_px: int, fills: list[float]) -> tuple[np.ndarray, np.ndarray, np.ndarray, int]:
    """hit, count, width over the road rows for a band of ``n`` rows ending ``bottom_gap`` rows above the region's
    bottom, its rows filled by these shares of the interior's width."""
    hit, count = np.zeros(len(ROWS), bool), np.zeros(len(ROWS), np.int64)
    width = np.full(len(ROWS), width_px, np.int64)
    bottom = len(ROWS) - 1 - bottom_gap
    hit[bottom - n + 1 : bottom + 1] = True
    count[bottom - n + 1 : bottom + 1] = np.rint(np.array(fills) * width_px).astype(np.int64)
    return hit, count, width, bottom


@settings(max_examples=200, deadline=None)
@given(n=st.integers(3, 8), gap=st.integers(0, 8), width_px=st.integers(60, 150), first=st.floats(0.0, 1.0),
       last=st.floats(0.0, 1.0), inner=st.floats(BAND_COVER + 0.01, 1.0))
def test_a_shallow_band_full_between_its_edge_rows_is_paint_whatever_its_edge_rows_cover(
    n: int, gap: int, width_px: int, first: float, last: float, inner: float
) -> None:
    hit, count, width, bottom = _band(n, gap, width_px, [first] + [inner] * (n - 2) + [last])
    assert _painted_band(hit, count, width, bottom, ROWS, CAM, 1.0) == bottom - n + 1


@settings(max_examples=200, deadline=None)
@given(n=st.integers(3, 8), gap=st.integers(0, 8), width_px=st.integers(60, 150), partial=st.floats(0.0, BAND_COVER - 0.05),
       data=st.data())
def test_a_band_with_inner_rows_short_of_the_width_stands(n: int, gap: int, width_px: int, partial: float, data: st.DataObject) -> None:
    """An object narrower than the lane leaves the road beside it on its inner rows: most of them short is no paint."""
    short = data.draw(st.integers(max(1, (n - 2) // 4 + 1), n - 2))  # more than BAND_ROWS_FULL's share of the inner rows
    fills = [1.0] + [partial] * short + [1.0] * (n - 2 - short) + [1.0]
    hit, count, width, bottom = _band(n, gap, width_px, fills)
    assert _painted_band(hit, count, width, bottom, ROWS, CAM, 1.0) is None


def test_two_rows_are_judged_as_they_are() -> None:
    hit, count, width, bottom = _band(2, 2, 100, [1.0, 0.5])
    assert _painted_band(hit, count, width, bottom, ROWS, CAM, 1.0) is None
    hit, count, width, bottom = _band(2, 2, 100, [1.0, 0.9])
    assert _painted_band(hit, count, width, bottom, ROWS, CAM, 1.0) == bottom - 1


def _strip_args(mask: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray, int]:
    """foreign, hit, width and the lowest hit row for a foreign mask over the road rows (every column searched)."""
    foreign = mask.astype(bool)
    hit = foreign.sum(axis=1) >= 3
    return foreign, hit, np.full(len(ROWS), W, np.int64), int(np.flatnonzero(hit)[-1])


@settings(max_examples=120, deadline=None)
@given(tilt_px=st.integers(-25, 25), near=st.integers(10, 30), thick=st.integers(3, 6), left=st.integers(0, 8))
def test_a_thin_strip_across_the_way_seen_askew_is_paint(tilt_px: int, near: int, thick: int, left: int) -> None:
    """A line across the way, crossed a few degrees askew (one end ``tilt_px`` rows higher): no row is full, yet it is paint.
    (The whole line in the picture: one that runs out of its bottom edge shows less than the way's width, and is judged
    as what it shows.)"""
    assume(near > -tilt_px + thick)
    mask = np.zeros((len(ROWS), W), np.uint8)
    bottom_row = len(ROWS) - 1 - near
    cv2.line(mask, (left, bottom_row), (W - 1 - left, bottom_row - tilt_px), 1, thick)
    foreign, hit, width, bottom = _strip_args(mask)
    top = _painted_strip(foreign, hit, width, bottom, ROWS, 0, CAM, 1.0)
    assert top is not None and top == int(np.flatnonzero(foreign.any(axis=1))[0])


@settings(max_examples=120, deadline=None)
@given(u=st.integers(40, 120), near=st.integers(5, 30), half=st.integers(3, 14), tall=st.integers(12, 40))
def test_an_upright_patch_is_no_strip(u: int, near: int, half: int, tall: int) -> None:
    """Something standing (a duck, a cone) covers rows above its foot as wide as it is: on the ground plane it runs
    along the camera's rays, ahead, not across the way."""
    mask = np.zeros((len(ROWS), W), np.uint8)
    bottom_row = len(ROWS) - 1 - near
    mask[max(0, bottom_row - tall) : bottom_row + 1, u - half : u + half] = 1
    foreign, hit, width, bottom = _strip_args(mask)
    assert _painted_strip(foreign, hit, width, bottom, ROWS, 0, CAM, 1.0) is None
