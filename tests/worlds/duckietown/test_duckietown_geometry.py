"""Plane geometry of the simulated time-of-flight sensor and the obstacle gap (pure functions)."""

from __future__ import annotations

import math

import numpy as np
import pytest

from fearguard.worlds.duckietown.world import polygon_gap_m, ray_polygon_range_m

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
