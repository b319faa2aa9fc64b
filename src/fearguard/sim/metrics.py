"""Run metrics (one row per frame → a typed summary) and the scenario's expectations checked against them.

Each frame's row holds the truth and, for a guarded run, the supervisor's mode, strategy, speed limit
and fear (None for an unguarded run). A frame stands for the time until the next frame (the last one
for the median frame interval). Events are counted on rising edges: a collision that lasts 30 frames
is one collision; leaving the lane twice is two departures. Infinite values (no object ahead, not
closing) become None in the summary, so it serialises as plain JSON (``RunMetrics.to_json``).

Expectations are a table: one checker per expectation name, run in ``EXPECTATION_NAMES`` order for the
expectations a scenario sets; threshold expectations are rows of (metric, at least / at most, unit).
Outcome expectations (collisions, departures, speeds, gaps) apply to every controller; the
supervisor-only ones (``SUPERVISOR_ONLY``: modes, strategies, emergency counts) are not applicable
(``ok`` None) to a baseline, which has no modes: they neither fail it nor pass it vacuously.
"""

from __future__ import annotations

import math
from collections.abc import Callable, Mapping, Sequence
from dataclasses import asdict, dataclass
from itertools import pairwise
from typing import Any

import numpy as np

from fearguard.policy import MODE_ORDER
from fearguard.readings import finite_reading
from fearguard.sim.scenario_values import EXPECTATION_NAMES, Expectations
from fearguard.sim.world import Truth

MODES = MODE_ORDER  # least to most cautious, as policy.Mode declares them
STOPPED_SPEED_MPS = 0.02  # [m/s] at or below this the car counts as stopped
SPEED_TOLERANCE_MPS = 1e-6  # [m/s] a speed cap is met up to floating-point rounding
TIME_TOLERANCE_S = 1e-9  # [s] "by t" / "not before t" compare times up to rounding
NOT_APPLICABLE = "n/a: judges the supervisor's mode, and this controller has none (a baseline)"
SUPERVISOR_ONLY = frozenset({"no_emergency", "max_emergency_entries", "max_mode_switches", "mode_by", "strategy_by", "mode_not_before"})


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
class Stop:
    """The car came to a stop (rising edge of speed ≤ STOPPED_SPEED_MPS); gap None: nothing ahead."""

    t_s: float
    s_m: float
    gap_m: float | None


@dataclass(frozen=True)
class RunMetrics:
    """The numbers of one run (see docs/scenarios.md, "Metrics"); the fields after ``stops`` are None for no frames."""

    frames: int
    duration_s: float
    distance_m: float
    guarded: bool
    collisions: int
    lane_departures: int
    time_outside_lane_s: float
    emergency_entries: int
    mode_switches: int
    time_in_mode_s: Mapping[str, float]
    stops: tuple[Stop, ...]
    mean_speed_mps: float | None = None
    max_speed_mps: float | None = None
    final_speed_mps: float | None = None
    final_s_m: float | None = None
    final_gap_m: float | None = None
    finished: bool | None = None
    first_collision_t_s: float | None = None
    max_abs_lateral_m: float | None = None
    min_gap_m: float | None = None
    min_ttc_s: float | None = None
    peak_lat_accel_mps2: float | None = None
    time_in_strategy_s: Mapping[str, float] | None = None
    first_mode_t_s: Mapping[str, float | None] | None = None
    first_strategy_t_s: Mapping[str, float] | None = None
    min_speed_limit_mps: float | None = None
    mean_fear: float | None = None
    max_fear: float | None = None

    def to_json(self) -> dict[str, Any]:
        """The summary.json keys (a run without frames has only the counts)."""
        stops = [asdict(s) for s in self.stops]
        if self.frames == 0:
            return {"frames": 0, "duration_s": self.duration_s, "distance_m": self.distance_m, "guarded": self.guarded,
                    "collisions": self.collisions, "lane_departures": self.lane_departures,
                    "time_outside_lane_s": self.time_outside_lane_s, "emergency_entries": self.emergency_entries,
                    "mode_switches": self.mode_switches, "time_in_mode_s": dict(self.time_in_mode_s), "stops": stops}
        return {
            "frames": self.frames, "duration_s": self.duration_s, "distance_m": self.distance_m, "mean_speed_mps": self.mean_speed_mps,
            "max_speed_mps": self.max_speed_mps, "final_speed_mps": self.final_speed_mps, "final_s_m": self.final_s_m,
            "final_gap_m": self.final_gap_m, "finished": self.finished, "guarded": self.guarded, "collisions": self.collisions,
            "first_collision_t_s": self.first_collision_t_s, "lane_departures": self.lane_departures,
            "time_outside_lane_s": self.time_outside_lane_s, "max_abs_lateral_m": self.max_abs_lateral_m,
            "min_gap_m": self.min_gap_m, "min_ttc_s": self.min_ttc_s, "peak_lat_accel_mps2": self.peak_lat_accel_mps2,
            "time_in_mode_s": dict(self.time_in_mode_s), "time_in_strategy_s": dict(self.time_in_strategy_s or {}),
            "first_mode_t_s": dict(self.first_mode_t_s or {}), "first_strategy_t_s": dict(self.first_strategy_t_s or {}),
            "emergency_entries": self.emergency_entries, "mode_switches": self.mode_switches, "stops": stops,
            "min_speed_limit_mps": self.min_speed_limit_mps, "mean_fear": self.mean_fear, "max_fear": self.max_fear,
        }


