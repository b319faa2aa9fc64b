"""Policy: fear → speed limit ∧ stopping envelope, the mode machine, and the emergency strategy.

Pure functions over plain values; the supervisor owns the state and the clock. Policy never looks
at pixels, only at fear, cues, the lead vehicle and the vehicle's limits.

Speed limit = min(fear limit, stopping envelope, emergency cap), then rate-limited upward by the
comfort acceleration. Each emergency cause that is active imposes its own cap and the smallest wins,
so a cue getting worse can only add caps: the limit never rises when a cue worsens.
"""

from __future__ import annotations

import math
from collections.abc import Mapping, Sequence
from dataclasses import dataclass, fields
from enum import Enum
from itertools import pairwise
from typing import Any

import numpy as np

from fearguard.fear import LEVEL_NAMES, Cause
from fearguard.observation import Lead  # defined with the other plain values; fearguard.policy.Lead keeps working
from fearguard.reader import Table, TomlSource
from fearguard.readings import finite_reading
from fearguard.vehicle import VehicleLimits

ENVELOPE_SHRINK = 1e-9  # [-] keeps v·t_r + v²/2a ≤ d − margin true after floating-point rounding
TIME_EPS_S = 1e-9  # [s] slack in time comparisons, so that 10 steps of 0.1 s count as 1.0 s


class Mode(Enum):
    """The supervisor's modes, declared from least to most cautious (expectations such as ``mode_by`` rely on the order)."""

    NORMAL = "NORMAL"
    CAUTION = "CAUTION"
    EMERGENCY = "EMERGENCY"


class Strategy(Enum):
    PASS_THROUGH = "PASS_THROUGH"
    FOLLOW_LEAD = "FOLLOW_LEAD"
    STOP = "STOP"
    CRAWL = "CRAWL"


@dataclass(frozen=True)
class PolicyConfig:
    """The policy numbers of a rule file's ``[policy]`` table (defaults: a 1:10 model car)."""

    speed_fraction: tuple[float, ...] = (1.0, 0.8, 0.6, 0.4, 0.3)  # of max speed, per fear level
    caution_fear: float = 0.375  # [-] fear at or above which the mode is CAUTION
    emergency_enter_fear: float = 0.7  # [-] fear that counts toward entering EMERGENCY
    emergency_exit_fear: float = 0.5  # [-] fear below which the hold timer runs
    enter_frames: int = 3  # [frames] consecutive frames over the enter threshold
    hold_s: float = 2.0  # [s] time below the exit threshold before EMERGENCY is left
    comfort_accel_mps2: float = 0.5  # [m/s²] fastest rise of the speed limit
    crawl_fraction: float = 0.15  # [-] of max speed, CRAWL cap (and FOLLOW_LEAD without a range)
    follow_time_gap_s: float = 1.5  # [s] FOLLOW_LEAD speed = lead range / time gap
    follow_gain: float = 1.0  # [deg/deg] steering per degree of lead bearing
    watchdog_frames: int = 10  # [frames] a frame later than this many typical periods after the last is a stall
    watchdog_age_s: float = 1.0  # [s] ... and later than this (openpilot: a message older than max(10 periods, …))
    recovery_dwell_s: float = 1.0  # [s] at standstill after a road-picture stop before a re-acquisition creep
    recovery_creep_m: float = 0.6  # [m] longest single creep
    recovery_creep_s: float = 4.0  # [s] longest single creep in time
    recovery_max_creeps: int = 4  # [-] creeps per EMERGENCY; then the car stays stopped and says why
    recovery_max_total_m: float = 2.0  # [m] total creep distance per EMERGENCY
    standstill_mps: float = 0.05  # [m/s] at or below this the car counts as standing still
    recovery_min_confidence: float = 0.25  # [-] lane_confidence from which the lane counts as partly seen (creep allowed)
    oscillation_deg: float = 10.0  # [deg] a steering sign flip between two frames, both beyond this, is large
    oscillation_flips: int = 3  # [-] this many large sign flips in a row: the estimator oscillates (a fault)
    lane_check_lookahead_s: float = 1.0  # [s] the lane check looks this far ahead (time to line crossing)
    lane_check_min_deg: float = 5.0  # [deg] the estimator must steer this much more toward the boundary than the lane
    lane_check_fraction: float = 0.6  # [-] of max speed while the lane check overrides the estimator

    @classmethod
    def from_table(cls, src: TomlSource, data: object, key_path: str = "policy") -> PolicyConfig:
        """Validate a ``[policy]`` table with the strict reader; errors name the file, the line and the key."""
        t = Table(src, data, key_path, [f.name for f in fields(cls)])
        values: dict[str, Any] = {}
        for key in t.data:
            if key == "speed_fraction":
                values[key] = _fractions(t, key)
            elif key in _WHOLE_KEYS:
                values[key] = t.integer(key, low=0 if key == "recovery_max_creeps" else 1)
            else:
                values[key] = t.number(key)
        cfg = cls(**values)
        for key, ok, problem in (
            ("emergency_enter_fear", 0.0 < cfg.emergency_enter_fear <= 1.0, "must be in (0, 1]"),
            ("emergency_exit_fear", 0.0 <= cfg.emergency_exit_fear < cfg.emergency_enter_fear,
             "must be >= 0 and below emergency_enter_fear (hysteresis)"),
            ("caution_fear", 0.0 < cfg.caution_fear <= cfg.emergency_enter_fear,
             "must be in (0, emergency_enter_fear]"),
            ("hold_s", cfg.hold_s >= 0.0, "must be >= 0"),
            ("comfort_accel_mps2", cfg.comfort_accel_mps2 > 0.0, "must be > 0"),
            ("crawl_fraction", 0.0 <= cfg.crawl_fraction <= 1.0, "must be in [0, 1]"),
            ("follow_time_gap_s", cfg.follow_time_gap_s > 0.0, "must be > 0"),
            ("follow_gain", cfg.follow_gain >= 0.0, "must be >= 0"),
            *((k, getattr(cfg, k) > 0.0, "must be > 0") for k in _POSITIVE_KEYS),
            ("recovery_dwell_s", cfg.recovery_dwell_s >= 0.0, "must be >= 0"),
            ("standstill_mps", cfg.standstill_mps >= 0.0, "must be >= 0"),
            ("lane_check_min_deg", cfg.lane_check_min_deg >= 0.0, "must be >= 0"),
            ("lane_check_fraction", 0.0 <= cfg.lane_check_fraction <= 1.0, "must be in [0, 1]"),
            ("recovery_min_confidence", 0.0 <= cfg.recovery_min_confidence <= 1.0, "must be in [0, 1]"),
        ):
            if not ok:
                raise t.fail(key, f"{problem}, got {getattr(cfg, key)}")
        return cfg


