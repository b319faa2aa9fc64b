"""Run metrics (one row per frame → a JSON-ready summary) and the scenario's expectations checked against them.

Each frame's row holds the truth and, for a guarded run, the supervisor's mode, strategy, speed limit
and fear (None for an unguarded run). A frame stands for the time until the next frame (the last one
for the median frame interval). Events are counted on rising edges: a collision that lasts 30 frames
is one collision; leaving the lane twice is two departures. Infinite values (no object ahead, not
closing) become None in the summary, so it serialises as plain JSON.
"""

from __future__ import annotations

import math
from collections.abc import Mapping, Sequence
from dataclasses import asdict, dataclass
from itertools import pairwise
from typing import Any

import numpy as np

from fearguard.readings import finite_reading
from fearguard.sim.scenario_values import Expectations
from fearguard.sim.world import Truth

MODES = ("NORMAL", "CAUTION", "EMERGENCY")
STOPPED_SPEED_MPS = 0.02  # [m/s] at or below this the car counts as stopped
SPEED_TOLERANCE_MPS = 1e-6  # [m/s] a speed cap is met up to floating-point rounding


@dataclass(frozen=True)
class Row:
    """One frame of a run: where the car was and what the supervisor decided."""

    t_s: float
    x_m: float
    y_m: float
    s_m: float
    lateral_m: float
    speed_mps: float
    gap_m: float
    ttc_s: float
    collided: bool
    in_lane: bool
    lat_accel_mps2: float
    finished: bool
    mode: str | None
    strategy: str | None
    speed_limit_mps: float | None
    fear: float | None


@dataclass(frozen=True)
class ExpectationResult:
    name: str
    ok: bool
    detail: str


class Metrics:
    """Accumulates one Row per frame; ``summary()`` turns them into numbers."""

    def __init__(self) -> None:
        self.rows: list[Row] = []

    def add(self, truth: Truth, mode: object = None, strategy: object = None, speed_limit_mps: float | None = None,
            fear: float | None = None) -> None:
        """Record one frame (mode/strategy: names, enum members, or None for an unguarded run)."""
        self.rows.append(Row(truth.t_s, truth.x_m, truth.y_m, truth.s_m, truth.lateral_m, truth.speed_mps, truth.gap_m, truth.ttc_s,
                             truth.collided, truth.in_lane, truth.lat_accel_mps2, truth.finished, _name(mode), _name(strategy),
                             finite_reading(speed_limit_mps), finite_reading(fear)))

    @property
    def timeline(self) -> list[dict[str, Any]]:
        """The rows as dicts (what ``check_expectations`` reads: t_s, mode, strategy, speed_mps, s_m, ...)."""
        return [asdict(r) for r in self.rows]

    def summary(self) -> dict[str, Any]:
        """JSON-ready numbers of the run (see docs/scenarios.md, "Metrics")."""
        return summarize(self.rows)


def summarize(rows: Sequence[Row]) -> dict[str, Any]:
    """The summary of a list of rows (a pure function of them)."""
    if not rows:
        return {"frames": 0, "duration_s": 0.0, "distance_m": 0.0, "guarded": False, "collisions": 0, "lane_departures": 0,
                "time_outside_lane_s": 0.0, "emergency_entries": 0, "mode_switches": 0,
                "time_in_mode_s": dict.fromkeys(MODES, 0.0), "stops": []}
    t = np.array([r.t_s for r in rows])
    dt = _frame_durations(t)
    speed = np.array([r.speed_mps for r in rows])
    x, y = np.array([r.x_m for r in rows]), np.array([r.y_m for r in rows])
    collided = np.array([r.collided for r in rows])
    outside = ~np.array([r.in_lane for r in rows])
    gaps = np.array([r.gap_m for r in rows])
    ttcs = np.array([r.ttc_s for r in rows])
    modes = [r.mode for r in rows]
    strategies = [r.strategy for r in rows]
    guarded = any(m is not None for m in modes)
    duration = float(dt.sum())
    stopped = speed <= STOPPED_SPEED_MPS
    stops = [{"t_s": rows[i].t_s, "s_m": rows[i].s_m, "gap_m": _json(rows[i].gap_m)} for i in np.flatnonzero(_rising(stopped))]
    fears = [r.fear for r in rows if r.fear is not None]
    first_collision = next((r.t_s for r in rows if r.collided), None)
    return {
        "frames": len(rows),
        "duration_s": duration,
        "distance_m": float(np.hypot(np.diff(x), np.diff(y)).sum()),
        "mean_speed_mps": float((speed * dt).sum() / duration) if duration > 0 else float(speed.mean()),
        "max_speed_mps": float(speed.max()),
        "final_speed_mps": float(speed[-1]),
        "final_s_m": rows[-1].s_m,
        "final_gap_m": _json(rows[-1].gap_m),
        "finished": rows[-1].finished,
        "guarded": guarded,
        "collisions": int(_rising(collided).sum()),
        "first_collision_t_s": first_collision,
        "lane_departures": int(_rising(outside).sum()),
        "time_outside_lane_s": float(dt[outside].sum()),
        "max_abs_lateral_m": float(np.abs([r.lateral_m for r in rows]).max()),
        "min_gap_m": _json(float(gaps.min())),
        "min_ttc_s": _json(float(ttcs.min())),
        "peak_lat_accel_mps2": float(np.abs([r.lat_accel_mps2 for r in rows]).max()),
        "time_in_mode_s": {m: float(dt[[k == m for k in modes]].sum()) for m in MODES},
        "time_in_strategy_s": {s: float(dt[[k == s for k in strategies]].sum()) for s in sorted({k for k in strategies if k})},
        "first_mode_t_s": {m: next((r.t_s for r in rows if r.mode == m), None) for m in MODES},
        "first_strategy_t_s": {s: next(r.t_s for r in rows if r.strategy == s) for s in sorted({k for k in strategies if k})},
        "emergency_entries": int(_rising(np.array([m == "EMERGENCY" for m in modes])).sum()),
        "mode_switches": sum(1 for a, b in pairwise(modes) if a is not None and b is not None and a != b),
        "stops": stops,
        "min_speed_limit_mps": min((r.speed_limit_mps for r in rows if r.speed_limit_mps is not None), default=None),
        "mean_fear": float(np.mean(fears)) if fears else None,
        "max_fear": float(np.max(fears)) if fears else None,
    }


