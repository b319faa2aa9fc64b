"""Metrics on a hand-made run, and expectations: pass, fail, and a clear detail for unguarded runs."""

from __future__ import annotations

import dataclasses
import json
import math

import pytest

from fearguard.policy import Mode, Strategy
from fearguard.sim.metrics import Metrics, check_expectations
from fearguard.sim.scenario import Expectations, ModeBy, SpeedCap, StrategyBy
from fearguard.sim.world import Truth

DT = 0.5


def truth(k: int, speed: float, gap: float = math.inf, collided: bool = False, in_lane: bool = True, lat_acc: float = 0.0) -> Truth:
    closing = speed if math.isfinite(gap) else 0.0
    ttc = gap / closing if math.isfinite(gap) and closing > 0 else math.inf
    return Truth(k * DT, k * 1.0, 0.0, 0.0, k * 1.0, 0.0, speed, gap, closing, ttc, collided, in_lane, lat_acc, False, False)


def hand_made_run() -> Metrics:
    """10 frames 0.5 s apart, 1 m apart: out of the lane twice, a stop before an obstacle, modes switching."""
    m = Metrics()
    rows = [
        (2.0, math.inf, False, True, "NORMAL", "PASS_THROUGH"),
        (2.0, math.inf, False, False, "NORMAL", "PASS_THROUGH"),
        (2.0, math.inf, False, True, "CAUTION", "PASS_THROUGH"),
        (2.0, 4.0, False, True, "EMERGENCY", "STOP"),
        (1.0, 3.0, False, False, "EMERGENCY", "STOP"),
        (0.0, 2.5, False, False, "EMERGENCY", "STOP"),
        (0.0, 2.5, False, True, "EMERGENCY", "STOP"),
        (1.0, 2.0, False, True, "CAUTION", "PASS_THROUGH"),
        (2.0, 0.0, True, True, "EMERGENCY", "STOP"),
        (0.0, 0.0, True, True, "EMERGENCY", "STOP"),
    ]
    for k, (speed, gap, hit, lane, mode, strategy) in enumerate(rows):
        m.add(truth(k, speed, gap, hit, lane, lat_acc=0.3 * k), Mode[mode], strategy, 1.5, 0.1 * k)
    return m


def test_summary_of_a_hand_made_run() -> None:
    s = hand_made_run().summary()
    json.dumps(s, allow_nan=False)  # JSON-ready: no inf/NaN
    assert s["frames"] == 10
    assert s["duration_s"] == pytest.approx(5.0)
    assert s["distance_m"] == pytest.approx(9.0)
    assert s["mean_speed_mps"] == pytest.approx(12.0 / 10)
    assert s["collisions"] == 1 and s["first_collision_t_s"] == pytest.approx(4.0)
    assert s["lane_departures"] == 2 and s["time_outside_lane_s"] == pytest.approx(1.5)
    assert s["min_gap_m"] == 0.0 and s["min_ttc_s"] == 0.0
    assert s["time_in_mode_s"] == pytest.approx({"NORMAL": 1.0, "CAUTION": 1.0, "EMERGENCY": 3.0})
    assert s["time_in_strategy_s"] == pytest.approx({"PASS_THROUGH": 2.0, "STOP": 3.0})
    assert s["emergency_entries"] == 2 and s["mode_switches"] == 4
    assert s["first_mode_t_s"] == {"NORMAL": 0.0, "CAUTION": 1.0, "EMERGENCY": 1.5}
    assert s["peak_lat_accel_mps2"] == pytest.approx(2.7)
    assert s["stops"] == [{"t_s": 2.5, "s_m": 5.0, "gap_m": 2.5}, {"t_s": 4.5, "s_m": 9.0, "gap_m": 0.0}]
    assert s["guarded"] and s["max_fear"] == pytest.approx(0.9)


