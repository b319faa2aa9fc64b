"""A camera-only car's range ahead: the nearer of the object search's and the vehicle box's, and no closing speed from
the jump when the box starts ranging the object the search ranged (MetaDrive seed 23, traffic 0.15: a car followed at
its own speed read 19.2 m by the search, then 13.8 m by its box; the jump read as a standing car, EMERGENCY STOP).
"""

from __future__ import annotations

import math
from dataclasses import replace

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

import fearguard as fg
import fearguard.perception as perception_module
from fearguard.observation import Lead
from fearguard.perception import SAME_RANGE_SHARE, CameraRange, fuse_camera_ranges
from fearguard.vision.frame import FrameAnalysis
from fearguard.vision.obstacle import Obstacle

ranges = st.one_of(st.just(math.inf), st.floats(0.3, 120.0))
bearings = st.floats(-30.0, 30.0)
sources = st.sampled_from([None, "object", "vehicle"])


@settings(max_examples=400, deadline=None)
@given(ranges, bearings, ranges, bearings, sources, st.floats(0.0, 2.0))
def test_the_range_is_always_the_nearer_reading_and_a_shift_only_moves_the_history_nearer(
    object_m: float, object_deg: float, vehicle_m: float, vehicle_deg: float, previous: str | None, lateral: float,
) -> None:
    fused = fuse_camera_ranges(object_m, object_deg, vehicle_m, vehicle_deg, previous, lateral)
    assert fused.range_m == min(object_m, vehicle_m)
    assert fused.source == ("vehicle" if vehicle_m < object_m else "object" if math.isfinite(object_m) else None)
    assert fused.shift_m <= 0.0
    if fused.shift_m < 0.0:  # only from the search's object (last frame) to a box ranging it nearer, never the other way
        assert previous == "object" and fused.source == "vehicle"
        assert fused.shift_m == pytest.approx(vehicle_m - object_m)
        assert vehicle_m >= SAME_RANGE_SHARE * object_m


def test_seed_23s_car_is_one_object_ranged_better() -> None:
    assert fuse_camera_ranges(19.22, -9.3, 13.80, -9.7, "object", 0.9) == CameraRange(13.80, "vehicle", pytest.approx(-5.42))
    # the box already ranged it last frame: nothing to shift
    assert fuse_camera_ranges(19.22, -9.3, 13.80, -9.7, "vehicle", 0.9).shift_m == 0.0


@pytest.mark.parametrize(
    ("object_m", "object_deg", "vehicle_m", "vehicle_deg", "why"),
    [
        (30.0, 0.0, 14.0, 0.0, "a box at less than half the search's range: something else, nearer"),
        (19.2, 0.0, 13.8, 12.0, "a box 2.9 m to the side of the search's object: another object"),
        (12.0, 0.0, 25.0, 0.0, "the search finds something nearer than the box: maybe a new object in front of it"),
    ],
)
def test_no_shift_where_the_two_readings_need_not_be_one_object(object_m, object_deg, vehicle_m, vehicle_deg, why) -> None:
    assert fuse_camera_ranges(object_m, object_deg, vehicle_m, vehicle_deg, "object", 0.9).shift_m == 0.0, why


# -- through Perception and the supervisor ----------------------------------------------------------------------------
ROAD = replace(fg.VehicleLimits.preset("road_car"), has_ultrasonic=False)  # a camera-only road car (MetaDrive's)
RULES = fg.load_rules("rules/road_car.toml")
FRAME = np.zeros((120, 160, 3), np.uint8)  # the pictures' content is scripted below: the analysis is replaced


def analysis(object_m: float, vehicle_m: float | None) -> FrameAnalysis:
    """A calm road picture whose object search finds something ``object_m`` ahead and, maybe, a vehicle box."""
    obstacle = Obstacle(100.0, 140.0, 80.0, -9.3, object_m)
    lead = Lead(-9.7, vehicle_m) if vehicle_m is not None else None
    return FrameAnalysis(lane_confidence=0.95, brightness=120.0, occlusion=0.0, lead=lead, qr_payloads=(), steering_deg=0.0,
                         obstacle=obstacle)


def follow(monkeypatch: pytest.MonkeyPatch, *, shift: bool) -> list[fg.Command]:
    """8.4 m/s behind a car at the same speed: 3 s ranged by the object search alone (19.2 m), then 3 s by its box too
    (13.8 m). ``shift=False``: the fusion without the history shift (what main did before)."""
    if not shift:
        real = fuse_camera_ranges
        monkeypatch.setattr(perception_module, "fuse_camera_ranges", lambda *a: replace(real(*a), shift_m=0.0))
    guard = fg.FearGuard(lambda f: 0.0, rules=RULES, vehicle=ROAD)
    script = iter([analysis(19.2, None)] * 30 + [analysis(19.2, 13.8)] * 30)
    monkeypatch.setattr(guard.perception, "_vision", lambda *a, **k: next(script))
    return [guard.step(fg.Observation(t_s=0.1 * k, speed_mps=8.4, frame=FRAME)) for k in range(60)]


def test_a_car_ranged_better_by_its_box_is_still_followed_not_stopped_for(monkeypatch: pytest.MonkeyPatch) -> None:
    cmds = follow(monkeypatch, shift=True)
    assert all(c.mode is not fg.Mode.EMERGENCY for c in cmds)
    switch = cmds[30]
    assert any("the same object, ranged better" in f for f in switch.perceived.facts)  # shown with the reasons when fear is up
    assert switch.closing_speed_mps == pytest.approx(ROAD.lead_max_decel_mps2 * 0.15)  # the lag term alone, not 5.4 m in 0.1 s
    assert min(c.speed_limit_mps for c in cmds[30:]) > 0.0


def test_without_the_shift_the_jump_reads_as_a_standing_car(monkeypatch: pytest.MonkeyPatch) -> None:
    cmds = follow(monkeypatch, shift=False)
    assert any(c.mode is fg.Mode.EMERGENCY for c in cmds[30:36])
