"""What a person reads after a Duckietown drive: a few lines from its summary, and the suite's table."""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from typing import Any


def _f(value: Any, fmt: str = ".2f", none: str = "–") -> str:
    return none if value is None else format(value, fmt)


def drive_lines(s: Mapping[str, Any]) -> list[str]:
    """The summary of one drive as lines of text."""
    modes = s.get("time_in_mode_s", {})
    lines = [
        f"{s.get('map')} ({s.get('controller')}, seed {s.get('seed')}): {s.get('duration_s', 0):.1f} s, "
        f"progress {s.get('progress_m', 0):.2f} m ("
        + (f"{s['laps']:.2f} laps of {s['route_m']:.2f} m" if s.get("laps") is not None else
           f"{100 * (s.get('route_completion') or 0):.0f} % of the {s.get('route_m', 0):.1f} m route")
        + f"), mean speed {_f(s.get('mean_speed_mps'))} m/s",
        f"lane offset RMS {_f(s.get('lane_offset_rms_m'), '.3f')} m, max {_f(s.get('lane_offset_max_m'), '.3f')} m, "
        f"wheel on a marking {100 * (s.get('marking_share') or 0):.0f} % of the time",
        f"departures {s.get('departures')}, centre-line crossings {s.get('centre_line_crossings')}, collisions {s.get('collisions')}, "
        f"invalid pose {'at ' + format(s['first_invalid_pose_t_s'], '.1f') + ' s' if s.get('invalid_pose') else 'no'}",
    ]
    if s.get("guarded"):
        lines.append("time in mode  " + "  ".join(f"{m} {v:.1f} s" for m, v in modes.items())
                     + f"; fear mean {_f(s.get('fear_mean'))}, max {_f(s.get('fear_max'))}")
        lines.append("strategies    " + "  ".join(f"{k} {v:.1f} s" for k, v in s.get("time_in_strategy_s", {}).items()))
    ob = s.get("obstacle")
    if ob:
        lines.append(f"obstacle: contact {ob['contact']}, stopped before contact {ob['stopped_before_contact']} "
                     f"(gap {_f(ob.get('stop_gap_m'), '.3f')} m at {_f(ob.get('stop_t_s'), '.1f')} s), "
                     f"min gap {_f(ob.get('min_gap_m'), '.3f')} m, removed at {_f(ob.get('removed_t_s'), '.1f')} s, "
                     f"went on {ob['went_on']} ({_f(ob.get('progress_after_removal_m'))} m)")
    timing = s.get("timing", {})
    if timing.get("controller_ms_median") is not None:
        lines.append(f"cost per step: controller {timing['controller_ms_median']:.1f} ms (median; p95 {timing['controller_ms_p95']:.1f}), "
                     f"simulator {timing['simulator_ms_median']:.1f} ms: "
                     f"{100 * timing['controller_share_of_simulator_step']:.0f} % of a simulator step")
    return lines


def print_drive(summary: Mapping[str, Any]) -> None:
    print("\n".join(drive_lines(summary)))


SUITE_COLUMNS = ("run", "controller", "progress m", "% of expert", "departures", "centre crossings", "collisions", "invalid pose",
                 "EMERGENCY s", "offset RMS m", "on marking %", "obstacle")


def _obstacle_cell(ob: Mapping[str, Any] | None) -> str:
    """What happened at the obstacle: stopped how far short and why (the command's cause), contact, went on."""
    if not ob:
        return "–"
    if ob["stopped_before_contact"]:
        what = f"stopped {_f(ob.get('stop_gap_m'))} m short ({ob.get('stop_cause') or 'no supervisor'})"
    else:
        what = "contact" if ob["contact"] else "did not stop"
    if ob["went_on"]:
        return what + ", went on"
    return what + (", did not go on" if ob.get("removed_t_s") is not None else "")


def suite_markdown(rows: Sequence[Mapping[str, Any]]) -> str:
    """The suite's table: one row per drive (guarded / unguarded / expert per map, then obstacles and seeds)."""
    out = ["| " + " | ".join(SUITE_COLUMNS) + " |", "|" + "---|" * len(SUITE_COLUMNS)]
    for r in rows:
        obstacle = _obstacle_cell(r.get("obstacle"))
        cells = [r["run"], r["controller"], _f(r["progress_m"]), _f(r.get("progress_vs_expert_pct"), ".0f"), str(r["departures"]),
                 str(r["centre_line_crossings"]), str(r["collisions"]), "yes" if r["invalid_pose"] else "no",
                 _f(r.get("emergency_s"), ".1f") if r["controller"] == "guarded" else "–", _f(r.get("lane_offset_rms_m"), ".3f"),
                 _f(100 * r["marking_share"], ".0f"), obstacle]
        out.append("| " + " | ".join(cells) + " |")
    return "\n".join(out) + "\n"
