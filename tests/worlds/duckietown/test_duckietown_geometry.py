"""Plane geometry of the simulated Duckietown world (pure functions): the time-of-flight ray, the obstacle gap, the route's bearing."""

from __future__ import annotations

import math

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from fearguard.worlds.duckietown.preset import CAMERA_AHEAD_M
from fearguard.worlds.duckietown.world import ROUTE_BEHIND_DEG, polygon_gap_m, ray_polygon_range_m, route_bearing_of

SQUARE = np.array([[1.0, -0.1], [1.2, -0.1], [1.2, 0.1], [1.0, 0.1]])


def test_ray_hits_the_near_face() -> None:
    dirs = np.array([[1.0, 0.0], [math.cos(0.05), math.sin(0.05)]])
    assert ray_polygon_range_m(np.zeros(2), dirs, SQUARE) == pytest.approx(1.0)


def test_ray_beside_or_behind_misses() -> None:
    assert math.isinf(ray_polygon_range_m(np.zeros(2), np.array([[0.0, 1.0]]), SQUARE))
    assert math.isinf(ray_polygon_range_m(np.zeros(2), np.array([[-1.0, 0.0]]), SQUARE))


def test_polygon_gap() -> None:
    other = SQUARE + np.array([0.5, 0.0])
    assert polygon_gap_m(SQUARE, other) == pytest.approx(0.3)
    assert polygon_gap_m(SQUARE, SQUARE + np.array([0.1, 0.05])) == 0.0  # overlapping
    assert polygon_gap_m(SQUARE, SQUARE[::-1] + np.array([0.0, 0.5])) == pytest.approx(0.3)  # either winding


@settings(max_examples=100, deadline=None)
@given(st.floats(-1.0, 1.0), st.floats(-1.0, 1.0))
def test_a_route_aim_point_is_steered_to_ahead_of_the_camera_and_never_behind_it(x_m: float, y_m: float) -> None:
    """In a junction the simulator's nearest curve can switch to another lane's, whose aim point lies behind the robot
    (+30° one step, ±175° the next): that is no route. A point ahead of the camera is steered to on its own side."""
    bearing = route_bearing_of((x_m, y_m))
    ahead = x_m - CAMERA_AHEAD_M
    if ahead < 0.0:
        assert bearing is None
    elif ahead > 0.0:
        assert bearing is not None and abs(bearing) < ROUTE_BEHIND_DEG and bearing * y_m >= 0.0
        assert math.tan(math.radians(bearing)) == pytest.approx(y_m / ahead, rel=1e-6, abs=1e-9)


def test_a_route_behind_the_robot_is_none_and_one_ahead_keeps_its_side() -> None:
    assert route_bearing_of((CAMERA_AHEAD_M - 0.2, 0.05)) is None  # the other lane's curve, behind
    assert route_bearing_of((CAMERA_AHEAD_M - 0.2, -0.05)) is None
    assert route_bearing_of((CAMERA_AHEAD_M + 0.2, 0.0)) == 0.0
    assert route_bearing_of((CAMERA_AHEAD_M + 0.2, 0.2)) == pytest.approx(45.0)
    assert route_bearing_of((CAMERA_AHEAD_M + 0.2, -0.2)) == pytest.approx(-45.0)
