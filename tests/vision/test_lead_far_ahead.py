"""A vehicle ahead is confirmed by its tail lights wherever they appear: above the road region's top row too.

The lead search finds a vehicle by the dark band under its rear and confirms it by some tail-light red above. The
working grey and HLS images hold only the road rows; a car 20 m or more ahead, seen from a car's height, has its
lamps above the road region's top row, where those images are 0, so it was never confirmed (16 of 40 drawn cars
7-30 m ahead boxed on straight roads and bends alike; now 39: docs/perception.md). Vehicles are drawn onto the
lanes of ``test_bend`` (OpenCV polygons through a pinhole camera, not any simulator's renderer): a rear of five
colours and several widths with a dark rear window, two tail lights and the dark band of its underside.
"""

from __future__ import annotations

import math

import cv2
import numpy as np
from hypothesis import assume, given, settings
from hypothesis import strategies as st
from tests.vision.test_bend import PAINTS, _boundary, _yawed, camera, curved_lane

from fearguard.camera import CameraModel
from fearguard.vision.frame import FrameAnalysis, FramePipeline

FALSE_LEADS_MAX = 5  # of 40 next-lane cars on bends of R 100-250 m boxed as the lead (measured: 5)
BODIES = {"white": (235, 235, 235), "silver": (170, 175, 180), "blue": (150, 60, 30), "green": (60, 120, 50), "black": (30, 30, 32)}


def _rear_corners(cam: CameraModel, radius_m: float, s_m: float, lateral_m: float, width_m: float, z0_m: float, z1_m: float,
                  lat0: float = -0.5, lat1: float = 0.5) -> np.ndarray:
    """Image corners of the rectangle on a vehicle's rear face (perpendicular to the lane at arc length ``s_m``,
    centred ``lateral_m`` left of the lane centre) from ``lat0``..``lat1`` of its width and heights z0..z1 above the
    ground."""
    h = cam.mount_height_m or 1.0
    corners = []
    for lat, z in ((lat0, z0_m), (lat1, z0_m), (lat1, z1_m), (lat0, z1_m)):
        x, y = _boundary(radius_m, lateral_m + lat * width_m, np.array([s_m]))
        u, v, _ = cam.project_points(x, y, np.array([z - h]))
        corners.append((u[0], v[0]))
    return np.array(corners)


def _underside(cam: CameraModel, radius_m: float, s_m: float, lateral_m: float, width_m: float) -> np.ndarray:
    """The dark ground under the vehicle, from just behind its rear to 2 m under it, as an image polygon."""
    pts = []
    for s, lat in ((s_m - 0.2, -0.5), (s_m - 0.2, 0.5), (s_m + 2.0, 0.5), (s_m + 2.0, -0.5)):
        x, y = _boundary(radius_m, lateral_m + lat * width_m, np.array([s]))
        u, v, _ = cam.project_ground(x, y)
        pts.append((u[0], v[0]))
    return np.array(pts)


def with_vehicle(img: np.ndarray, cam: CameraModel, radius_m: float, s_m: float, lateral_m: float, width_m: float,
                 body: tuple[int, int, int], lamps: tuple[int, int, int] = (20, 20, 215)) -> np.ndarray:
    """The picture with a vehicle's rear drawn onto it: underside shadow, body (0.35-1.5 m), its rear window of dark
    glass (1.0-1.4 m), two tail lights of colour ``lamps`` (BGR; red by default)."""
    out = img.copy()

    def fill(poly: np.ndarray, colour: tuple[int, int, int]) -> None:
        cv2.fillPoly(out, [np.int32(np.round(poly * 4))], colour, shift=2)

    fill(_underside(cam, radius_m, s_m, lateral_m, width_m), (22, 22, 24))
    fill(_rear_corners(cam, radius_m, s_m, lateral_m, width_m, 0.12, 0.35), (18, 18, 20))  # bumper shadow and tyres
    fill(_rear_corners(cam, radius_m, s_m, lateral_m, width_m, 0.35, 1.5), body)
    fill(_rear_corners(cam, radius_m, s_m, lateral_m, width_m, 1.0, 1.4, -0.4, 0.4), (45, 40, 38))
    for a, b in ((-0.48, -0.3), (0.3, 0.48)):
        fill(_rear_corners(cam, radius_m, s_m, lateral_m, width_m, 0.8, 1.0, a, b), lamps)
    return out


def drive_behind(cam: CameraModel, radius_m: float, lane_m: float, paint: str, grey: int, seed: int, s_m: float,
                 lateral_m: float, width_m: float, body: str) -> FrameAnalysis:
    """Three frames of straight empty road, three of the empty bend (the lane tracks settle on it), then twelve with
    the vehicle on it: the last analysis (a box found in any of the twelve would still be coasting in the track)."""
    p = FramePipeline(cam, 20.0)
    a = None
    for i in range(18):
        frame = curved_lane(cam, radius_m if i >= 3 else math.inf, lane_m, PAINTS[paint], grey, False, seed + i)
        if i >= 6:
            frame = with_vehicle(frame, cam, radius_m, s_m, lateral_m, width_m, BODIES[body])
        a = p.process(frame, i / 20.0)
    assert a is not None
    return a


