"""Issue 35: how a creep steers (the lane seen now, else the wrapped estimator within a bound, else the plan's held
steering), and how collision fear reads an object that keeps moving."""

from __future__ import annotations

import math

from hypothesis import given
from hypothesis import strategies as st

from fearguard.fear import Cause
from fearguard.policy.config import Strategy
from fearguard.policy.decision import emergency_step, fear_range_m
from fearguard.policy.emergency import EmergencyPlan

CRAWL = EmergencyPlan(Strategy.CRAWL, 0.3, 1.5, "road not trusted: re-acquisition creep", Cause.ROAD)
STOP = EmergencyPlan(Strategy.STOP, 0.0, 1.5, "road not trusted: stop", Cause.ROAD)


def test_a_creep_steers_by_the_lane_seen_now_first() -> None:
    choice = emergency_step(CRAWL, "creep 1", -2.0, 0.0, "", estimator_deg=9.0, max_creep_deg=15.0)
    assert choice.steering_deg == -2.0 and any("lane geometry seen now" in r for r in choice.reasons)


@given(estimator=st.floats(-90, 90), bound=st.floats(0.5, 30))
def test_without_a_lane_a_creep_follows_the_estimator_within_its_bound(estimator: float, bound: float) -> None:
    choice = emergency_step(CRAWL, "creep 1", None, 0.0, "", estimator_deg=estimator, max_creep_deg=bound)
    assert abs(choice.steering_deg) <= bound + 1e-12
    assert choice.steering_deg == max(-bound, min(bound, estimator))


def test_a_distrusted_estimator_leaves_the_held_steering_and_a_stop_says_why() -> None:
    assert emergency_step(CRAWL, "creep 1", None, 0.0, "", estimator_deg=None).steering_deg == 1.5
    stop = emergency_step(STOP, "", None, 0.0, "recovery: analysing at standstill", estimator_deg=4.0)
    assert stop.steering_deg == 1.5 and stop.reasons[-1] == "recovery: analysing at standstill"


@given(d=st.floats(0.1, 200), v=st.floats(0.1, 40), c=st.floats(-40, 40))
def test_a_moving_object_never_reads_nearer_than_it_is_and_closing_faster_reads_nearer(d: float, v: float, c: float) -> None:
    read = fear_range_m(d, v, c)
    assert read >= d
    if c >= v:
        assert read == d  # standing, or coming toward the car: as it is
    if c <= 0:
        assert math.isinf(read)  # a steady or opening gap demands no braking
    if 0 < c < v:
        assert fear_range_m(d, v, min(v, c * 1.5)) <= read


def test_unknown_motion_reads_the_range_as_it_is() -> None:
    assert fear_range_m(5.0, None, 1.0) == 5.0 and fear_range_m(5.0, 2.0, None) == 5.0 and fear_range_m(5.0, 2.0, math.nan) == 5.0
    assert fear_range_m(math.inf, 2.0, 1.0) == math.inf and fear_range_m(5.0, 0.0, 0.0) == 5.0