_WHOLE_KEYS = ("enter_frames", "watchdog_frames", "recovery_max_creeps", "oscillation_flips")
_POSITIVE_KEYS = ("watchdog_age_s", "recovery_creep_m", "recovery_creep_s", "recovery_max_total_m", "oscillation_deg",
                  "lane_check_lookahead_s")


def _fractions(t: Table, key: str) -> tuple[float, ...]:
    value = t.data[key]
    if not isinstance(value, Mapping):
        raise t.fail(key, "must be a table like { very_low = 1.0, low = 0.8, ... }")
    missing = [n for n in LEVEL_NAMES if n not in value]
    extra = [k for k in value if k not in LEVEL_NAMES]
    if missing or extra:
        raise t.fail(key, f"needs exactly the levels {', '.join(LEVEL_NAMES)}; missing {missing}, unknown {extra}")
    seq = [finite_reading(value[n]) for n in LEVEL_NAMES]
    if not all(v is not None and 0.0 <= v <= 1.0 for v in seq):
        raise t.fail(key, f"each fraction must be a number in [0, 1], got {[value[n] for n in LEVEL_NAMES]}")
    fractions = tuple(float(v) for v in seq if v is not None)
    if any(b > a for a, b in pairwise(fractions)):
        raise t.fail(key, f"fractions must not increase with fear (monotone policy), got {list(fractions)}")
    return fractions


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


def watchdog_s(period_s: float | None, cfg: PolicyConfig) -> float:
    """Longest gap between frames before the input counts as stalled: max(N typical periods, the configured age)."""
    return max(cfg.watchdog_age_s, cfg.watchdog_frames * period_s) if period_s is not None else cfg.watchdog_age_s


def rate_limited_mps(previous_mps: float, target_mps: float, dt_s: float, cfg: PolicyConfig) -> float:
    """The limit falls at once and rises no faster than the comfort acceleration."""
    return min(target_mps, previous_mps + cfg.comfort_accel_mps2 * max(dt_s, 0.0))


