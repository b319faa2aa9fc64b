"""The object search along a route's path (vision/obstacle.py ``RoutePath``): where no lane boundary is seen and the
caller's route steers the car, the search looks along the route's arc — as far as its aim point — not straight ahead,
so a roundabout's island ahead of a car turning past it is no object in its path; a lane seen is still searched."""

from __future__ import annotations

import math

import cv2
import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from fearguard.camera import CameraModel
from fearguard.vision.frame import FramePipeline
from fearguard.vision.lanes import road_region
from fearguard.vision.obstacle import INSET, PATH_CAR_WIDTHS, RoutePath
from fearguard.vision.steering import lookahead_row

W, H = 320, 240
COLOURS = [(0, 140, 255), (40, 210, 230), (200, 60, 40), (240, 240, 240), (160, 40, 200)]


@settings(max_examples=60, deadline=None)
@given(height=st.floats(0.1, 2.5), pitch=st.floats(-2.0, 8.0), curvature=st.floats(-0.15, 0.15), width=st.floats(0.15, 2.2),
       reach=st.floats(2.0, 40.0))
def test_the_corridor_is_the_arc_as_wide_as_the_path_and_no_farther_than_its_reach(
    height: float, pitch: float, curvature: float, width: float, reach: float
) -> None:
    cam = CameraModel.default(W, H, mount_height_m=height, pitch_deg=pitch)
    region = road_region(W, H, cam)
    left, right = RoutePath(curvature, width).bounds_px(cam, region, 1.0, reach)
    rows = np.arange(region.top_v_px, region.bottom_v_px + 1) + 0.5
    half = 0.5 * PATH_CAR_WIDTHS * width / (1.0 - 2.0 * INSET)
    checked = 0
    for v, a, b in zip(rows, left, right, strict=True):
        x = cam.ground_range_m(float(v))
        if x is None or x > reach or abs(curvature) * x >= 1.0:
            assert math.isnan(a) and math.isnan(b)
            continue
        assert a <= b
        centre = (1.0 - math.sqrt(1.0 - (curvature * x) ** 2)) / curvature if curvature else 0.0  # the circle's offset at x
        for u, y in ((a, centre + half), (b, centre - half)):
            pu, _, front = cam.project_ground(np.array([x]), np.array([y]))
            assert front[0] and u == pytest.approx(float(pu[0]), abs=1e-6)
        checked += 1
    near = cam.ground_range_m(float(rows[-1]))
    assert checked > 0 or near is None or near > reach or abs(curvature) * near >= 1.0


