"""How fast: fear's speed, the stopping envelope (responsibility-sensitive safety), the lateral limit, rate limits, and
the timing of frames. Pure functions over plain values: the supervisor owns the state and the clock.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from itertools import pairwise

import numpy as np

from fearguard.policy.config import TIME_EPS_S, PolicyConfig
from fearguard.vehicle import VehicleLimits

ENVELOPE_SHRINK = 1e-9  # [-] keeps v·t_r + v²/2a ≤ d − margin true after floating-point rounding


def fear_speed_mps(fear: float, level_anchors: np.ndarray, cfg: PolicyConfig, vehicle: VehicleLimits) -> float:
    """Speed allowed by fear: the level fractions interpolated between the level anchors (increasing)."""
    return float(np.interp(fear, level_anchors, cfg.speed_fraction)) * vehicle.max_speed_mps


def stopping_distance_m(speed_mps: float, vehicle: VehicleLimits) -> float:
    """Distance to stop from speed: reaction distance plus braking distance v²/2a (inf for a speed whose square
    is beyond the float range)."""
    try:
        braking_m = speed_mps**2 / (2.0 * vehicle.max_decel_mps2)
    except OverflowError:  # e.g. a measured speed of 1e200 m/s: no stop is possible
        braking_m = math.inf
    return speed_mps * vehicle.reaction_time_s + braking_m


def lead_speed_mps(speed_mps: float | None, closing_speed_mps: float | None) -> float:
    """Speed of the object ahead (≥ 0) from the ego's speed and the closing speed; unknown either: 0 (standing, worst)."""
    if speed_mps is None or closing_speed_mps is None or not math.isfinite(closing_speed_mps):
        return 0.0
    return max(0.0, speed_mps - closing_speed_mps)


def envelope_speed_mps(range_m: float, vehicle: VehicleLimits, lead_speed: float = 0.0) -> float:
    """Largest v inside the responsibility-sensitive-safety distance; inf when nothing is in range.

    The ego reacts after t_r and brakes at a; the object ahead, now at ``lead_speed`` (m/s, ≥ 0), may brake at
    ``lead_max_decel_mps2`` (b): v·t_r + v²/(2a) ≤ max(0, d − margin + v_f²/(2b)). A standing obstacle (v_f = 0)
    is the special case v·t_r + v²/(2a) ≤ max(0, d − margin). Faster closing (a slower lead) never raises it.
    """
    if math.isinf(range_m):
        return math.inf
    v_f = max(0.0, lead_speed) if math.isfinite(lead_speed) else 0.0
    room = max(0.0, range_m - vehicle.stop_margin_m + v_f * v_f / (2.0 * vehicle.lead_max_decel_mps2))
    t_r, a = vehicle.reaction_time_s, vehicle.max_decel_mps2
    v = 2.0 * room / (t_r + math.sqrt(t_r * t_r + 2.0 * room / a)) if room > 0.0 else 0.0
    return v * (1.0 - ENVELOPE_SHRINK)


def imminent_collision(range_m: float, speed_mps: float, vehicle: VehicleLimits, closing_speed_mps: float | None = None) -> bool:
    """No braking within the limits avoids contact: the gap is gone before the ego sheds its closing speed.

    The same relative-motion model as the envelope, on what is happening now: the ego brakes at a after t_r
    until it moves at the lead's speed (the lead holding its speed); closing c = v − v_f, so the gap shrinks by
    c·t_r + c²/(2a). Unknown closing speed: a standing obstacle (c = v). Inside the margin: imminent.
    """
    if math.isinf(range_m):
        return False
    if range_m <= vehicle.stop_margin_m:
        return True
    closing = speed_mps - lead_speed_mps(speed_mps, closing_speed_mps) if closing_speed_mps is not None else speed_mps
    closing = max(0.0, closing)
    return stopping_distance_m(closing, vehicle) >= range_m - vehicle.stop_margin_m


