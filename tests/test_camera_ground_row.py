"""``CameraModel.ground_row_px``: the image row of the ground a distance ahead, the inverse of ``ground_range_m`` (the
row a lane steering told to aim ``aim_m`` ahead looks at)."""

from __future__ import annotations

import math

import pytest
from hypothesis import given
from hypothesis import strategies as st

from fearguard.camera import CameraModel


@given(fov=st.floats(40.0, 120.0), height=st.floats(0.05, 3.0), pitch=st.floats(-5.0, 30.0), w=st.sampled_from([160, 320, 641]),
       range_m=st.floats(0.1, 200.0))
def test_the_row_of_a_range_reads_that_range_back(fov: float, height: float, pitch: float, w: int, range_m: float) -> None:
    cam = CameraModel.default(w, w * 3 // 4, fov, mount_height_m=height, pitch_deg=pitch)
    row = cam.ground_row_px(range_m)
    if row is None:  # only ground so near below a camera pitched up that it lies behind the image plane
        assert math.degrees(math.atan2(height, range_m)) - pitch >= 89.99
        return
    back = cam.ground_range_m(row)
    assert back is not None and back == pytest.approx(range_m, rel=1e-6)
    assert row > cam.horizon_v_px()  # the ground ahead lies below the horizon
    farther = cam.ground_row_px(range_m * 1.5)
    assert farther is not None and farther < row  # farther ground sits nearer the horizon


@pytest.mark.parametrize("range_m", [0.0, -3.0, math.inf, math.nan])
def test_no_row_for_a_range_that_is_not_ahead(range_m: float) -> None:
    assert CameraModel.default(320, 240, 60.0, mount_height_m=1.4, pitch_deg=3.0).ground_row_px(range_m) is None


def test_no_row_without_a_mount_height() -> None:
    assert CameraModel.default(320, 240, 60.0).ground_row_px(10.0) is None