@dataclass(frozen=True)
class ExpectationResult:
    """One expectation checked: ``ok`` None = not applicable (a supervisor-only check on a baseline run)."""

    name: str
    ok: bool | None
    detail: str

    @property
    def failed(self) -> bool:
        return self.ok is False

    @property
    def outcome(self) -> bool:
        """An outcome of the drive (collision, departure, speed, gap...) rather than a judgement of the supervisor's mode."""
        return self.name.split(" ")[0] not in SUPERVISOR_ONLY


class Metrics:
    """Accumulates one Row per frame; ``result()`` turns them into RunMetrics."""

    def __init__(self) -> None:
        self.rows: list[Row] = []

    def add(self, truth: Truth, mode: object = None, strategy: object = None, speed_limit_mps: float | None = None,
            fear: float | None = None) -> None:
        """Record one frame (mode/strategy: names, enum members, or None for an unguarded run)."""
        self.rows.append(Row(truth.t_s, truth.x_m, truth.y_m, truth.s_m, truth.lateral_m, truth.speed_mps, truth.gap_m, truth.ttc_s,
                             truth.collided, truth.in_lane, truth.lat_accel_mps2, truth.finished, _name(mode), _name(strategy),
                             finite_reading(speed_limit_mps), finite_reading(fear)))

    def result(self) -> RunMetrics:
        """The typed numbers of the run so far."""
        return summarize(self.rows)

    def summary(self) -> dict[str, Any]:
        """JSON-ready numbers of the run (``result().to_json()``)."""
        return self.result().to_json()


def summarize(rows: Sequence[Row]) -> RunMetrics:
    """The metrics of a list of rows (a pure function of them)."""
    if not rows:
        return RunMetrics(0, 0.0, 0.0, False, 0, 0, 0.0, 0, 0, dict.fromkeys(MODES, 0.0), ())
    t = np.array([r.t_s for r in rows])
    dt = _frame_durations(t)
    speed = np.array([r.speed_mps for r in rows])
    x, y = np.array([r.x_m for r in rows]), np.array([r.y_m for r in rows])
    outside = ~np.array([r.in_lane for r in rows])
    modes = [r.mode for r in rows]
    duration = float(dt.sum())
    return RunMetrics(
        frames=len(rows), duration_s=duration, distance_m=float(np.hypot(np.diff(x), np.diff(y)).sum()),
        guarded=any(m is not None for m in modes), collisions=int(_rising(np.array([r.collided for r in rows])).sum()),
        lane_departures=int(_rising(outside).sum()), time_outside_lane_s=float(dt[outside].sum()),
        emergency_entries=int(_rising(np.array([m == "EMERGENCY" for m in modes])).sum()),
        mode_switches=sum(1 for a, b in pairwise(modes) if a is not None and b is not None and a != b),
        time_in_mode_s={m: float(dt[[k == m for k in modes]].sum()) for m in MODES},
        stops=tuple(Stop(rows[i].t_s, rows[i].s_m, _json(rows[i].gap_m)) for i in np.flatnonzero(_rising(speed <= STOPPED_SPEED_MPS))),
        mean_speed_mps=float((speed * dt).sum() / duration) if duration > 0 else float(speed.mean()),
        max_speed_mps=float(speed.max()), final_speed_mps=float(speed[-1]), final_s_m=rows[-1].s_m,
        final_gap_m=_json(rows[-1].gap_m), finished=rows[-1].finished,
        first_collision_t_s=next((r.t_s for r in rows if r.collided), None),
        max_abs_lateral_m=float(np.abs([r.lateral_m for r in rows]).max()),
        min_gap_m=_json(float(np.min([r.gap_m for r in rows]))), min_ttc_s=_json(float(np.min([r.ttc_s for r in rows]))),
        peak_lat_accel_mps2=float(np.abs([r.lat_accel_mps2 for r in rows]).max()),
        **_supervisor_metrics(rows, dt),
    )