Latch = tuple[tuple[Cause, float | None], ...]  # (cause, since when its fear is below the exit threshold)


@dataclass(frozen=True)
class ModeState:
    """The mode machine's memory between frames."""

    mode: Mode = Mode.NORMAL
    frames_over: int = 0  # consecutive frames with fear ≥ enter threshold
    entered_s: float | None = None  # when EMERGENCY was entered
    below_since_s: float | None = None  # since when fear is below the exit threshold (in EMERGENCY)
    latched: Latch = ()  # causes that drove this EMERGENCY, each kept until hold_s below the exit threshold
    fault: bool = False  # a fault drove this EMERGENCY: stop until it is left


def _relatch(latched: Latch, over: frozenset[Cause], cause_fears: Mapping[Cause, float], t_s: float, cfg: PolicyConfig) -> Latch:
    """Add this frame's causes; drop a latched cause once its fear has stayed below exit for hold_s."""
    previous = dict(latched)
    out: list[tuple[Cause, float | None]] = []
    for cause in Cause:
        if cause in over or (cause in previous and cause_fears.get(cause, 0.0) >= cfg.emergency_exit_fear):
            out.append((cause, None))
        elif cause in previous:
            below = previous[cause]
            below = t_s if below is None else below
            if t_s - below < cfg.hold_s:
                out.append((cause, below))
    return tuple(out)


def next_mode(
    state: ModeState,
    fear: float,
    t_s: float,
    at_once: bool,
    cfg: PolicyConfig,
    cause_fears: Mapping[Cause, float] | None = None,
    over: frozenset[Cause] = frozenset(),
    fault: bool = False,
) -> tuple[ModeState, str]:
    """Advance the mode machine one frame; ``at_once`` (imminent collision, fault) enters immediately.

    ``over`` are this frame's causes that demand EMERGENCY (fear over the enter threshold, an imminent
    collision): they are latched, so the plan remembers why it braked during the hold.
    Returns the new state and what happened, for the reasons (empty when nothing changed).
    """
    fears = cause_fears or {}
    hot = fear >= cfg.emergency_enter_fear
    if state.mode is Mode.EMERGENCY:
        latched, faulted = _relatch(state.latched, over, fears, t_s, cfg), state.fault or fault
        if at_once or fear >= cfg.emergency_exit_fear:
            return ModeState(Mode.EMERGENCY, state.frames_over + hot, state.entered_s, None, latched, faulted), ""
        below = t_s if state.below_since_s is None else state.below_since_s
        if t_s - below >= cfg.hold_s:
            mode = Mode.CAUTION if fear >= cfg.caution_fear else Mode.NORMAL
            return ModeState(mode), f"left EMERGENCY after {t_s - below:.2f} s below fear {cfg.emergency_exit_fear:.2f}"
        return ModeState(Mode.EMERGENCY, 0, state.entered_s, below, latched, faulted), ""
    frames = state.frames_over + 1 if hot else 0
    if at_once or frames >= cfg.enter_frames:
        why = "at once" if at_once else f"after {frames} frames with fear >= {cfg.emergency_enter_fear:.2f}"
        latched = tuple((c, None) for c in Cause if c in over)
        return ModeState(Mode.EMERGENCY, frames, t_s, None, latched, fault), f"entered EMERGENCY {why}"
    mode = Mode.CAUTION if fear >= cfg.caution_fear else Mode.NORMAL
    return ModeState(mode, frames), ""


class _Priority(Enum):
    """Tie-break among equal caps: the most protective strategy is reported."""

    STOP = 0
    FOLLOW_LEAD = 1
    CRAWL = 2


@dataclass(frozen=True)
class EmergencyPlan:
    """What to do in EMERGENCY: the strategy, its speed cap, and the steering to use (None = pass)."""

    strategy: Strategy
    cap_mps: float
    steering_deg: float | None
    why: str
    cause: Cause | None = None  # the hazard this plan answers; None for a fault


def active_causes(cause_fears: Mapping[Cause, float], state: ModeState, cfg: PolicyConfig) -> frozenset[Cause]:
    """Causes an EMERGENCY plan answers: latched at or since entry, or now at or above the exit threshold."""
    now = {c for c in Cause if cause_fears.get(c, 0.0) >= cfg.emergency_exit_fear}
    return frozenset({c for c, _ in state.latched} | now)