def true_bearing_deg(cam: CameraModel, radius_m: float, s_m: float, lateral_m: float) -> float:
    x, y = _yawed(*_boundary(radius_m, lateral_m, np.array([s_m])), 0.0)
    u, _v, _ = cam.project_ground(x, y)
    return cam.bearing_deg(float(u[0]))


vehicles = dict(
    fov=st.floats(60.0, 90.0), height=st.floats(1.2, 1.6), pitch=st.floats(1.0, 5.0),
    radius=st.sampled_from([500.0, 1000.0, math.inf]),
    left=st.booleans(), lane=st.floats(3.0, 3.8), paint=st.sampled_from(sorted(PAINTS)), grey=st.integers(80, 140),
    seed=st.integers(0, 1000), ahead=st.floats(7.0, 30.0), width=st.floats(1.6, 2.0), body=st.sampled_from(sorted(BODIES)),
)


def _lateral_of_curve(radius_m: float, s_m: float, lane_m: float) -> float:
    """How far the lane centre at ``s_m`` has turned away from the straight ahead, in lane widths (the chord's miss)."""
    _x, y = _boundary(radius_m, 0.0, np.array([s_m]))
    return abs(float(y[0])) / lane_m


@settings(max_examples=25, deadline=None, derandomize=True)
@given(**vehicles)
def test_a_vehicle_in_the_ego_lane_is_the_lead(fov, height, pitch, radius, left, lane, paint, grey, seed, ahead,
                                                          width, body) -> None:
    """The vehicle in the ego lane 7-30 m ahead and at least 12 pixels wide, on a straight road or a gentle bend
    (R 500 m up), is boxed at its bearing within 1.5° (a 1.7 m car 30 m ahead through a 90° lens is 9 pixels wide:
    missed). (On tighter bends a car far ahead stands beside the straight lines the lead is searched
    between — 28 m round R 100 m is 1.3 lane widths off the straight ahead — and is missed: counted below.)"""
    cam = camera(fov, height, pitch)
    assume(cam.fx_px * width / ahead >= 12.0)  # a car narrower than 12 of the 320 pixels is past what the search can box
    r = radius if left else -radius
    a = drive_behind(cam, r, lane, paint, grey, seed, ahead, 0.0, width, body)
    assert a.lead is not None, (r, ahead, _lateral_of_curve(r, ahead, lane))
    assert abs(a.lead.bearing_deg - true_bearing_deg(cam, r, ahead, 0.0)) <= 1.5


@settings(max_examples=25, deadline=None, derandomize=True)
@given(**vehicles, side=st.sampled_from([-1.0, 1.0]))
def test_a_vehicle_in_the_next_lane_is_not_the_lead(fov, height, pitch, radius, left, lane, paint, grey, seed, ahead, width, body,
                                                    side) -> None:
    """A vehicle one lane to either side on a straight road or a gentle bend (R 500 m up) is never boxed as a lead (it
    would slow the car for traffic it is passing)."""
    cam = camera(fov, height, pitch)
    r = radius if left else -radius
    a = drive_behind(cam, r, lane, paint, grey, seed, ahead, side * lane, width, body)
    assert a.lead is None


def test_on_bends_of_r100_to_250_m_the_lead_is_found_and_a_next_lane_car_seldom_taken_for_it() -> None:
    """40 seeded bends of R 100-250 m (docs/perception.md's table, the same cases): the car in the ego lane is boxed at
    its bearing in at least 39; a car in the next lane instead is boxed in at most FALSE_LEADS_MAX — far ahead on a
    bend the straight lines the lead is searched between run into the lane on the bend's outside. A known weakness,
    pinned so that a change that makes either worse is seen."""
    rng = np.random.default_rng(7)
    false = found = 0
    for _ in range(40):
        cam = camera(rng.uniform(60, 90), rng.uniform(1.2, 1.6), rng.uniform(1, 5))
        r = float(rng.choice([-1, 1]) * rng.uniform(100, 250))
        lane = rng.uniform(3.0, 3.8)
        road = (str(rng.choice(sorted(PAINTS))), int(rng.integers(80, 141)), int(rng.integers(1000)), rng.uniform(7, 30))
        side, width, body = float(rng.choice([-1.0, 1.0])), rng.uniform(1.6, 2.0), str(rng.choice(sorted(BODIES)))
        false += drive_behind(cam, r, lane, *road, side * lane, width, body).lead is not None
        lead = drive_behind(cam, r, lane, *road, 0.0, width, body).lead
        found += lead is not None and abs(lead.bearing_deg - true_bearing_deg(cam, r, road[3], 0.0)) <= 1.5
    assert found >= 39 and false <= FALSE_LEADS_MAX, (found, false)


def test_tail_lights_above_the_road_rows_are_seen() -> None:
    """A white SUV 22 m round a right bend of R 60 m, seen from 1.5 m up with a 70° lens: its lamps lie above the road
    region's top row, where the working images hold nothing; looked for in the frame, the car is boxed (before: no
    lead at 22 m on R 60, 100 and 150 m alike)."""
    cam = camera(70.0, 1.5, 2.0)
    a = drive_behind(cam, -60.0, 3.5, "white", 110, 7, 22.0, 0.0, 1.9, "white")
    assert a.lead is not None and abs(a.lead.bearing_deg - true_bearing_deg(cam, -60.0, 22.0, 0.0)) <= 1.5