def _supervisor_metrics(rows: Sequence[Row], dt: np.ndarray) -> dict[str, Any]:
    """Strategy times, first times per mode and strategy, the lowest limit, mean and peak fear."""
    strategies = [r.strategy for r in rows]
    used = sorted({k for k in strategies if k})
    fears = [r.fear for r in rows if r.fear is not None]
    return {
        "time_in_strategy_s": {s: float(dt[[k == s for k in strategies]].sum()) for s in used},
        "first_mode_t_s": {m: next((r.t_s for r in rows if r.mode == m), None) for m in MODES},
        "first_strategy_t_s": {s: next(r.t_s for r in rows if r.strategy == s) for s in used},
        "min_speed_limit_mps": min((r.speed_limit_mps for r in rows if r.speed_limit_mps is not None), default=None),
        "mean_fear": float(np.mean(fears)) if fears else None,
        "max_fear": float(np.max(fears)) if fears else None,
    }


# -- expectations --------------------------------------------------------------------------------
Check = Callable[[Any, RunMetrics, Sequence[Row]], list[ExpectationResult]]


def _threshold(name: str, metric: str, at_least: bool, what: str, none: str | None = None) -> Check:
    """An expectation "metric ≥ want" (or ≤); ``none``: the verdict text when the metric is absent and that is fine."""

    def check(want: float, run: RunMetrics, rows: Sequence[Row]) -> list[ExpectationResult]:
        got = getattr(run, metric)
        if got is None:
            return [ExpectationResult(name, none is not None, none or f"not measured ({what})")]
        ok = got >= want if at_least else got <= want
        return [ExpectationResult(name, bool(ok), f"{got:.3g} {what}, at {'least' if at_least else 'most'} {want:g} expected")]

    return check


def _supervised(name: str, check: Callable[[Any, RunMetrics], tuple[bool, str]]) -> Check:
    """A false-alarm limit on the supervisor's modes: not applicable to a car without a supervisor."""

    def run_check(want: Any, run: RunMetrics, rows: Sequence[Row]) -> list[ExpectationResult]:
        if not _guarded(rows):
            return [ExpectationResult(name, None, NOT_APPLICABLE)]
        ok, detail = check(want, run)
        return [ExpectationResult(name, bool(ok), detail)]

    return run_check


def _no_collision(want: bool, run: RunMetrics, rows: Sequence[Row]) -> list[ExpectationResult]:
    when = f" (first at {run.first_collision_t_s} s)" if run.collisions else ""
    return [ExpectationResult("no_collision", (run.collisions == 0) == want, f"{run.collisions} collision(s){when}")]


def _no_lane_departure(want: bool, run: RunMetrics, rows: Sequence[Row]) -> list[ExpectationResult]:
    n = run.lane_departures
    return [ExpectationResult("no_lane_departure", (n == 0) == want,
                              f"{n} lane departure(s), {run.time_outside_lane_s:.2f} s outside the lane")]


def _no_emergency(want: bool, run: RunMetrics) -> tuple[bool, str]:
    t_em = run.time_in_mode_s.get("EMERGENCY", 0.0)
    return (t_em == 0.0) == want, f"{run.emergency_entries} EMERGENCY entr(ies), {t_em:.2f} s in EMERGENCY"


def _stopped_before_obstacle(want: bool, run: RunMetrics, rows: Sequence[Row]) -> list[ExpectationResult]:
    stops = [s for s in run.stops if s.gap_m is not None]
    ok = bool(stops) and run.collisions == 0
    first = stops[0] if stops else None
    detail = f"stopped {first.gap_m:.2f} m before it at {first.t_s:.2f} s" if first else "never stopped with an object ahead in the lane"
    return [ExpectationResult("stopped_before_obstacle", ok == want,
                              detail + (f"; {run.collisions} collision(s)" if run.collisions else ""))]




def _at_least(field: str, seen: str | None, wanted: str) -> bool:
    """A mode counts from the wanted one up (EMERGENCY is at least as cautious as CAUTION); a strategy only as itself."""
    if field == "mode" and seen in MODE_ORDER and wanted in MODE_ORDER:
        return MODE_ORDER.index(seen) >= MODE_ORDER.index(wanted)
    return seen == wanted


