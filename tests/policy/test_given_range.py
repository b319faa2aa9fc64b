"""A range the caller gives is never thrown away (issue 31): it binds the envelope and feeds fear, whatever the car declares.

``has_ultrasonic = False`` only means that ``inf`` ("nothing known in range") is not a fault; a finite reading counts,
and one beyond the sensor's maximum counts as "nothing within the maximum", never as that many metres.
"""

from __future__ import annotations

import math
from collections import deque
from dataclasses import replace

import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

import fearguard as fg
from fearguard.testing.history import Step
from fearguard.testing.invariants import check_safe_distance
from fearguard.testing.subject import Subject, distinct_presets
from fearguard.vehicle import PRESETS

CALM = fg.Cues(lane_confidence=1.0, brightness=130.0, occlusion=0.0, obstacle_range_m=math.inf, qr_staleness_s=0.0)
CARS = {f"{name}{'' if has else '-no-sensor'}": replace(car, has_ultrasonic=has)
        for name, car in distinct_presets().items() for has in (True, False)}
RULES = {"default": fg.load_rules(), "road_car": fg.load_rules("rules/road_car.toml"), "duckiebot": fg.load_rules("rules/duckiebot.toml")}


def rules_for(car: fg.VehicleLimits) -> fg.RuleBase:
    return RULES["road_car"] if car.max_speed_mps > 10 else RULES["duckiebot"] if car.max_speed_mps <= 0.5 else RULES["default"]


def test_a_range_of_zero_on_a_camera_only_car_stops_it() -> None:
    guard = fg.FearGuard(lambda f: 0.0, vehicle=fg.VehicleLimits(max_speed_mps=2.0))
    cmds = [guard.step(fg.Observation(t_s=0.05 * k, speed_mps=1.0, cues=replace(CALM, obstacle_range_m=0.0))) for k in range(3)]
    assert all(c.mode is fg.Mode.EMERGENCY and c.strategy is fg.Strategy.STOP and c.speed_limit_mps == 0.0 for c in cmds)
    notes = [r for c in cmds for r in c.reasons if "declares no range sensor" in r]
    assert len(notes) == 1 and "counted" in notes[0]  # said once, not every frame
    assert cmds[0].cause is fg.Cause.COLLISION


def _drive_to_obstacle(car: fg.VehicleLimits, rules: fg.RuleBase, start_m: float, dt: float = 0.05) -> tuple[float, float]:
    """A longitudinal simulation: the car at top speed toward a standing obstacle reported in the cues; it follows the
    speed limit after its reaction time and brakes at its stated deceleration. (smallest gap, final speed)."""
    guard = fg.FearGuard(lambda f: 0.0, rules=rules, vehicle=car)
    v, gap, t = car.max_speed_mps, start_m, 0.0
    delay = deque([car.max_speed_mps] * max(1, round(car.reaction_time_s / dt)))
    smallest = gap
    for _ in range(int(60.0 / dt)):
        cmd = guard.step(fg.Observation(t_s=t, speed_mps=v, cues=replace(CALM, obstacle_range_m=max(gap, 0.0))))
        delay.append(cmd.speed_limit_mps)
        wanted = delay.popleft()
        v = max(wanted, v - car.max_decel_mps2 * dt) if wanted < v else v
        gap -= v * dt
        smallest = min(smallest, gap)
        t += dt
        if v == 0.0:
            break
    return smallest, v


def test_a_road_car_that_declares_no_radar_still_stops_for_an_obstacle_reported_in_the_cues() -> None:
    car = replace(PRESETS["road_car"], has_ultrasonic=False)  # radar numbers given, has_ultrasonic left at False
    smallest, v = _drive_to_obstacle(car, RULES["road_car"], 120.0)
    assert v == 0.0 and smallest > 0.0  # on main at 0ffbd56 the gap went to -471 m


def test_a_road_car_keeps_its_gap_to_a_lead_braking_hard() -> None:
    car = replace(PRESETS["road_car"], has_ultrasonic=False)
    guard = fg.FearGuard(lambda f: 0.0, rules=RULES["road_car"], vehicle=car)
    dt, v, lead_v, gap, t = 0.05, 25.0, 25.0, 60.0, 0.0
    delay = deque([v] * round(car.reaction_time_s / dt))
    smallest = gap
    for k in range(int(30.0 / dt)):
        lead_v = lead_v if k * dt < 2.0 else max(0.0, lead_v - 6.0 * dt)  # the lead brakes at -6 m/s² after 2 s
        cmd = guard.step(fg.Observation(t_s=t, speed_mps=v, cues=replace(CALM, obstacle_range_m=gap)))
        delay.append(cmd.speed_limit_mps)
        wanted = delay.popleft()
        v = max(wanted, v - car.max_decel_mps2 * dt) if wanted < v else min(wanted, v + 1.0 * dt)
        gap += (lead_v - v) * dt
        smallest = min(smallest, gap)
        t += dt
    assert smallest > 0.0 and v == 0.0


