"""Metrics of a MetaDrive drive from the simulator's truth (one Sample per step → a JSON-ready summary).

- progress: the route driven (MetaDrive's ``travelled_length``), and route completion (its share of the route);
- lane offset from the lane centre (RMS, max; + = left), share of time with a wheel over a solid line;
- out of road (MetaDrive: off every lane of the road, or on the sidewalk: the episode ends) and crashes by kind
  (vehicle, object, other), counted on rising edges; centre-line crossings (the car's centre beyond the yellow line,
  in the oncoming lanes: MetaDrive counts those as road, so "out of road" alone misses a car on the wrong side);
- the vehicle or object ahead in the ego's path: smallest bumper-to-bumper gap and smallest time to collision;
Every step lasts the simulator's step (0.1 s). What the supervisor did (modes, EMERGENCY episodes, fear) comes from
the run's Recorder (``recorder.CommandStats``), its one owner: ``supervisor_times`` turns its shares into seconds.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np

from fearguard.outputs.recorder import CommandStats
from fearguard.worlds.duckietown.metrics import rising_edges

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
    over_centre_line: bool = False  # the car's centre beyond the yellow line: in the oncoming lanes


def _finite_min(values: Sequence[float]) -> float | None:
    finite = [v for v in values if math.isfinite(v)]
    return min(finite) if finite else None


def summarize_drive(samples: Sequence[Sample], dt_s: float, route_m: float | None = None) -> dict[str, Any]:
    """JSON-ready numbers of a drive from the truth (NaN / inf become None)."""
    if not samples:
        return {"steps": 0, "duration_s": 0.0, "progress_m": 0.0, "route_completion": 0.0, "out_of_road": 0, "crashes": 0}
    progress = float(samples[-1].progress_m)
    speeds = np.fromiter((s.speed_mps for s in samples), float, len(samples))
    offset = np.abs(np.fromiter((s.lane_offset_m for s in samples), float, len(samples)))
    crashes = {kind: rising_edges([getattr(s, f"crashed_{kind}") for s in samples]) for kind in ("vehicle", "object", "other")}
    seen = bool(np.isfinite(offset).any())
    return {
        "steps": len(samples), "duration_s": len(samples) * dt_s, "progress_m": progress, "route_m": route_m,
        "route_completion": min(1.0, max(0.0, progress / route_m)) if route_m else None,
        "distance_m": float(speeds.sum() * dt_s), "mean_speed_mps": float(speeds.mean()),
        "lane_offset_rms_m": float(np.sqrt(np.nanmean(offset**2))) if seen else None,
        "lane_offset_max_m": float(np.nanmax(offset)) if seen else None,
        "solid_line_share": float(np.mean([s.on_solid_line for s in samples])),
        "out_of_road": rising_edges([s.out_of_road for s in samples]), "crashes": sum(crashes.values()), "crashes_by_kind": crashes,
        "centre_line_crossings": rising_edges([s.over_centre_line for s in samples]),
        "over_centre_line_s": float(np.count_nonzero([s.over_centre_line for s in samples]) * dt_s),
        "min_gap_m": _finite_min([s.gap_m for s in samples]), "min_ttc_s": _finite_min([s.ttc_s for s in samples]),
        "time_stopped_s": float(np.count_nonzero(speeds <= STOPPED_SPEED_MPS) * dt_s),
    }


def supervisor_times(stats: CommandStats, duration_s: float) -> dict[str, Any]:
    """Seconds per mode and the EMERGENCY entries from the recorder's statistics (empty without a supervisor)."""
    if not stats.supervised_frames:
        return {"guarded": False, "time_in_mode_s": {}, "emergency_entries": None}
    return {"guarded": True, "time_in_mode_s": {mode: share * duration_s for mode, share in stats.mode_share.items()},
            "emergency_entries": len(stats.emergency_episodes)}


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
