"""What counts as coloured unlike the road: on a grey road exactly what it always was (car paint, or a saturation far
from the road's); on a saturated floor (wood, an orange tarp) the floor is road, and a pixel of another hue is not."""

from __future__ import annotations

import math

import cv2
import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from fearguard.vision.lanes import road_region
from fearguard.vision.occlusion import (
    COLOUR_SAT_MIN,
    HUE_DEV,
    SAT_DEV,
    RoadAppearance,
    coloured_unlike_road,
    floor_hue,
    hue_distance,
    mean_hue,
    surface_maps,
)

pixels = st.lists(st.tuples(st.floats(0, 255), st.integers(0, 179)), min_size=1, max_size=30)


@settings(max_examples=200, deadline=None, derandomize=True)
@given(px=pixels, road_sat=st.floats(0, 255))
def test_on_a_grey_road_coloured_is_car_paint_or_far_from_the_road_s_saturation(px, road_sat):
    """A grey road (no floor hue) — whatever its lane interior's saturation, a red car filling it included."""
    sat = np.array([p[0] for p in px], np.float32)
    hue = np.array([p[1] for p in px], np.uint8)
    road = RoadAppearance(100.0, road_sat, 0.05)  # a grey road has no floor hue
    expected = (sat >= COLOUR_SAT_MIN) | (np.abs(sat - road_sat) >= SAT_DEV)
    assert np.array_equal(coloured_unlike_road(sat, hue, road), expected)


@settings(max_examples=200, deadline=None, derandomize=True)
@given(road_hue=st.floats(0, 179.9), offset=st.floats(-89.9, 89.9), road_sat=st.floats(COLOUR_SAT_MIN - 0.5 * SAT_DEV, 200))
def test_on_a_saturated_floor_its_own_colour_is_road_and_another_hue_is_not(road_hue, offset, road_sat):
    road = RoadAppearance(120.0, road_sat, 0.05, road_hue)
    sat = np.array([road_sat], np.float32)
    hue = np.array([round(road_hue + offset) % 180], np.uint8)
    got = bool(coloured_unlike_road(sat, hue, road)[0])
    far = hue_distance(hue, road_hue)[0]
    if sat[0] >= COLOUR_SAT_MIN and far >= HUE_DEV:
        assert got
    if far < HUE_DEV:
        assert not got  # the floor's own hue and saturation: road


def test_hues_are_circular():
    assert abs(mean_hue(np.array([178.0, 2.0])) % 180.0) < 1e-6
    assert math.isclose(mean_hue(np.array([10.0, 20.0, math.nan])), 15.0)
    assert math.isnan(mean_hue(np.array([math.nan])))
    assert hue_distance(np.array([175, 5, 90], np.uint8), 0.0).tolist() == [5.0, 5.0, 90.0]


def _maps(bgr: np.ndarray):
    region = road_region(bgr.shape[1], bgr.shape[0])
    return surface_maps(cv2.cvtColor(bgr, cv2.COLOR_BGR2GRAY), cv2.cvtColor(bgr, cv2.COLOR_BGR2HLS), np.zeros(bgr.shape[:2], np.uint8),
                        region)


@pytest.mark.parametrize(("floor", "hue"), [((110, 170, 200), 20.0), ((40, 110, 215), 12.0), ((200, 140, 60), 103.0)])
def test_a_floor_coloured_across_the_whole_width_has_its_hue(floor, hue):
    img = np.empty((240, 320, 3), np.uint8)
    img[:] = floor
    assert abs(floor_hue(_maps(img)) - hue) < 3.0


def test_a_grey_road_with_a_red_car_in_its_lane_has_no_floor_hue():
    img = np.full((240, 320, 3), 120, np.uint8)
    img[150:230, 80:240] = (60, 60, 170)  # the car covers the lane, not the road on both sides of it
    assert math.isnan(floor_hue(_maps(img)))
    img[:] = (60, 60, 170)  # ... a picture that is all red is a red floor
    assert math.isfinite(floor_hue(_maps(img)))
