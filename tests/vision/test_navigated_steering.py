"""The route-following steering stack (vision/navigated.py): the lane seen, and the route where the route leaves it."""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest
from hypothesis import given
from hypothesis import strategies as st

from fearguard.camera import CameraModel
from fearguard.vision.lane_steering import HoughLaneSteering
from fearguard.vision.navigated import FORK_DEG, NavigatedSteering

CAM = CameraModel.default(320, 240, mount_height_m=2.1)
ANALYSIS = HoughLaneSteering(CAM).pipeline.process(np.full((240, 320, 3), 110, np.uint8), 0.0)


def _steer(lane: float | None, route: float | None, limit: float = 30.0) -> float:
    navigated = NavigatedSteering(HoughLaneSteering(CAM), lambda: route, limit)
    return navigated.steer_from(dataclasses.replace(ANALYSIS, steering_deg=lane))


@given(lane=st.floats(-30, 30), route=st.one_of(st.none(), st.floats(-180, 180)))
def test_the_lane_steers_unless_the_route_leaves_it(lane: float, route: float | None) -> None:
    out = _steer(lane, route)
    if route is None or abs(route - lane) <= FORK_DEG:
        assert out == lane
    else:
        assert out == pytest.approx(max(-30.0, min(30.0, route)))


@pytest.mark.parametrize("route", [None, 12.0, -45.0])
def test_no_lane_seen_is_the_route_or_the_lane_steerings_own_answer(route: float | None) -> None:
    expected = 0.0 if route is None else max(-30.0, min(30.0, route))  # HoughLaneSteering answers 0 without a lane
    assert _steer(None, route) == expected


def test_it_is_a_frame_steering_sharing_the_lane_steerings_pipeline() -> None:
    from fearguard.perception import FrameSteering

    lanes = HoughLaneSteering(CAM)
    navigated = NavigatedSteering(lanes, lambda: None, 30.0)
    assert isinstance(navigated, FrameSteering) and navigated.pipeline is lanes.pipeline
    assert navigated(np.full((240, 320, 3), 110, np.uint8)) == 0.0
