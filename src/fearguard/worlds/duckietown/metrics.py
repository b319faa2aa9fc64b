"""Metrics of a Duckietown drive from the simulator's ground truth (one Sample per step → a JSON-ready summary).

Lane geometry from the robot's lane offset d (m, + = right of the simulator's lane centre) and the
outer faces of its wheels at d ± WHEEL_OUTER_HALF_TRACK_M:
- on a marking: a wheel over the white tape's inner edge or the yellow line's near edge;
- departure: a wheel beyond the white tape's outer edge (off the road), counted on rising edges;
- centre-line crossing: a wheel beyond the yellow line's far edge (into the oncoming lane);
- the simulator's "invalid pose" (off the drivable tiles, or contact) and contact with an object.
Progress is the distance driven along the lane direction (the route completed); every step lasts
the simulator's dt. Time per mode and strategy, fear, stops, and for an obstacle scenario the
smallest gap, whether the robot stopped before contact and whether it went on once it was removed.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass
from itertools import pairwise
from typing import Any

import numpy as np

from fearguard.policy import MODE_ORDER
from fearguard.worlds.duckietown.preset import (
    WHEEL_OUTER_HALF_TRACK_M,
    WHITE_INNER_M,
    WHITE_OUTER_M,
    YELLOW_INNER_M,
    YELLOW_OUTER_M,
)

MODES = MODE_ORDER  # least to most cautious, as policy.Mode declares them
STOPPED_SPEED_MPS = 0.02  # [m/s] at or below this the robot counts as standing
RESUMED_PROGRESS_M = 0.2  # [m] driven after the obstacle was removed: the robot went on


@dataclass(frozen=True)
class Sample:
    """One simulator step: the truth after it, and what the supervisor had decided (None: no supervisor)."""

    t_s: float
    speed_mps: float
    lane_offset_m: float  # NaN: not in a lane
    progress_m: float
    invalid_pose: bool
    collided: bool
    obstacle_gap_m: float = math.inf  # inf: no obstacle in the world
    obstacle_present: bool = False
    mode: str | None = None
    strategy: str | None = None
    fear: float | None = None
    cause: str | None = None  # the command's dominant cause ("collision", "road", ...; "fault")


def on_marking(offset_m: float) -> bool:
    """A wheel is over a tape (or the robot is not in a lane at all)."""
    if not math.isfinite(offset_m):
        return True
    return offset_m + WHEEL_OUTER_HALF_TRACK_M > WHITE_INNER_M or offset_m - WHEEL_OUTER_HALF_TRACK_M < YELLOW_INNER_M


def departed(offset_m: float) -> bool:
    """A wheel is beyond the outer edge of the white tape: off the road (or not in a lane at all)."""
    return not math.isfinite(offset_m) or offset_m + WHEEL_OUTER_HALF_TRACK_M > WHITE_OUTER_M


def crossed_centre(offset_m: float) -> bool:
    """A wheel is beyond the far edge of the yellow line: in the oncoming lane."""
    return math.isfinite(offset_m) and offset_m - WHEEL_OUTER_HALF_TRACK_M < YELLOW_OUTER_M


def rising_edges(flags: Sequence[bool]) -> int:
    """How many times a flag turns on (an event that lasts many steps counts once)."""
    count, before = 0, False
    for flag in flags:
        count += bool(flag and not before)
        before = bool(flag)
    return count


def route_completion(progress_m: float, route_m: float, closed: bool) -> dict[str, Any]:
    """Laps of a loop, or the share of an open route driven (capped at 1)."""
    if route_m <= 0:
        return {"route_m": route_m, "route_closed": closed, "laps": None, "route_completion": None}
    share = max(0.0, progress_m) / route_m
    return {"route_m": route_m, "route_closed": closed, "laps": share if closed else None,
            "route_completion": None if closed else min(1.0, share)}


def summarize_drive(samples: Sequence[Sample], dt_s: float) -> dict[str, Any]:
    """JSON-ready numbers of a drive (NaN/inf become None): motion, the lane, the supervisor's modes, the obstacle."""
    if not samples:
        return {"steps": 0, "duration_s": 0.0, "progress_m": 0.0, "distance_m": 0.0, "departures": 0, "collisions": 0}
    speed = np.array([s.speed_mps for s in samples])
    out: dict[str, Any] = {
        "steps": len(samples),
        "duration_s": len(samples) * dt_s,
        "progress_m": samples[-1].progress_m,
        "distance_m": float(speed.sum() * dt_s),
        "mean_speed_mps": float(speed.mean()),
        **_lane_summary(np.array([s.lane_offset_m for s in samples])),
        "invalid_pose": any(s.invalid_pose for s in samples),
        "first_invalid_pose_t_s": next((s.t_s for s in samples if s.invalid_pose), None),
        "collisions": rising_edges([s.collided for s in samples]),
        "time_stopped_s": float(np.sum(speed <= STOPPED_SPEED_MPS) * dt_s),
        **_mode_summary(samples, dt_s),
    }
    if any(s.obstacle_present for s in samples) or any(math.isfinite(s.obstacle_gap_m) for s in samples):
        out["obstacle"] = _obstacle_summary(samples, [s.obstacle_gap_m for s in samples if s.obstacle_present])
    return out