def test_no_object_ahead_gives_null_gap() -> None:
    m = Metrics()
    for k in range(3):
        m.add(truth(k, 1.0))
    s = m.summary()
    assert s["min_gap_m"] is None and s["min_ttc_s"] is None and not s["guarded"]
    assert s["time_in_mode_s"] == {"NORMAL": 0.0, "CAUTION": 0.0, "EMERGENCY": 0.0}
    assert Metrics().summary()["frames"] == 0


def results(expect: Expectations, metrics: Metrics) -> dict[str, tuple[bool, str]]:
    return {r.name: (r.ok, r.detail) for r in check_expectations(expect, metrics.result(), metrics.rows)}


def test_expectations_pass_and_fail_on_the_hand_made_run() -> None:
    expect = Expectations(
        no_collision=True, no_lane_departure=True, max_time_outside_lane_s=2.0, min_mean_speed_mps=1.0, max_mean_speed_mps=1.1,
        min_distance_m=9.0, max_distance_m=8.0, no_emergency=True, max_emergency_entries=2, max_mode_switches=3,
        stopped_before_obstacle=True, min_gap_m=0.1, min_ttc_s=1.0, max_lat_accel_mps2=3.0,
        mode_by=(ModeBy(2.0, "EMERGENCY"), ModeBy(0.5, "CAUTION")), strategy_by=(StrategyBy(1.5, "STOP"),),
        mode_not_before=(ModeBy(1.0, "EMERGENCY"), ModeBy(2.0, "EMERGENCY")),
        max_speed_between=(SpeedCap(0.5, t_s=2.5, until_s=4.0), SpeedCap(2.0, from_m=0.0, to_m=3.0), SpeedCap(0.5, from_m=50.0, to_m=60.0)),
    )
    got = results(expect, hand_made_run())
    passed = {name for name, (ok, _) in got.items() if ok}
    assert passed == {
        "max_time_outside_lane_s", "min_mean_speed_mps", "min_distance_m", "max_emergency_entries", "max_lat_accel_mps2",
        "mode_by EMERGENCY by 2 s", "strategy_by STOP by 1.5 s", "mode_not_before EMERGENCY before 1 s",
        "max_speed_between 0-3 m: 2 m/s", "max_speed_between 50-60 m: 0.5 m/s",
    }
    assert got["no_collision"] == (False, "1 collision(s) (first at 4.0 s)")
    assert got["mode_by CAUTION by 0.5 s"] == (False, "first CAUTION at 1.00 s")
    assert got["mode_not_before EMERGENCY before 2 s"] == (False, "EMERGENCY already at 1.50 s")
    assert got["stopped_before_obstacle"][1].startswith("stopped 2.50 m before it at 2.50 s")  # but it hit later: fails
    assert got["max_speed_between 2.5-4 s: 0.5 m/s"] == (False, "fastest 1.00 m/s there")
    assert "never closing" not in got["min_ttc_s"][1]
    assert len(got) == len(expect.names()) + 4  # one result per list entry


def test_mode_by_counts_a_more_cautious_mode_but_strategy_by_only_itself() -> None:
    m = Metrics()
    for k in range(10):  # straight to EMERGENCY (a fault on the first frame), CAUTION only later
        m.add(truth(k, 0.0), "EMERGENCY" if k < 6 else "CAUTION", "STOP" if k < 6 else "PASS_THROUGH", None, None)
    expect = Expectations(mode_by=(ModeBy(0.2, "CAUTION"), ModeBy(0.2, "NORMAL")), strategy_by=(StrategyBy(0.2, "CRAWL"),))
    got = results(expect, m)
    assert got["mode_by CAUTION by 0.2 s"] == (True, "first EMERGENCY at 0.00 s")
    assert got["mode_by NORMAL by 0.2 s"] == (True, "first EMERGENCY at 0.00 s")
    assert got["strategy_by CRAWL by 0.2 s"] == (False, "never CRAWL")
    cautious_only = Metrics()
    for k in range(10):
        cautious_only.add(truth(k, 0.0), "CAUTION", "PASS_THROUGH", None, None)
    got = results(Expectations(mode_by=(ModeBy(5.0, "EMERGENCY"),)), cautious_only)
    assert got["mode_by EMERGENCY by 5 s"] == (False, "never EMERGENCY")