CAUSE_WORDS = {  # what each cause means, for reasons that name it after its fear has gone
    Cause.COLLISION: "a collision risk",
    Cause.ROAD: "the road picture was lost",
    Cause.LOCALISATION: "the localisation went stale",
}


def _cause_text(cause: Cause, fear: float, state: ModeState, cfg: PolicyConfig, t_s: float | None) -> str:
    """Why a cause is active: its fear now, or — latched, its fear already below the exit threshold — the hold."""
    below = dict(state.latched).get(cause)
    if below is None or fear >= cfg.emergency_exit_fear:
        return {Cause.COLLISION: f"collision risk (fear {fear:.2f})", Cause.ROAD: f"road not trusted (fear {fear:.2f})",
                Cause.LOCALISATION: f"localisation stale (fear {fear:.2f})"}[cause]
    left = f" ({max(0.0, cfg.hold_s - (t_s - below)):.1f} s left)" if t_s is not None else ""
    return f"holding EMERGENCY for {cfg.hold_s:g} s after {CAUSE_WORDS[cause]}{left}"


def emergency_plan(
    cause_fears: Mapping[Cause, float],
    state: ModeState,
    lead: Lead | None,
    held_steering_deg: float,
    cfg: PolicyConfig,
    vehicle: VehicleLimits,
    creep: str = "",
    t_s: float | None = None,
) -> EmergencyPlan:
    """Analyse, then act: every active cause proposes a plan; the one with the lowest cap wins.

    Active: latched at or since entry, or now at or above the exit threshold. A cue getting worse can
    only add causes, so it can only lower the cap: the speed limit stays monotone in every cue.
    ``creep`` (the recovery's reason, empty = none): the road-picture stop becomes a bounded CRAWL to
    re-acquire the road (the supervisor allows it only with the range clear and no fault). ``t_s`` (now) lets
    a cause kept by the hold say how long is left.
    """
    active = active_causes(cause_fears, state, cfg)
    stop = EmergencyPlan(Strategy.STOP, 0.0, held_steering_deg, f"fault: stop, holding {held_steering_deg:+.1f} deg")
    plans = [stop] if state.fault else []
    crawl_cap = cfg.crawl_fraction * vehicle.max_speed_mps
    for cause in sorted(active, key=list(Cause).index):
        why = _cause_text(cause, cause_fears.get(cause, 0.0), state, cfg, t_s)
        if cause is Cause.COLLISION:
            plans.append(EmergencyPlan(Strategy.STOP, 0.0, None, f"{why}: stop", cause))
        elif cause is Cause.ROAD and lead is not None and lead.usable:
            rng = lead.usable_range_m
            cap = rng / cfg.follow_time_gap_s if rng is not None else crawl_cap
            bearing = float(lead.bearing_deg)  # usable: a reading (readings.py), e.g. a Fraction, as a float
            steer = float(np.clip(cfg.follow_gain * bearing, -vehicle.max_steering_deg, vehicle.max_steering_deg))
            gap = f"range {rng:.2f} m, {cfg.follow_time_gap_s:.1f} s gap" if rng is not None else "no range: crawl speed"
            follow = f"{why}: follow the lead at bearing {bearing:+.1f} deg ({gap})"
            plans.append(EmergencyPlan(Strategy.FOLLOW_LEAD, cap, steer, follow, cause))
        elif cause is Cause.ROAD and creep:
            plans.append(EmergencyPlan(Strategy.CRAWL, crawl_cap, held_steering_deg,
                                       f"{why}, range clear: {creep}, holding {held_steering_deg:+.1f} deg", cause))
        elif cause is Cause.ROAD:
            plans.append(EmergencyPlan(Strategy.STOP, 0.0, held_steering_deg,
                                       f"{why} and no lead to follow: stop, holding {held_steering_deg:+.1f} deg", cause))
        else:
            plans.append(EmergencyPlan(Strategy.CRAWL, crawl_cap, None, f"{why}: crawl", cause))
    best = min(plans, key=lambda p: (p.cap_mps, _Priority[p.strategy.name].value), default=stop)
    road_steer = [p.steering_deg for p in plans if p.steering_deg is not None]
    steering = best.steering_deg if best.steering_deg is not None else (road_steer[0] if road_steer else None)
    return EmergencyPlan(best.strategy, best.cap_mps, steering, best.why, best.cause)