def _frame(cam: CameraModel, rng: np.random.Generator, colour: tuple[int, int, int], at_m: float,
           lines: bool | tuple[float, ...]) -> np.ndarray:
    """A plain grey road under a sky, a box standing straight ahead ``at_m`` from the camera; with ``lines`` a 3.5 m lane
    (or the lines at these lateral offsets)."""
    img = np.full((H, W, 3), (110, 112, 108), np.uint8)
    img[: int(cam.horizon_v_px()), :] = (230, 200, 170)
    img = np.clip(img.astype(int) + rng.integers(-6, 7, img.shape), 0, 255).astype(np.uint8)
    if lines:
        for y in (1.75, -1.75) if lines is True else lines:
            u, v, _ = cam.project_ground(np.array([3.0, 40.0]), np.array([y, y]))
            cv2.line(img, (int(u[0]), int(v[0])), (int(u[1]), int(v[1])), (235, 235, 235), 3)
    near, far = cam.ground_row_px(at_m), cam.ground_row_px(at_m + 1.0)
    img[int(far) : int(near), W // 2 - 18 : W // 2 + 18] = colour  # ~0.75 m wide at 6 m: a fifth of a road lane, as the search asks
    return img


def _search(cam: CameraModel, path: RoutePath | None, colour: tuple[int, int, int], at_m: float, lines: bool | tuple[float, ...],
            seed: int):
    rng = np.random.default_rng(seed)
    pipeline = FramePipeline(cam, fps=10)
    for i in range(8):
        analysis = pipeline.process(_frame(cam, rng, colour, at_m, lines), 0.1 * i, path=path)
    return analysis


@pytest.mark.parametrize("colour", COLOURS)
@pytest.mark.parametrize("height", [1.2, 1.5, 2.1])
def test_with_no_lane_seen_the_search_follows_the_route_not_the_straight_prior(colour: tuple[int, int, int], height: float) -> None:
    cam = CameraModel.default(W, H, mount_height_m=height)
    at = 0.9 * _aim_m(cam)  # within the route's reach
    seed = COLOURS.index(colour)
    straight = _search(cam, None, colour, at, False, seed)
    assert straight.left is None and straight.right is None  # nothing of a lane: the straight prior is searched
    assert straight.obstacle is not None and straight.obstacle.range_m == pytest.approx(at - cam.front_offset_m, rel=0.1)
    for turn_deg in (-35.0, 35.0):  # the route turns away from the box: it lies beside the path there, not in it
        turning = _search(cam, RoutePath(math.tan(math.radians(turn_deg)) / 7.0, 1.85), colour, at, False, seed)
        assert turning.obstacle is None
    ahead = _search(cam, RoutePath(0.0, 1.85), colour, at, False, seed)  # the route runs through it
    assert ahead.obstacle is not None


def _aim_m(cam: CameraModel) -> float:
    """The ground distance of the steering's aim row (the route's reach) for a camera given no aim distance."""
    distance = cam.ground_range_m(lookahead_row(road_region(W, H, cam)))
    assert distance is not None
    return distance


def test_the_route_path_is_searched_no_farther_than_its_aim_and_the_clear_distance_says_so() -> None:
    cam = CameraModel.default(W, H, mount_height_m=1.5)
    at = 1.4 * _aim_m(cam)
    beyond = _search(cam, RoutePath(0.0, 1.85), COLOURS[0], at, False, 0)
    assert beyond.obstacle is None
    assert beyond.searched_m == pytest.approx(_aim_m(cam) - cam.front_offset_m, rel=0.05)
    straight = _search(cam, None, COLOURS[0], at, False, 0)
    assert straight.obstacle is not None and beyond.searched_m < straight.searched_m


@pytest.mark.parametrize("colour", COLOURS[:3])
def test_a_lane_seen_is_searched_whatever_the_route(colour: tuple[int, int, int]) -> None:
    cam = CameraModel.default(W, H, mount_height_m=1.5)
    turning = _search(cam, RoutePath(math.tan(math.radians(-25.0)) / 7.0, 1.85), colour, 0.75 * _aim_m(cam), True, 1)
    assert turning.left is not None and turning.right is not None
    assert turning.obstacle is not None


@pytest.mark.parametrize("colour", COLOURS[:3])
@pytest.mark.parametrize("side", [1.75, -1.75])
def test_a_lane_seen_on_one_side_is_searched_only_where_the_route_takes_the_car(colour: tuple[int, int, int], side: float) -> None:
    """Its other side is a guess (the seen one a lane width over): at a Duckietown junction that guess took in the
    crossing road's stop line beside the robot's way, read as an object 0.13 m ahead. With a route, an object in the
    guessed lane but off the route's path is none; one on the path still is; without a route the lane is searched."""
    cam = CameraModel.default(W, H, mount_height_m=1.5)
    at, seed = 0.75 * _aim_m(cam), COLOURS.index(colour)
    alone = _search(cam, None, colour, at, (side,), seed)
    assert (alone.left is None) != (alone.right is None)  # one side seen
    assert alone.obstacle is not None
    away = -35.0 if side > 0 else 35.0  # turning into the guessed side, away from the box straight ahead
    assert _search(cam, RoutePath(math.tan(math.radians(away)) / 7.0, 1.85), colour, at, (side,), seed).obstacle is None
    assert _search(cam, RoutePath(0.0, 1.85), colour, at, (side,), seed).obstacle is not None
