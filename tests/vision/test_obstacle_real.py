"""An object standing in the ego lane, any colour, gets the flat-ground range of the row it stands on (real stills)."""

from __future__ import annotations

import math
from pathlib import Path

import cv2
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st
from tests.perturb import with_box

import fearguard as fg
from fearguard.camera import CameraModel

COLOURS = {"orange cone": (0, 140, 255), "yellow duck": (40, 210, 230), "grey box": (90, 90, 90), "white box": (240, 240, 240)}
ROWS = {"far": (0.70, 0.78), "near": (0.80, 0.88)}


@pytest.fixture(scope="module")
def stills(shared_data: Path):
    return {p.name: cv2.imread(str(p)) for p in sorted((shared_data / "road" / "images").glob("*.jpg"))}


def _camera(frame) -> CameraModel:
    h, w = frame.shape[:2]
    return CameraModel.default(w, h, mount_height_m=1.2)  # a dash-cam 1.2 m above the road, level


def test_clean_road_has_no_object_in_the_lane(stills):
    """Known weakness: deep tree shadows (test4, test5) can read as an object; 12 of 14 clean stills see none."""
    seen = [name for name, img in stills.items() if fg.analyze_frame(img, _camera(img)).obstacle is not None]
    assert len(seen) <= 2, seen


def test_objects_of_any_colour_get_the_ground_plane_range_of_their_lowest_row(stills):
    checked = 0
    for name, img in stills.items():
        cam = _camera(img)
        if fg.analyze_frame(img, cam).obstacle is not None:
            continue  # a shadow already reads as an object here (see above)
        h = img.shape[0]
        for colour in COLOURS.values():
            ranges = {}
            for row, (v0, v1) in ROWS.items():
                found = fg.analyze_frame(with_box(img, (0.45, v0, 0.55, v1), colour), cam).obstacle
                assert found is not None and found.range_m is not None, (name, colour, row)
                expected = cam.ground_range_m(v1 * h)
                assert found.range_m == pytest.approx(expected, rel=0.25), (name, colour, row)
                ranges[row] = found.range_m
            assert ranges["near"] < ranges["far"]
            checked += 1
    assert checked >= 4 * 12


def test_without_mounting_height_there_is_no_range_and_no_search(stills):
    img = stills["solidWhiteRight.jpg"]
    assert fg.analyze_frame(with_box(img, (0.45, 0.8, 0.55, 0.88), (0, 140, 255))).obstacle is None


def test_a_car_without_a_range_sensor_brakes_for_what_its_camera_sees(stills):
    """The camera's ground-plane range of an object in the lane reaches the obstacle cue (it used to be overwritten
    with "nothing in range" by the supervisor), once the object has been seen on consecutive frames."""
    import numpy as np

    img = stills["solidWhiteRight.jpg"]
    cam = _camera(img)
    car = fg.VehicleLimits(has_ultrasonic=False, has_qr_localisation=False)
    rng = np.random.default_rng(0)

    def frames(picture):
        for _ in range(6):  # fresh sensor noise each frame: a camera, not a frozen picture
            yield np.clip(picture.astype(np.int16) + rng.integers(-2, 3, picture.shape), 0, 255).astype(np.uint8)

    clear = fg.FearGuard(fg.HoughLaneSteering(cam), vehicle=car, camera=cam)
    cmds = [clear.step(fg.Observation(t_s=0.05 * k, speed_mps=1.0, frame=f)) for k, f in enumerate(frames(img))]
    assert all(c.cues.obstacle_range_m == float("inf") for c in cmds)
    boxed = fg.FearGuard(fg.HoughLaneSteering(cam), vehicle=car, camera=cam)
    with_cone = with_box(img, (0.45, 0.80, 0.55, 0.88), (0, 140, 255))
    cmds = [boxed.step(fg.Observation(t_s=0.05 * k, speed_mps=1.0, frame=f)) for k, f in enumerate(frames(with_cone))]
    assert cmds[0].cues.obstacle_range_m == float("inf")  # one frame is no object yet
    last = cmds[-1]
    assert last.cues.obstacle_range_m == pytest.approx(cam.ground_range_m(0.88 * img.shape[0]), rel=0.25)
    assert any("camera: object in the lane" in f for f in last.perceived.facts)


@settings(max_examples=8, deadline=None, derandomize=True, suppress_health_check=[HealthCheck.function_scoped_fixture])
@given(range_m=st.floats(0.3, 150.0), bearing=st.floats(-20.0, 20.0))
def test_a_camera_only_car_reads_the_vehicle_it_boxed_in_its_lane_as_the_obstacle(stills, range_m: float, bearing: float):
    """A vehicle boxed in the ego lane (the camera's own box, or an external detector's ``Observation.lead``) is the
    obstacle range of a car without a range sensor when it is nearer than any object the lane search found: a slower
    truck ahead was boxed from 34 m in MetaDrive while the search found it at 16 m, and the car stopped at a 9.6 m gap
    instead of following (docs/metadrive.md). A car with a range sensor keeps its sensor's reading."""
    img = stills["solidWhiteRight.jpg"]
    cam = _camera(img)
    lead = fg.Lead(bearing_deg=bearing, range_m=range_m)
    camera_only = fg.FearGuard(fg.HoughLaneSteering(cam), vehicle=fg.VehicleLimits(has_ultrasonic=False, has_qr_localisation=False),
                               camera=cam)
    cmd = camera_only.step(fg.Observation(t_s=0.0, speed_mps=1.0, frame=img, lead=lead))
    assert cmd.cues.obstacle_range_m == range_m
    assert any("vehicle ahead in the lane" in f for f in cmd.perceived.facts)
    sensed = fg.FearGuard(fg.HoughLaneSteering(cam), vehicle=fg.VehicleLimits(has_ultrasonic=True, has_qr_localisation=False),
                          camera=cam)
    cmd = sensed.step(fg.Observation(t_s=0.0, speed_mps=1.0, frame=img, lead=lead, ultrasonic_range_m=math.inf))
    assert cmd.cues.obstacle_range_m == math.inf