def _lane_summary(offsets: np.ndarray) -> dict[str, Any]:
    """Lane offset statistics, the share of time on a marking, departures and centre-line crossings."""
    finite = offsets[np.isfinite(offsets)]
    return {
        "lane_offset_rms_m": float(np.sqrt(np.mean(finite**2))) if finite.size else None,
        "lane_offset_max_m": float(np.abs(finite).max()) if finite.size else None,
        "lane_offset_mean_m": float(finite.mean()) if finite.size else None,
        "marking_share": float(np.mean([on_marking(d) for d in offsets])),
        "departures": rising_edges([departed(d) for d in offsets]),
        "centre_line_crossings": rising_edges([crossed_centre(d) for d in offsets]),
    }


def _mode_summary(samples: Sequence[Sample], dt_s: float) -> dict[str, Any]:
    """Time in each mode and strategy, EMERGENCY entries and fear (a drive without a supervisor has none)."""
    modes = [s.mode for s in samples]
    strategies = [s.strategy for s in samples]
    fears = [s.fear for s in samples if s.fear is not None]
    return {
        "guarded": any(m is not None for m in modes),
        "time_in_mode_s": {m: sum(dt_s for k in modes if k == m) for m in MODES},
        "time_in_strategy_s": {s: sum(dt_s for k in strategies if k == s) for s in sorted({k for k in strategies if k})},
        "emergency_entries": rising_edges([m == "EMERGENCY" for m in modes]),
        "fear_mean": float(np.mean(fears)) if fears else None,
        "fear_max": float(np.max(fears)) if fears else None,
    }


def _obstacle_summary(samples: Sequence[Sample], gaps: Sequence[float]) -> dict[str, Any]:
    """Did the robot stop before touching the obstacle, how close did it get, did it go on once it was gone?"""
    present = [s for s in samples if s.obstacle_present]
    touched = any(s.collided for s in present)
    stopped = next((s for s in present if s.speed_mps <= STOPPED_SPEED_MPS and s.t_s > 0.5), None)
    removed_at = next((b for a, b in pairwise(samples) if a.obstacle_present and not b.obstacle_present), None)
    after = samples[-1].progress_m - removed_at.progress_m if removed_at is not None else None
    finite = [g for g in gaps if math.isfinite(g)]
    return {
        "min_gap_m": min(finite) if finite else None,
        "contact": touched,
        "stopped_before_contact": stopped is not None and not touched,
        "stop_gap_m": stopped.obstacle_gap_m if stopped is not None and math.isfinite(stopped.obstacle_gap_m) else None,
        "stop_t_s": stopped.t_s if stopped is not None else None,
        "stop_cause": stopped.cause if stopped is not None else None,  # why it stood: "collision" (saw it), "road", ...
        "removed_t_s": removed_at.t_s if removed_at is not None else None,
        "progress_after_removal_m": after,
        "went_on": after is not None and after >= RESUMED_PROGRESS_M,
    }
