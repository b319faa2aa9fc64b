"""Ground-truth metrics of a Duckietown drive (lane geometry, events, obstacle outcome)."""

from __future__ import annotations

import math

import pytest

from fearguard.worlds.duckietown import preset as p
from fearguard.worlds.duckietown.metrics import Sample, crossed_centre, departed, on_marking, rising_edges, summarize_drive

DT = 1 / 30


def test_lane_geometry_thresholds() -> None:
    w = p.WHEEL_OUTER_HALF_TRACK_M
    assert not on_marking(0.0) and not departed(0.0) and not crossed_centre(0.0)
    assert on_marking(p.WHITE_INNER_M - w + 1e-3) and not departed(p.WHITE_INNER_M - w + 1e-3)
    assert departed(p.WHITE_OUTER_M - w + 1e-3) and not departed(p.WHITE_OUTER_M - w - 1e-3)
    assert on_marking(p.YELLOW_INNER_M + w - 1e-3) and not crossed_centre(p.YELLOW_INNER_M + w - 1e-3)
    assert crossed_centre(p.YELLOW_OUTER_M + w - 1e-3)
    assert departed(math.nan) and on_marking(math.nan) and not crossed_centre(math.nan)  # not in a lane at all


def test_events_count_once_each() -> None:
    assert rising_edges([False, True, True, False, True]) == 2
    assert rising_edges([True]) == 1 and rising_edges([]) == 0


def _drive(offsets: list[float], **kw: object) -> list[Sample]:
    return [Sample(t_s=(k + 1) * DT, speed_mps=0.2, lane_offset_m=d, progress_m=0.2 * (k + 1) * DT, invalid_pose=False,
                   collided=False, **kw) for k, d in enumerate(offsets)]  # type: ignore[arg-type]


def test_summary_of_a_drive_that_leaves_the_road_twice() -> None:
    s = summarize_drive(_drive([0.0, 0.03, 0.15, 0.15, 0.0, 0.2, -0.09]), DT)
    assert s["departures"] == 2 and s["centre_line_crossings"] == 1
    assert s["lane_offset_max_m"] == pytest.approx(0.2)
    assert s["lane_offset_rms_m"] == pytest.approx(math.sqrt((0.03**2 + 2 * 0.15**2 + 0.2**2 + 0.09**2) / 7))
    assert s["marking_share"] == pytest.approx(4 / 7)
    assert s["progress_m"] == pytest.approx(0.2 * 7 * DT)
    assert not s["guarded"] and s["time_in_mode_s"]["EMERGENCY"] == 0


def test_obstacle_outcome_stopped_short_then_went_on() -> None:
    samples: list[Sample] = []
    progress = 0.0
    for k in range(150):
        t = (k + 1) * DT
        present = k < 90
        speed = 0.2 if k < 30 or k >= 100 else 0.0
        progress += speed * DT
        samples.append(Sample(t, speed, 0.0, progress, False, False, 0.5 - progress if present else math.inf, present,
                              "EMERGENCY" if 30 <= k < 100 else "NORMAL", "STOP" if 30 <= k < 100 else "PASS_THROUGH", 0.5))
    ob = summarize_drive(samples, DT)["obstacle"]
    assert ob["stopped_before_contact"] and not ob["contact"] and ob["went_on"]
    assert ob["stop_gap_m"] == pytest.approx(0.5 - 0.2 * 30 * DT)
    assert ob["removed_t_s"] == pytest.approx(91 * DT)


def test_obstacle_outcome_contact() -> None:
    samples = [Sample((k + 1) * DT, 0.2, 0.0, 0.0, k >= 5, k >= 5, max(0.0, 0.1 - 0.02 * k), True) for k in range(8)]
    s = summarize_drive(samples, DT)
    assert s["collisions"] == 1 and s["invalid_pose"]
    assert s["obstacle"]["contact"] and not s["obstacle"]["stopped_before_contact"] and not s["obstacle"]["went_on"]


def test_route_completion_laps_or_share() -> None:
    from fearguard.worlds.duckietown.metrics import route_completion

    assert route_completion(24.0, 12.0, True)["laps"] == pytest.approx(2.0)
    open_route = route_completion(30.0, 21.0, False)
    assert open_route["route_completion"] == 1.0 and open_route["laps"] is None
    assert route_completion(1.0, 0.0, False)["route_completion"] is None