@pytest.mark.parametrize("name", sorted(CARS))
def test_2_safe_distance_for_every_finite_range_given(name: str) -> None:
    """Invariant 2 at any finite range in the cues (also beyond the sensor's maximum), with and without has_ultrasonic."""
    car = CARS[name]
    subject = Subject(rules_for(car), car)
    top = car.ultrasonic_max_range_m

    @settings(max_examples=40, deadline=None, derandomize=True, database=None)
    @given(d=st.one_of(st.floats(0.0, 2.0 * top), st.floats(top, 1e6)), dt=st.sampled_from([0.05, 0.1]),
           v0=st.floats(0.0, car.max_speed_mps))
    def steady(d: float, dt: float, v0: float) -> None:
        n = math.ceil((car.max_speed_mps / subject.rules.policy.comfort_accel_mps2 + 2.0) / dt)
        history = tuple(Step(t_s=k * dt, speed_mps=v0, cues=replace(CALM, obstacle_range_m=d), steer_output=0.0) for k in range(n))
        from fearguard.testing.history import Case

        assert check_safe_distance(subject, Case.drive(history)) is None

    steady()


def _last(car: fg.VehicleLimits, rules: fg.RuleBase, prefix: list[float], last: float, speed: float) -> fg.Command:
    guard = fg.FearGuard(lambda f: 0.0, rules=rules, vehicle=car)
    cmd = None
    for k, d in enumerate([*prefix, last]):
        cmd = guard.step(fg.Observation(t_s=0.1 * k, speed_mps=speed, cues=replace(CALM, obstacle_range_m=d)))
    assert cmd is not None
    return cmd


@pytest.mark.parametrize("name", sorted(CARS))
def test_3_monotone_over_ranges_beyond_the_sensors_maximum(name: str) -> None:
    """A nearer reading never gives a higher limit nor a lower fear, up to and beyond the maximum, and inf above all."""
    car = CARS[name]
    rules, top = rules_for(car), car.ultrasonic_max_range_m

    @settings(max_examples=30, deadline=None, derandomize=True, database=None)
    @given(a=st.floats(0.0, 50.0 * top), b=st.one_of(st.floats(0.0, 50.0 * top), st.just(math.inf)),
           prefix=st.lists(st.one_of(st.floats(0.0, 5.0 * top), st.just(math.inf)), max_size=6),
           speed=st.floats(0.0, car.max_speed_mps))
    def pair(a: float, b: float, prefix: list[float], speed: float) -> None:
        near, far = min(a, b), max(a, b)
        cn, cf = _last(car, rules, prefix, near, speed), _last(car, rules, prefix, far, speed)
        assert cn.speed_limit_mps <= cf.speed_limit_mps + 1e-12
        assert cn.fear >= cf.fear - 1e-12

    pair()


def test_a_reading_beyond_the_maximum_counts_as_the_maximum_not_as_its_metres() -> None:
    car = PRESETS["hc_sr04_pi"]  # HC-SR04, 3.96 m
    far = _last(car, RULES["default"], [], 731.0, 1.0)
    nothing = _last(car, RULES["default"], [], math.inf, 1.0)
    at_max = _last(car, RULES["default"], [], car.ultrasonic_max_range_m, 1.0)
    assert far.speed_limit_mps == nothing.speed_limit_mps == at_max.speed_limit_mps
    assert far.cues.obstacle_range_m == car.ultrasonic_max_range_m
    assert any("beyond the range sensor's maximum" in r for r in far.reasons)


@pytest.mark.parametrize("text", ["inf", b"inf", "5", None])
def test_text_in_the_range_cue_is_unknown_not_a_clear_road(text: object) -> None:
    cmd = _last(fg.VehicleLimits(), RULES["default"], [math.inf] * 4, text, 2.0)  # type: ignore[arg-type]
    assert cmd.mode is fg.Mode.EMERGENCY and cmd.strategy is fg.Strategy.STOP and cmd.speed_limit_mps == 0.0
    assert any(r.startswith("obstacle_range_m ") and r.endswith("is not a number: counted as its worst value") for r in cmd.reasons)


def test_a_range_reading_given_to_a_frame_level_camera_only_car_counts() -> None:
    guard = fg.FearGuard(lambda f: 0.0, vehicle=fg.VehicleLimits())
    cmd = guard.step(fg.Observation(t_s=0.0, speed_mps=1.0, ultrasonic_range_m=0.1))
    assert cmd.cues.obstacle_range_m == 0.1 and cmd.mode is fg.Mode.EMERGENCY and cmd.strategy is fg.Strategy.STOP
    assert any("declares no range sensor" in r for r in cmd.reasons)
    later = guard.step(fg.Observation(t_s=0.1, speed_mps=0.0, ultrasonic_range_m=None))
    assert later.cues.obstacle_range_m == math.inf  # missing on a car without a declared sensor: nothing known
    assert not any("declares no range sensor" in r for r in later.reasons)


def test_a_dict_as_cues_is_a_fault_with_a_reason() -> None:
    guard = fg.FearGuard(lambda f: 0.0)
    cmd = guard.step(fg.Observation(t_s=0.0, cues={"lane_confidence": 1.0}))  # type: ignore[arg-type]
    assert cmd.mode is fg.Mode.EMERGENCY and cmd.strategy is fg.Strategy.STOP and cmd.cause is None
    assert cmd.reasons[0] == "fault: Observation.cues must be a fearguard.Cues (or None), got dict"


def test_an_out_of_range_cue_says_which_value_and_why() -> None:
    guard = fg.FearGuard(lambda f: 0.0)
    cmd = guard.step(fg.Observation(t_s=0.0, cues=replace(CALM, lane_confidence=5.0)))
    assert "lane_confidence 5.0 is outside 0..1: counted as its worst value" in cmd.reasons