def test_a_clean_run_meets_its_expectations() -> None:
    m = Metrics()
    for k in range(10):
        m.add(truth(k, 1.5 if k < 8 else 0.0, gap=10.0 - k), "NORMAL" if k < 3 else "EMERGENCY", "STOP", None, None)
    expect = Expectations(no_collision=True, no_lane_departure=True, stopped_before_obstacle=True, min_gap_m=1.0,
                          mode_by=(ModeBy(2.0, "EMERGENCY"),), max_emergency_entries=1)
    assert all(ok for ok, _ in results(expect, m).values())


def test_supervisor_only_expectations_do_not_apply_to_a_baseline() -> None:
    m = Metrics()
    for k in range(4):
        m.add(truth(k, 1.0))
    expect = Expectations(no_collision=True, no_emergency=True, mode_by=(ModeBy(1.0, "EMERGENCY"),),
                          strategy_by=(StrategyBy(1.0, "FOLLOW_LEAD"),), min_gap_m=0.5)
    got = results(expect, m)
    assert got["no_collision"][0] and got["min_gap_m"] == (True, "no object ahead at any time")
    na = (None, "n/a: judges the supervisor's mode, and this controller has none (a baseline)")
    for name in ("mode_by EMERGENCY by 1 s", "strategy_by FOLLOW_LEAD by 1 s", "no_emergency"):
        assert got[name] == na  # neither a failure a baseline cannot avoid nor a vacuous pass
    checked = check_expectations(expect, m.result(), m.rows)
    assert [r.name for r in checked if not r.outcome] == ["no_emergency", "mode_by EMERGENCY by 1 s", "strategy_by FOLLOW_LEAD by 1 s"]
    assert not any(r.failed for r in checked)


def test_modes_may_be_given_as_enum_members_or_names() -> None:
    m = Metrics()
    m.add(truth(0, 1.0), Mode.NORMAL, Strategy.PASS_THROUGH)
    m.add(truth(1, 0.5), "EMERGENCY", "STOP")
    got = check_expectations(Expectations(mode_by=(ModeBy(0.5, "EMERGENCY"),)), m.result(), m.rows)
    assert [(r.ok, r.detail) for r in got] == [(True, "first EMERGENCY at 0.50 s")]
    assert [r.mode for r in m.rows] == ["NORMAL", "EMERGENCY"]


def test_an_unknown_speed_cannot_show_a_cap_was_kept() -> None:
    m = Metrics()
    m.add(truth(0, math.nan), "EMERGENCY", "STOP")
    got = check_expectations(Expectations(max_speed_between=(SpeedCap(1.0, t_s=0.0, until_s=5.0),)), m.result(), m.rows)
    assert [r.ok for r in got] == [False]


def test_there_is_one_checker_per_expectation_in_the_order_they_are_checked() -> None:
    from fearguard.sim.metrics import CHECKS
    from fearguard.sim.scenario_values import EXPECTATION_NAMES

    assert tuple(CHECKS) == EXPECTATION_NAMES == tuple(f.name for f in dataclasses.fields(Expectations))


def test_a_run_without_frames_summarises_to_the_counts_only() -> None:
    s = Metrics().summary()
    assert s == {"frames": 0, "duration_s": 0.0, "distance_m": 0.0, "guarded": False, "collisions": 0, "lane_departures": 0,
                 "time_outside_lane_s": 0.0, "emergency_entries": 0, "mode_switches": 0,
                 "time_in_mode_s": {"NORMAL": 0.0, "CAUTION": 0.0, "EMERGENCY": 0.0}, "stops": []}
    got = results(Expectations(min_mean_speed_mps=0.1, max_mean_speed_mps=1.0, min_gap_m=0.1), Metrics())
    unknown = (False, "not measured (m/s mean speed)")
    assert got == {"min_mean_speed_mps": unknown, "max_mean_speed_mps": unknown, "min_gap_m": (True, "no object ahead at any time")}
