"""Stop lines: stand before a painted line across the lane, wait, then cross (issue 35).

A line seen ahead at d is a standing obstacle at d for the stopping envelope (the car brakes to stand before it);
after ``stop_line_wait_s`` at standstill the stop is served and lines are not stopped for again until the car has
driven ``stop_line_cross_m`` (the crossing: where the markings are missing, the road-picture machinery — the flicker
grace, the re-acquisition creep — takes over). ``stop_line_wait_s`` = 0: lines are not stopped for (the rule file's
choice; a road car's lines are not validated yet).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

from fearguard.policy.config import TIME_EPS_S, PolicyConfig
from fearguard.policy.speed import envelope_speed_mps, stopping_distance_m
from fearguard.vehicle import VehicleLimits

STOP_AHEAD_S = 1.0  # [s] a line nearer than the stopping distance plus this much travel is stopped for now (seen late: the
#   camera's search finds a stop line only a few car lengths ahead)


@dataclass(frozen=True)
class StopLine:
    """The stop-line memory: stopping for a line, standing since when, and how far the car has crossed since a served stop."""

    stopping: bool = False  # a line near enough was seen: stand, whether or not it is still in view
    stood_since_s: float | None = None  # standing still while stopping since (None: not standing yet)
    crossed_m: float | None = None  # [m] driven since the stop was served (None: no stop served)
    clear_m: float = 0.0  # [m] how far ahead the path was known clear when the stop was served

    def clear_left_m(self) -> float:
        """While crossing: how much of the path known clear at the stop is still ahead (0 when not crossing)."""
        return max(0.0, self.clear_m - self.crossed_m) if self.crossed_m is not None else 0.0


def next_stop_line(state: StopLine, line_m: float | None, speed_mps: float, t_s: float, dt_s: float, cfg: PolicyConfig,
                   vehicle: VehicleLimits, clear_m: float = 0.0) -> tuple[StopLine, float, str]:
    """Advance one frame: the new memory, the speed cap (inf: none) and its reason ("" when nothing to say).

    A line farther than the stopping distance plus ``STOP_AHEAD_S`` of travel caps the speed at the envelope for a
    standing obstacle there; nearer, the car stops now (cap 0) and stands ``stop_line_wait_s`` — the line need not stay
    in view, it passes under the camera — then crosses, remembering how far the path was known clear when it stood
    (``clear_m``): across an intersection the lane and its search may be gone."""
    if cfg.stop_line_wait_s <= 0.0:
        return state, math.inf, ""
    v = max(0.0, speed_mps) if math.isfinite(speed_mps) else vehicle.max_speed_mps
    if state.crossed_m is not None:
        crossed = state.crossed_m + v * max(0.0, dt_s)
        if crossed < cfg.stop_line_cross_m:
            return (StopLine(crossed_m=crossed, clear_m=state.clear_m), math.inf,
                    f"stop line served: crossing ({crossed:.2f} of {cfg.stop_line_cross_m:.2f} m)")
        state = StopLine()
    if not state.stopping:
        if line_m is None or not math.isfinite(line_m):
            return StopLine(), math.inf, ""
        if line_m - vehicle.stop_margin_m > stopping_distance_m(v, vehicle) + v * STOP_AHEAD_S:
            cap = envelope_speed_mps(max(0.0, line_m), vehicle)
            return StopLine(), cap, f"stop line {line_m:.2f} m ahead: approaching, at most {cap:.2f} m/s"
    since = (state.stood_since_s if state.stood_since_s is not None else t_s) if v <= cfg.standstill_mps else None
    if since is not None and t_s - since >= cfg.stop_line_wait_s - TIME_EPS_S:
        return StopLine(crossed_m=0.0, clear_m=clear_m), math.inf, f"stop line: stood {t_s - since:.1f} s, crossing"
    what = f"standing {t_s - since:.1f} of {cfg.stop_line_wait_s:.1f} s" if since is not None else "stopping"
    return StopLine(True, since), 0.0, f"stop line: {what}"