def check_expectations(expectations: Expectations, summary: Mapping[str, Any], timeline: Sequence[Any]) -> list[ExpectationResult]:
    """Every expectation the scenario sets, checked against the run (timeline rows: dicts or objects with t_s, mode, ...)."""
    rows = [_row_view(r) for r in timeline]
    guarded = any(r["mode"] is not None for r in rows)
    e = expectations
    out: list[ExpectationResult] = []

    def add(name: str, ok: bool, detail: str) -> None:
        out.append(ExpectationResult(name, bool(ok), detail))

    def unguarded(name: str) -> bool:
        if not guarded:
            add(name, False, "no supervisor mode recorded (unguarded run): this expectation needs a guarded run")
        return not guarded

    def no_false_alarm_possible(name: str) -> bool:
        """False-alarm limits hold vacuously for a car without a supervisor: it has no modes to switch."""
        if not guarded:
            add(name, True, "no supervisor (unguarded run): no mode, so no false alarm")
        return not guarded

    collisions = int(summary.get("collisions", 0))
    if e.no_collision is not None:
        when = f" (first at {summary.get('first_collision_t_s')} s)" if collisions else ""
        add("no_collision", (collisions == 0) == e.no_collision, f"{collisions} collision(s){when}")
    if e.no_lane_departure is not None:
        n = int(summary.get("lane_departures", 0))
        add("no_lane_departure", (n == 0) == e.no_lane_departure,
            f"{n} lane departure(s), {summary.get('time_outside_lane_s', 0.0):.2f} s outside the lane")
    _at_most(add, "max_time_outside_lane_s", e.max_time_outside_lane_s, summary.get("time_outside_lane_s"), "s outside the lane")
    _at_least(add, "min_mean_speed_mps", e.min_mean_speed_mps, summary.get("mean_speed_mps"), "m/s mean speed")
    _at_most(add, "max_mean_speed_mps", e.max_mean_speed_mps, summary.get("mean_speed_mps"), "m/s mean speed")
    _at_least(add, "min_distance_m", e.min_distance_m, summary.get("distance_m"), "m driven")
    _at_most(add, "max_distance_m", e.max_distance_m, summary.get("distance_m"), "m driven")
    if e.no_emergency is not None and not no_false_alarm_possible("no_emergency"):
        t_em = summary.get("time_in_mode_s", {}).get("EMERGENCY", 0.0)
        add("no_emergency", (t_em == 0.0) == e.no_emergency,
            f"{summary.get('emergency_entries', 0)} EMERGENCY entr(ies), {t_em:.2f} s in EMERGENCY")
    if e.max_emergency_entries is not None and not no_false_alarm_possible("max_emergency_entries"):
        n = int(summary.get("emergency_entries", 0))
        add("max_emergency_entries", n <= e.max_emergency_entries, f"{n} EMERGENCY entr(ies), at most {e.max_emergency_entries} allowed")
    if e.max_mode_switches is not None and not no_false_alarm_possible("max_mode_switches"):
        n = int(summary.get("mode_switches", 0))
        add("max_mode_switches", n <= e.max_mode_switches, f"{n} mode switch(es), at most {e.max_mode_switches} allowed")
    if e.stopped_before_obstacle is not None:
        stops = [s for s in summary.get("stops", []) if s.get("gap_m") is not None]
        ok = bool(stops) and collisions == 0
        detail = (f"stopped {stops[0]['gap_m']:.2f} m before it at {stops[0]['t_s']:.2f} s" if stops else
                  "never stopped with an object ahead in the lane")
        add("stopped_before_obstacle", ok == e.stopped_before_obstacle, detail + (f"; {collisions} collision(s)" if collisions else ""))
    _at_least(add, "min_gap_m", e.min_gap_m, summary.get("min_gap_m"), "m smallest gap", none="no object ahead at any time")
    _at_least(add, "min_ttc_s", e.min_ttc_s, summary.get("min_ttc_s"), "s smallest time to collision", none="never closing in")
    _at_most(add, "max_lat_accel_mps2", e.max_lat_accel_mps2, summary.get("peak_lat_accel_mps2"), "m/s² peak lateral acceleration")
    by = [("mode", w.mode, w.t_s) for w in e.mode_by] + [("strategy", w.strategy, w.t_s) for w in e.strategy_by]
    for field, value, t_s in by:  # "reach this mode / strategy by t_s"
        name = f"{field}_by {value} by {t_s:g} s"
        if not unguarded(name):
            first = next((r["t_s"] for r in rows if r[field] == value), None)
            detail = f"first {value} at {first:.2f} s" if first is not None else f"never {value}"
            add(name, first is not None and first <= t_s + 1e-9, detail)
    for want in e.mode_not_before:
        name = f"mode_not_before {want.mode} before {want.t_s:g} s"
        if not unguarded(name):
            early = next((r["t_s"] for r in rows if r["mode"] == want.mode and r["t_s"] < want.t_s - 1e-9), None)
            add(name, early is None,
                f"{want.mode} already at {early:.2f} s" if early is not None else f"no {want.mode} before {want.t_s:g} s")
    for cap in e.max_speed_between:
        if cap.t_s is not None and cap.until_s is not None:
            lo, hi, key, unit = cap.t_s, cap.until_s, "t_s", "s"
        else:
            lo, hi, key, unit = cap.from_m, cap.to_m, "s_m", "m"
        name = f"max_speed_between {lo:g}-{hi:g} {unit}: {cap.max_speed_mps:g} m/s"
        inside = [r["speed_mps"] for r in rows if lo <= r[key] < hi]  # type: ignore[operator]
        if not inside:
            add(name, True, f"no frame in {lo:g}-{hi:g} {unit} (the car never got there)")
        else:
            top = max(inside)
            add(name, top <= cap.max_speed_mps + SPEED_TOLERANCE_MPS, f"fastest {top:.2f} m/s there")
    return out


