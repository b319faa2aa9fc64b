"""Metrics of a MetaDrive drive from the simulator's truth (one Sample per step → a JSON-ready summary).

- progress: the route driven (MetaDrive's ``travelled_length``), and route completion (its share of the route);
- lane offset from the lane centre (RMS, max; + = left), share of time with a wheel over a solid line;
- out of road (MetaDrive: off every lane of the road, or on the sidewalk: the episode ends) and crashes by kind
  (vehicle, object, other), counted on rising edges;
- the vehicle or object ahead in the ego's path: smallest bumper-to-bumper gap and smallest time to collision;
- time per mode and strategy, fear, EMERGENCY entries (the supervisor's, None for the baselines).
Every step lasts the simulator's step (0.1 s).
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np

from fearguard.supervisor import Mode

MODES = tuple(m.name for m in Mode)
STOPPED_SPEED_MPS = 0.3  # [m/s] at or below this the car counts as standing (the road-car rules' standstill_mps)
PASSED_PROGRESS_M = 5.0  # [m] beyond the stopped car's position along the route: the ego passed it


@dataclass(frozen=True)
class Sample:
    """One simulator step: the truth after it, and what the supervisor decided (None: no supervisor)."""

    t_s: float
    speed_mps: float
    lane_offset_m: float
    on_solid_line: bool
    out_of_road: bool
    crashed_vehicle: bool
    crashed_object: bool
    crashed_other: bool
    progress_m: float
    gap_m: float = math.inf
    ttc_s: float = math.inf
    mode: str | None = None
    strategy: str | None = None
    fear: float | None = None


def rising_edges(flags: Sequence[bool]) -> int:
    """How many times a flag turns on (an event that lasts many steps counts once)."""
    count, before = 0, False
    for flag in flags:
        count += bool(flag and not before)
        before = bool(flag)
    return count


def _finite_min(values: Sequence[float]) -> float | None:
    finite = [v for v in values if math.isfinite(v)]
    return min(finite) if finite else None


def summarize_drive(samples: Sequence[Sample], dt_s: float, route_m: float | None = None) -> dict[str, Any]:
    """JSON-ready numbers of a drive (NaN / inf become None)."""
    if not samples:
        return {"steps": 0, "duration_s": 0.0, "progress_m": 0.0, "route_completion": 0.0, "out_of_road": 0, "crashes": 0}
    speed = np.array([s.speed_mps for s in samples])
    offsets = np.array([s.lane_offset_m for s in samples])
    finite = offsets[np.isfinite(offsets)]
    modes = [s.mode for s in samples]
    strategies = [s.strategy for s in samples]
    fears = [s.fear for s in samples if s.fear is not None]
    progress = float(samples[-1].progress_m)
    crashes = {kind: rising_edges([getattr(s, f"crashed_{kind}") for s in samples]) for kind in ("vehicle", "object", "other")}
    return {
        "steps": len(samples),
        "duration_s": len(samples) * dt_s,
        "progress_m": progress,
        "route_m": route_m,
        "route_completion": min(1.0, max(0.0, progress / route_m)) if route_m else None,
        "distance_m": float(speed.sum() * dt_s),
        "mean_speed_mps": float(speed.mean()),
        "lane_offset_rms_m": float(np.sqrt(np.mean(finite**2))) if finite.size else None,
        "lane_offset_max_m": float(np.abs(finite).max()) if finite.size else None,
        "solid_line_share": float(np.mean([s.on_solid_line for s in samples])),
        "out_of_road": rising_edges([s.out_of_road for s in samples]),
        "crashes": sum(crashes.values()),
        "crashes_by_kind": crashes,
        "min_gap_m": _finite_min([s.gap_m for s in samples]),
        "min_ttc_s": _finite_min([s.ttc_s for s in samples]),
        "time_stopped_s": float(np.sum(speed <= STOPPED_SPEED_MPS) * dt_s),
        "guarded": any(m is not None for m in modes),
        "time_in_mode_s": {m: sum(dt_s for k in modes if k == m) for m in MODES},
        "time_in_strategy_s": {s: sum(dt_s for k in strategies if k == s) for s in sorted({k for k in strategies if k})},
        "emergency_entries": rising_edges([m == "EMERGENCY" for m in modes]),
        "fear_mean": float(np.mean(fears)) if fears else None,
        "fear_max": float(np.max(fears)) if fears else None,
    }


def stopped_car_outcome(samples: Sequence[Sample], car_progress_m: float) -> dict[str, Any]:
    """With a stopped car in the lane ``car_progress_m`` along the route: contact, stopped behind it, passed it."""
    touched = any(s.crashed_vehicle for s in samples)
    stopped = next((s for s in samples if s.speed_mps <= STOPPED_SPEED_MPS and s.t_s > 1.0 and math.isfinite(s.gap_m)), None)
    passed = samples[-1].progress_m > car_progress_m + PASSED_PROGRESS_M if samples else False
    return {
        "contact": touched,
        "stopped_behind": stopped is not None and not touched,
        "stop_gap_m": stopped.gap_m if stopped is not None else None,
        "stop_t_s": stopped.t_s if stopped is not None else None,
        "passed": passed and not touched,
        "waited_behind": (not passed) and (not touched) and stopped is not None,
    }