# -- recovery: analyse, then act ------------------------------------------------------------------
@dataclass(frozen=True)
class Recovery:
    """The re-acquisition memory of one EMERGENCY: creeps done, distance crept, the dwell and the creep under way."""

    creeps: int = 0  # creeps started in this EMERGENCY
    total_m: float = 0.0  # distance crept in this EMERGENCY
    still_since_s: float | None = None  # standing still (eligible) since
    creep_since_s: float | None = None  # the current creep started at (None: not creeping)
    creep_m: float = 0.0  # distance of the current creep


def recovery_eligible(
    state: ModeState, active: frozenset[Cause], range_m: float, lead: Lead | None, imminent: bool,
) -> bool:
    """An EMERGENCY caused by the road picture alone: no fault, no collision cause, range clear, no lead to follow."""
    return (
        state.mode is Mode.EMERGENCY and not state.fault and not imminent and Cause.ROAD in active
        and Cause.COLLISION not in active and math.isinf(range_m) and range_m > 0 and (lead is None or not lead.usable)
    )


def next_recovery(
    rec: Recovery, eligible: bool, t_s: float, dt_s: float, speed_mps: float, cfg: PolicyConfig, lane_seen: bool = True,
) -> tuple[Recovery, str]:
    """Advance the recovery one frame; returns the new memory and, while creeping, the creep's reason (else "").

    After ``recovery_dwell_s`` at standstill the car creeps at most ``recovery_creep_m`` and ``recovery_creep_s``,
    at most ``recovery_max_creeps`` times and ``recovery_max_total_m`` in all; not eligible = no creep now (a creep
    under way ends). A creep starts only while something of the lane is seen (``lane_seen``): creeping blind cannot
    re-acquire a road that is not there; a flicker of the picture during a creep does not end it.
    The distance is the speed integrated over time (unknown speed counts as the top speed: the creep ends sooner).
    """
    moved = max(0.0, speed_mps) * max(dt_s, 0.0)
    if rec.creep_since_s is not None:
        creep_m, total_m = rec.creep_m + moved, rec.total_m + moved
        done = (creep_m >= cfg.recovery_creep_m or t_s - rec.creep_since_s >= cfg.recovery_creep_s - TIME_EPS_S
                or total_m >= cfg.recovery_max_total_m)
        if eligible and not done:
            why = (f"re-acquisition creep {rec.creeps} of {cfg.recovery_max_creeps} "
                   f"({creep_m:.2f} of {cfg.recovery_creep_m:.2f} m, {t_s - rec.creep_since_s:.1f} of {cfg.recovery_creep_s:.1f} s)")
            return Recovery(rec.creeps, total_m, None, rec.creep_since_s, creep_m), why
        return Recovery(rec.creeps, total_m), ""
    if speed_mps > cfg.standstill_mps or recovery_exhausted(rec, cfg):
        return Recovery(rec.creeps, rec.total_m), ""
    still = t_s if rec.still_since_s is None else rec.still_since_s
    if not (eligible and lane_seen) or t_s - still < cfg.recovery_dwell_s - TIME_EPS_S:
        return Recovery(rec.creeps, rec.total_m, still), ""  # the dwell counts standing still; the creep waits
    why = f"re-acquisition creep {rec.creeps + 1} of {cfg.recovery_max_creeps} after {t_s - still:.1f} s at standstill"
    return Recovery(rec.creeps + 1, rec.total_m, None, t_s, 0.0), why


def recovery_exhausted(rec: Recovery, cfg: PolicyConfig) -> bool:
    """No creep left in this EMERGENCY: the car stays stopped."""
    return rec.creeps >= cfg.recovery_max_creeps or rec.total_m >= cfg.recovery_max_total_m


def recovery_status(rec: Recovery, eligible: bool, cfg: PolicyConfig, t_s: float, lane_seen: bool = True) -> str:
    """What the recovery is doing while the car is stopped by the road picture (for the reasons)."""
    if not eligible:
        return ""
    if recovery_exhausted(rec, cfg):
        return (f"recovery exhausted: {rec.creeps} creep(s), {rec.total_m:.2f} m crept, the road is still not seen: "
                f"staying stopped")
    if not lane_seen:
        return (f"recovery: nothing of the lane seen (confidence below {cfg.recovery_min_confidence:.2f}): "
                f"a creep cannot re-acquire it, staying stopped")
    if rec.still_since_s is not None:
        return f"recovery: analysing at standstill ({t_s - rec.still_since_s:.1f} of {cfg.recovery_dwell_s:.1f} s before a creep)"
    return "recovery: waiting for standstill before a creep"