def lateral_speed_mps(steering_deg: float, vehicle: VehicleLimits) -> float:
    """Largest speed at this steering angle within the lateral acceleration: v ≤ √(a_lat·L/|tan δ|) (bicycle model)."""
    tan_d = abs(math.tan(math.radians(steering_deg)))
    if tan_d < 1e-12:
        return math.inf
    return math.sqrt(vehicle.max_lateral_accel_mps2 * vehicle.wheelbase_m / tan_d)


def rate_limited_steering_deg(previous_deg: float | None, target_deg: float, dt_s: float, vehicle: VehicleLimits) -> float:
    """The smallest change toward the target that respects the steering-rate limit (the target when it is within)."""
    if previous_deg is None:
        return target_deg
    step = vehicle.max_steering_rate_dps * max(dt_s, 0.0)
    return min(max(target_deg, previous_deg - step), previous_deg + step)


def oscillating(recent_deg: Sequence[float], cfg: PolicyConfig) -> bool:
    """The last ``oscillation_flips`` frame-to-frame changes are all sign flips between angles beyond ``oscillation_deg``."""
    tail = list(recent_deg)[-(cfg.oscillation_flips + 1):]
    if len(tail) < cfg.oscillation_flips + 1:
        return False
    return all(a * b < 0 and min(abs(a), abs(b)) >= cfg.oscillation_deg for a, b in pairwise(tail))


CLOSING_WINDOW_S = 0.3  # [s] ranges this recent give the closing speed at cue level (6 frames at 20 Hz: ~0.15 s lag)


def closing_speed_from_ranges(
    ranges: Sequence[tuple[float, float]], t_s: float, lead_max_decel_mps2: float = 0.0, window_s: float = CLOSING_WINDOW_S,
) -> float | None:
    """Closing speed (m/s, + = closing) now, from the (time, range) pairs of the last ``window_s``.

    Minus the least-squares slope is the closing speed at the window's mean time; since then the object ahead
    may have braked at ``lead_max_decel_mps2``, so that much is added for the lag (the estimate errs toward
    closing). None with fewer than two readings in the window (unknown: the obstacle counts as standing).
    """
    recent = [(t, r) for t, r in ranges if t_s - t <= window_s + TIME_EPS_S]
    if len(recent) < 2:
        return None
    mt = sum(t for t, _ in recent) / len(recent)
    mr = sum(r for _, r in recent) / len(recent)
    var = sum((t - mt) ** 2 for t, _ in recent)
    if var <= 0.0:
        return None
    return -sum((t - mt) * (r - mr) for t, r in recent) / var + lead_max_decel_mps2 * (t_s - mt)


SAME_OBJECT_M = 1.0  # [m] after frames without a range, a reading this near the last one (or SAME_OBJECT_SHARE of it) is the
SAME_OBJECT_SHARE = 0.1  # [-] same object: its ranges go on. A car followed at its own speed on a curve, its box lost for
#   one frame (MetaDrive seed 29, traffic 0.1): its ranges cleared, the next read as a standing car 16 m ahead, EMERGENCY STOP


def same_object_after_gap(last: tuple[float, float], t_s: float, range_m: float, window_s: float = CLOSING_WINDOW_S) -> bool:
    """Whether a range reading after frames without one continues the ranges whose latest is ``last`` (time, range):
    within the closing window and within SAME_OBJECT_M or SAME_OBJECT_SHARE of the last range (else another object, or
    one whose speed is no longer known: it counts as standing)."""
    t_last, r_last = last
    return 0.0 <= t_s - t_last <= window_s + TIME_EPS_S and abs(range_m - r_last) <= max(SAME_OBJECT_M, SAME_OBJECT_SHARE * r_last)


def watchdog_s(period_s: float | None, cfg: PolicyConfig) -> float:
    """Longest gap between frames before the input counts as stalled: max(N typical periods, the configured age)."""
    return max(cfg.watchdog_age_s, cfg.watchdog_frames * period_s) if period_s is not None else cfg.watchdog_age_s


def rate_limited_mps(previous_mps: float, target_mps: float, dt_s: float, cfg: PolicyConfig) -> float:
    """The limit falls at once and rises no faster than the comfort acceleration."""
    return min(target_mps, previous_mps + cfg.comfort_accel_mps2 * max(dt_s, 0.0))