def _at_least(add: Any, name: str, want: float | None, got: float | None, what: str, none: str | None = None) -> None:
    if want is None:
        return
    if got is None:
        add(name, none is not None, none or f"not measured ({what})")
    else:
        add(name, got >= want, f"{got:.3g} {what}, at least {want:g} expected")


def _at_most(add: Any, name: str, want: float | None, got: float | None, what: str) -> None:
    if want is None:
        return
    if got is None:
        add(name, False, f"not measured ({what})")
    else:
        add(name, got <= want, f"{got:.3g} {what}, at most {want:g} expected")


def _frame_durations(t: np.ndarray) -> np.ndarray:
    """Each frame lasts until the next one; the last for the median interval (0 for a single frame)."""
    if len(t) < 2:
        return np.zeros(len(t))
    d = np.diff(t)
    return np.append(d, float(np.median(d)))


def _rising(flags: np.ndarray) -> np.ndarray:
    """True where a flag turns on (the first frame counts when it starts on)."""
    return flags & ~np.concatenate([[False], flags[:-1]])


def _name(value: object) -> str | None:
    if value is None:
        return None
    return str(getattr(value, "name", value))


def _json(value: float) -> float | None:
    return value if math.isfinite(value) else None


def _row_view(row: Any) -> dict[str, Any]:
    """A timeline row as a dict with t_s, mode, strategy, speed_mps, s_m (dicts and objects alike)."""
    get = row.get if isinstance(row, Mapping) else (lambda k, d=None: getattr(row, k, d))
    def num(key: str) -> float:
        value = finite_reading(get(key))
        return math.nan if value is None else value

    return {"t_s": num("t_s"), "mode": _name(get("mode")), "strategy": _name(get("strategy")), "speed_mps": num("speed_mps"),
            "s_m": num("s_m")}