def _reached_by(field: str) -> Check:
    """"Reach this mode (or a more cautious one) / this strategy by t_s": one result per entry."""

    def check(wants: Sequence[Any], run: RunMetrics, rows: Sequence[Row]) -> list[ExpectationResult]:
        out = []
        for want in wants:
            value = getattr(want, field)
            name = f"{field}_by {value} by {want.t_s:g} s"
            if not _guarded(rows):
                out.append(ExpectationResult(name, None, NOT_APPLICABLE))
                continue
            first_row = next((r for r in rows if _at_least(field, getattr(r, field), value)), None)
            first = first_row.t_s if first_row is not None else None
            seen = getattr(first_row, field) if first_row is not None else value
            detail = f"first {seen} at {first:.2f} s" if first is not None else f"never {value}"
            out.append(ExpectationResult(name, first is not None and first <= want.t_s + TIME_TOLERANCE_S, detail))
        return out

    return check


def _mode_not_before(wants: Sequence[Any], run: RunMetrics, rows: Sequence[Row]) -> list[ExpectationResult]:
    out = []
    for want in wants:
        name = f"mode_not_before {want.mode} before {want.t_s:g} s"
        if not _guarded(rows):
            out.append(ExpectationResult(name, None, NOT_APPLICABLE))
            continue
        early = next((r.t_s for r in rows if r.mode == want.mode and r.t_s < want.t_s - TIME_TOLERANCE_S), None)
        out.append(ExpectationResult(name, early is None, f"{want.mode} already at {early:.2f} s" if early is not None
                                     else f"no {want.mode} before {want.t_s:g} s"))
    return out


def _max_speed_between(caps: Sequence[Any], run: RunMetrics, rows: Sequence[Row]) -> list[ExpectationResult]:
    out = []
    for cap in caps:
        if cap.t_s is not None and cap.until_s is not None:
            lo, hi, key, unit = cap.t_s, cap.until_s, "t_s", "s"
        else:
            lo, hi, key, unit = cap.from_m, cap.to_m, "s_m", "m"
        name = f"max_speed_between {lo:g}-{hi:g} {unit}: {cap.max_speed_mps:g} m/s"
        inside = [r.speed_mps for r in rows if lo <= getattr(r, key) < hi]
        if not inside:
            out.append(ExpectationResult(name, True, f"no frame in {lo:g}-{hi:g} {unit} (the car never got there)"))
        else:
            top = max(inside)
            out.append(ExpectationResult(name, top <= cap.max_speed_mps + SPEED_TOLERANCE_MPS, f"fastest {top:.2f} m/s there"))
    return out


CHECKS: dict[str, Check] = {  # one checker per expectation; run in EXPECTATION_NAMES order
    "no_collision": _no_collision,
    "no_lane_departure": _no_lane_departure,
    "max_time_outside_lane_s": _threshold("max_time_outside_lane_s", "time_outside_lane_s", False, "s outside the lane"),
    "min_mean_speed_mps": _threshold("min_mean_speed_mps", "mean_speed_mps", True, "m/s mean speed"),
    "max_mean_speed_mps": _threshold("max_mean_speed_mps", "mean_speed_mps", False, "m/s mean speed"),
    "min_distance_m": _threshold("min_distance_m", "distance_m", True, "m driven"),
    "max_distance_m": _threshold("max_distance_m", "distance_m", False, "m driven"),
    "no_emergency": _supervised("no_emergency", _no_emergency),
    "max_emergency_entries": _supervised("max_emergency_entries", lambda want, run: (
        run.emergency_entries <= want, f"{run.emergency_entries} EMERGENCY entr(ies), at most {want} allowed")),
    "max_mode_switches": _supervised("max_mode_switches", lambda want, run: (
        run.mode_switches <= want, f"{run.mode_switches} mode switch(es), at most {want} allowed")),
    "stopped_before_obstacle": _stopped_before_obstacle,
    "min_gap_m": _threshold("min_gap_m", "min_gap_m", True, "m smallest gap", none="no object ahead at any time"),
    "min_ttc_s": _threshold("min_ttc_s", "min_ttc_s", True, "s smallest time to collision", none="never closing in"),
    "max_lat_accel_mps2": _threshold("max_lat_accel_mps2", "peak_lat_accel_mps2", False, "m/s² peak lateral acceleration"),
    "mode_by": _reached_by("mode"),
    "strategy_by": _reached_by("strategy"),
    "mode_not_before": _mode_not_before,
    "max_speed_between": _max_speed_between,
}
assert tuple(CHECKS) == EXPECTATION_NAMES, "one checker per expectation, in the order they are checked"


def check_expectations(expectations: Expectations, run: RunMetrics, rows: Sequence[Row]) -> list[ExpectationResult]:
    """Every expectation the scenario sets, checked against the run's metrics and rows."""
    return [result for name in expectations.names() for result in CHECKS[name](getattr(expectations, name), run, rows)]


def _guarded(rows: Sequence[Row]) -> bool:
    return any(r.mode is not None for r in rows)


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
