"""A car that has stopped in front of a standing box stays stopped while the box is there.

Found in the real Donkey loop (CI, ``tests/integrations/test_donkey_loop.py``): the car stopped 0.32 m before a box,
its speed estimated from the throttle (no odometer) decaying toward 0 — 0.007 m/s two seconds later — while the range
filter read a steady gap. "Ego at 0.007 m/s, closing 0" read as a lead moving away at 0.007 m/s, a steady gap demands no
braking, collision fear read "nothing in range", the hold ran out, NORMAL, and the car drove on into the box. An object
moving no faster than the rules' ``moving_object_min_mps`` stands (``decision.fear_range_m``).
"""

from __future__ import annotations

import math
from dataclasses import replace

from hypothesis import given, settings
from hypothesis import strategies as st

import fearguard as fg
from fearguard.policy.decision import fear_range_m
from fearguard.testing.subject import distinct_presets

CALM = fg.Cues(lane_confidence=1.0, brightness=130.0, occlusion=0.0, obstacle_range_m=math.inf, qr_staleness_s=0.0)
RULES = {"default": fg.load_rules(), "road_car": fg.load_rules("rules/road_car.toml"), "duckiebot": fg.load_rules("rules/duckiebot.toml")}
CARS = {name: (car, RULES["road_car"] if car.max_speed_mps > 10 else RULES["duckiebot"] if car.max_speed_mps <= 0.5
         else RULES["default"]) for name, car in distinct_presets().items() if car.has_ultrasonic}
DT = 0.05  # [s] a 20 Hz loop


def emergency_range_m(rules: fg.RuleBase) -> float:
    """The farthest range (of a coarse scan) at which a standing obstacle alone demands an emergency."""
    top = rules.policy.emergency_enter_fear
    scan = [k * 0.01 for k in range(1, 5000)]
    return max(d for d in scan if rules.evaluate(replace(CALM, obstacle_range_m=d)).fear >= top + 0.02)


@given(d=st.floats(0.1, 200), v=st.floats(0.0, 0.3), c=st.floats(-1.0, 1.0), slowest=st.floats(0.0, 0.3))
def test_an_object_no_faster_than_the_slowest_moving_speed_reads_as_it_is(d: float, v: float, c: float, slowest: float) -> None:
    if v - c <= slowest:
        assert fear_range_m(d, v, c, slowest) == d


@settings(max_examples=60, deadline=None)
@given(
    name=st.sampled_from(sorted(CARS)), at=st.floats(0.3, 1.0), seconds=st.floats(3.0, 6.0),
    speeds=st.lists(st.floats(0.0, 1.0), min_size=1, max_size=8), rates=st.lists(st.floats(0.0, 1.0), min_size=1, max_size=8),
)
def test_standing_before_a_box_that_demands_an_emergency_the_car_is_never_told_to_move(
    name: str, at: float, seconds: float, speeds: list[float], rates: list[float],
) -> None:
    """Any preset, standing before a box at a range that alone demands an emergency; the car's speed estimate anywhere within the
    rules' standstill speed (a decaying throttle model, wheel-speed noise), the range rate noisy too, the box's apparent
    speed (speed + range rate) never above ``moving_object_min_mps``."""
    car, rules = CARS[name]
    still, slowest = rules.policy.standstill_mps, rules.policy.moving_object_min_mps
    d = max(car.ultrasonic_min_range_m, at * emergency_range_m(rules))
    guard = fg.FearGuard(lambda f: 0.0, rules=rules, vehicle=car)
    for k in range(int(seconds / DT)):
        v = still * speeds[k % len(speeds)]
        rate = -still + slowest * rates[k % len(rates)]  # v + rate ≤ still − still + slowest
        cmd = guard.step(fg.Observation(t_s=k * DT, speed_mps=v, cues=replace(CALM, obstacle_range_m=d), range_rate_mps=rate))
        assert not any("nothing in range" in r for r in cmd.reasons), cmd.reasons
        if k >= rules.policy.enter_frames:  # the mode machine's confirmation: then stopped, for as long as the box stands
            assert cmd.mode is fg.Mode.EMERGENCY and cmd.speed_limit_mps == 0.0, (k, v, rate, cmd.mode, cmd.reasons)
