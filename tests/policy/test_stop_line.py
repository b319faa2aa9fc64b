"""Stop lines (issue 35): brake to stand before the line, wait, cross; no second stop while crossing; off when the
rule file says 0."""

from __future__ import annotations

import dataclasses
import math

from hypothesis import given
from hypothesis import strategies as st

import fearguard as fg
from fearguard.policy import PolicyConfig
from fearguard.policy.speed import envelope_speed_mps
from fearguard.policy.stop_line import StopLine, next_stop_line

CFG = dataclasses.replace(PolicyConfig(), stop_line_wait_s=1.0, stop_line_cross_m=0.6)
BOT = fg.VehicleLimits.preset("duckiebot")


def test_off_when_the_wait_is_zero() -> None:
    state, cap, why = next_stop_line(StopLine(), 0.3, 0.2, 0.0, 0.1, PolicyConfig(), BOT)
    assert math.isinf(cap) and why == "" and state == StopLine()


def test_brake_stand_wait_cross_then_no_second_stop_until_crossed() -> None:
    state, t, speed, caps = StopLine(), 0.0, 0.2, []
    for k in range(80):
        t += 0.1
        line = 0.3 if k < 5 else None  # seen late, then it passes under the camera
        state, cap, why = next_stop_line(state, line, speed, t, 0.1, CFG, BOT)
        caps.append((cap, why, state))
        speed = 0.0 if cap <= 0.0 else min(0.2, cap)
    assert caps[0][0] == 0.0  # seen within the stopping distance and a second of travel: stop now
    served = [k for k, (_, why, _) in enumerate(caps) if "crossing" in why]
    assert served, "the stop was never served"
    first = served[0]
    stood = [k for k, (_, why, _) in enumerate(caps[:first]) if "standing" in why]
    assert all(cap == 0.0 for cap, _, _ in caps[:first])  # out of view, it is still stopped for
    assert stood and 0.1 * (first - stood[0]) >= CFG.stop_line_wait_s - 0.1 - 1e-9
    assert all(math.isinf(cap) for cap, _, s in caps[first:] if s.crossed_m is not None)  # crossing: the same line is no stop


def test_a_far_line_caps_at_the_envelope_for_a_standing_obstacle_there() -> None:
    _, cap, why = next_stop_line(StopLine(), 3.0, 0.2, 0.0, 0.05, CFG, BOT)
    assert cap == envelope_speed_mps(3.0, BOT) and "approaching" in why


@given(line=st.floats(0.0, 5.0), speed=st.floats(0.0, 3.0))
def test_a_line_never_raises_a_cap_above_the_envelope_for_a_standing_obstacle_there(line: float, speed: float) -> None:
    _, cap, _ = next_stop_line(StopLine(), line, speed, 0.0, 0.05, CFG, BOT)
    assert cap <= envelope_speed_mps(line, BOT) + 1e-12
