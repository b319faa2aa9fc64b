"""What a person reads after a MetaDrive drive: a few lines from its summary, and the suite's table."""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from typing import Any


def _f(value: Any, fmt: str = ".2f", none: str = "–") -> str:
    return none if value is None else format(value, fmt)


def drive_lines(s: Mapping[str, Any]) -> list[str]:
    """The summary of one drive as lines of text, one topic each."""
    crashes = s.get("crashes_by_kind", {})
    route = f"{100 * (s.get('route_completion') or 0):.0f} % of the {_f(s.get('route_m'), '.0f')} m route"
    topics = {
        "drive": f"MetaDrive {s.get('map')}, seed {s.get('seed')}, {s.get('lighting')}, {s.get('controller')}: "
                 f"{s.get('duration_s', 0):.1f} s, {s.get('progress_m', 0):.1f} m ({route}), mean {_f(s.get('mean_speed_mps'), '.1f')} m/s"
                 + (f"; MetaDrive ended it: {s['end_reason']}" if s.get("end_reason") else ""),
        "lane": f"offset RMS {_f(s.get('lane_offset_rms_m'))} m, max {_f(s.get('lane_offset_max_m'))} m; "
                f"on a solid line {100 * (s.get('solid_line_share') or 0):.0f} % of the time; out of road {s.get('out_of_road')}; "
                f"over the centre line {s.get('centre_line_crossings')} times, {_f(s.get('over_centre_line_s'), '.1f')} s",
        "crashes": f"{s.get('crashes')} (" + ", ".join(f"{kind} {n}" for kind, n in crashes.items()) + ")",
        "ahead": f"min gap {_f(s.get('min_gap_m'), '.1f')} m, min TTC {_f(s.get('min_ttc_s'), '.1f')} s",
    }
    if s.get("guarded"):
        topics["modes"] = ", ".join(f"{mode} {sec:.1f} s" for mode, sec in s.get("time_in_mode_s", {}).items()) + (
            f"; {s.get('emergency_entries')} EMERGENCY entries; fear mean {_f(s.get('fear_mean'))}, max {_f(s.get('fear_max'))}")
    car = s.get("stopped_car")
    if car:
        gap = _f(car.get("stop_gap_m"), ".1f")
        topics["stopped car"] = (f"contact {car['contact']}, stopped behind {car['stopped_behind']} (gap {gap} m), "
                                 f"passed {car['passed']}, waited behind {car['waited_behind']}")
    timing = s.get("timing", {})
    if timing.get("controller_ms_median") is not None:
        topics["cost"] = (f"fearguard {timing['controller_ms_median']:.1f} ms a step (p95 {timing['controller_ms_p95']:.1f}), "
                          f"MetaDrive {timing['simulator_ms_median']:.0f} ms: {100 * timing['controller_share_of_simulator_step']:.1f} %")
    return [f"{topic}: {text}" for topic, text in topics.items()]


def print_drive(summary: Mapping[str, Any]) -> None:
    print("\n".join(drive_lines(summary)))


SUITE_COLUMNS = ("run", "seed", "controller", "progress m", "% of expert", "route %", "out of road", "over centre line",
                 "crashes", "min gap m",
                 "min TTC s", "EMERGENCY s", "offset RMS m", "stopped car", "fearguard ms", "simulator ms")


def _stopped_car_cell(car: Mapping[str, Any] | None) -> str:
    """What happened at the stopped car: contact, or stopped how far short, then passed or waited."""
    if not car:
        return "–"
    if car.get("contact"):
        return "contact"
    what = f"stopped {_f(car.get('stop_gap_m'), '.1f')} m short" if car.get("stopped_behind") else "did not stop"
    return what + (", passed" if car.get("passed") else ", waited" if car.get("waited_behind") else "")


def suite_markdown(rows: Sequence[Mapping[str, Any]]) -> str:
    """The suite's table: one row per drive."""
    out = ["| " + " | ".join(SUITE_COLUMNS) + " |", "|" + "---|" * len(SUITE_COLUMNS)]
    for r in rows:
        cells = [r["run"], str(r["seed"]), r["controller"], _f(r["progress_m"], ".1f"), _f(r.get("progress_vs_expert_pct"), ".0f"),
                 _f(100 * r["route_completion"] if r.get("route_completion") is not None else None, ".0f"), str(r["out_of_road"]),
                 _f(r.get("centre_line_crossings"), "d"),
                 str(r["crashes"]), _f(r.get("min_gap_m"), ".1f"), _f(r.get("min_ttc_s"), ".1f"),
                 _f(r.get("emergency_s"), ".1f") if r["controller"] == "guarded" else "–", _f(r.get("lane_offset_rms_m")),
                 _stopped_car_cell(r.get("stopped_car")), _f(r.get("controller_ms"), ".1f"), _f(r.get("simulator_ms"), ".0f")]
        out.append("| " + " | ".join(cells) + " |")
    return "\n".join(out) + "\n"
