"""Metrics of a MetaDrive drive from the simulator's truth (events, gaps, the stopped-car outcome)."""

from __future__ import annotations

import math

import pytest

from fearguard.outputs.recorder import Recorder
from fearguard.supervisor import FearGuard, Observation
from fearguard.worlds.metadrive.metrics import Sample, rising_edges, stopped_car_outcome, summarize_drive, supervisor_times

DT = 0.1


def _samples(n: int, **changes: object) -> list[Sample]:
    out = []
    for k in range(n):
        values = dict(t_s=(k + 1) * DT, speed_mps=10.0, lane_offset_m=0.0, on_solid_line=False, out_of_road=False,
                      crashed_vehicle=False, crashed_object=False, crashed_other=False, progress_m=(k + 1) * 1.0)
        values.update({key: (v(k) if callable(v) else v) for key, v in changes.items()})
        out.append(Sample(**values))  # type: ignore[arg-type]
    return out


def test_events_count_once_each() -> None:
    assert rising_edges([False, True, True, False, True]) == 2 and rising_edges([]) == 0


def test_summary_counts_crashes_by_kind_and_the_smallest_gap() -> None:
    s = summarize_drive(_samples(10, crashed_vehicle=lambda k: k >= 8, gap_m=lambda k: 30.0 - 3 * k,
                                 ttc_s=lambda k: math.inf if k < 2 else 5.0 - 0.5 * k, lane_offset_m=lambda k: 0.1 * (k % 2)), DT, 100.0)
    assert s["crashes"] == 1 and s["crashes_by_kind"] == {"vehicle": 1, "object": 0, "other": 0}
    assert s["min_gap_m"] == pytest.approx(3.0) and s["min_ttc_s"] == pytest.approx(0.5)
    assert s["progress_m"] == 10.0 and s["route_completion"] == pytest.approx(0.1)
    assert s["lane_offset_max_m"] == pytest.approx(0.1) and s["lane_offset_rms_m"] == pytest.approx(math.sqrt(0.005))



def test_the_wrong_side_counts_each_crossing_and_its_time() -> None:
    """Over the centre line is road to MetaDrive (not out of road): counted on its own, each crossing once."""
    s = summarize_drive(_samples(10, over_centre_line=lambda k: k in (2, 3, 7)), DT, 100.0)
    assert s["centre_line_crossings"] == 2 and s["over_centre_line_s"] == pytest.approx(0.3) and s["out_of_road"] == 0


def test_out_of_road_counts_each_departure_once() -> None:
    s = summarize_drive(_samples(6, out_of_road=lambda k: k in (2, 3, 5)), DT)
    assert s["out_of_road"] == 2 and s["route_completion"] is None


def test_time_in_mode_comes_from_the_recorders_statistics() -> None:
    recorder = Recorder(None, fps=10.0)
    guard = FearGuard(lambda frame: 0.0)
    for k in range(10):  # no frame, no cues: a fault every step, EMERGENCY after the entry frames
        recorder.frame(k, k * DT, guard.step(Observation(t_s=k * DT, speed_mps=0.0, frame=None)))
    times = supervisor_times(recorder.stats, 1.0)
    assert times["guarded"] and sum(times["time_in_mode_s"].values()) == pytest.approx(1.0)
    assert times["time_in_mode_s"]["EMERGENCY"] > 0 and times["emergency_entries"] == 1
    assert supervisor_times(Recorder(None, fps=10.0).stats, 1.0) == {"guarded": False, "time_in_mode_s": {}, "emergency_entries": None}


def test_stopped_car_waited_behind_or_passed() -> None:
    waited = _samples(40, speed_mps=lambda k: 0.0 if k > 20 else 5.0, progress_m=lambda k: min(k, 20) * 2.0, gap_m=lambda k: 8.0)
    out = stopped_car_outcome(waited, car_progress_m=50.0)
    assert out["stopped_behind"] and out["waited_behind"] and not out["passed"] and not out["contact"]
    passed = _samples(40, progress_m=lambda k: k * 3.0)
    assert stopped_car_outcome(passed, car_progress_m=50.0)["passed"]
    hit = _samples(10, crashed_vehicle=lambda k: k == 9)
    assert stopped_car_outcome(hit, car_progress_m=5.0)["contact"] and not stopped_car_outcome(hit, car_progress_m=5.0)["passed"]
