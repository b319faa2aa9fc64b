"""Policy: fear → speed limit ∧ stopping envelope, the mode machine, and the emergency strategy.

Pure functions over plain values; the supervisor owns the state and the clock. Policy never looks
at pixels, only at fear, cues, the lead vehicle and the vehicle's limits.

Speed limit = min(fear limit, stopping envelope, emergency cap), then rate-limited upward by the
comfort acceleration. Each emergency cause that is active imposes its own cap and the smallest wins,
so a cue getting worse can only add caps: the limit never rises when a cue worsens.
"""

from __future__ import annotations

import math
from collections.abc import Mapping
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


class Mode(Enum):
    NORMAL = "NORMAL"
    CAUTION = "CAUTION"
    EMERGENCY = "EMERGENCY"


class Strategy(Enum):
    PASS_THROUGH = "PASS_THROUGH"
    FOLLOW_LEAD = "FOLLOW_LEAD"
    STOP = "STOP"
    CRAWL = "CRAWL"


def _finite(value: object) -> bool:
    return finite_reading(value) is not None


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

    @classmethod
    def from_table(cls, src: TomlSource, data: object, key_path: str = "policy") -> PolicyConfig:
        """Validate a ``[policy]`` table with the strict reader; errors name the file, the line and the key."""
        t = Table(src, data, key_path, [f.name for f in fields(cls)])
        values: dict[str, Any] = {}
        for key in t.data:
            if key == "speed_fraction":
                values[key] = _fractions(t, key)
            elif key == "enter_frames":
                values[key] = t.integer(key, low=1)
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
        ):
            if not ok:
                raise t.fail(key, f"{problem}, got {getattr(cfg, key)}")
        return cfg


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


def envelope_speed_mps(range_m: float, vehicle: VehicleLimits) -> float:
    """Largest v with v·t_r + v²/(2a) ≤ max(0, d − margin); inf when nothing is in range."""
    if math.isinf(range_m):
        return math.inf
    room = max(0.0, range_m - vehicle.stop_margin_m)
    t_r, a = vehicle.reaction_time_s, vehicle.max_decel_mps2
    v = 2.0 * room / (t_r + math.sqrt(t_r * t_r + 2.0 * room / a)) if room > 0.0 else 0.0
    return v * (1.0 - ENVELOPE_SHRINK)


def imminent_collision(range_m: float, speed_mps: float, vehicle: VehicleLimits) -> bool:
    """The car cannot stop short of the obstacle from its current speed (or is inside the margin)."""
    if math.isinf(range_m):
        return False
    return range_m <= vehicle.stop_margin_m or stopping_distance_m(speed_mps, vehicle) >= range_m - vehicle.stop_margin_m


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


def emergency_plan(
    cause_fears: Mapping[Cause, float],
    state: ModeState,
    lead: Lead | None,
    held_steering_deg: float,
    cfg: PolicyConfig,
    vehicle: VehicleLimits,
) -> EmergencyPlan:
    """Analyse, then act: every active cause proposes a plan; the one with the lowest cap wins.

    Active: latched at or since entry, or now at or above the exit threshold. A cue getting worse can
    only add causes, so it can only lower the cap: the speed limit stays monotone in every cue.
    """
    active = {c for c, _ in state.latched} | {c for c in Cause if cause_fears.get(c, 0.0) >= cfg.emergency_exit_fear}
    stop = EmergencyPlan(Strategy.STOP, 0.0, held_steering_deg, f"fault: stop, holding {held_steering_deg:+.1f} deg")
    plans = [stop] if state.fault else []
    for cause in sorted(active, key=list(Cause).index):
        f = cause_fears.get(cause, 0.0)
        if cause is Cause.COLLISION:
            plans.append(EmergencyPlan(Strategy.STOP, 0.0, None, f"collision risk (fear {f:.2f}): stop"))
        elif cause is Cause.ROAD and lead is not None and lead.usable:
            rng = lead.usable_range_m
            cap = rng / cfg.follow_time_gap_s if rng is not None else cfg.crawl_fraction * vehicle.max_speed_mps
            bearing = float(lead.bearing_deg)  # usable: a reading (readings.py), e.g. a Fraction, as a float
            steer = float(np.clip(cfg.follow_gain * bearing, -vehicle.max_steering_deg, vehicle.max_steering_deg))
            gap = f"range {rng:.2f} m, {cfg.follow_time_gap_s:.1f} s gap" if rng is not None else "no range: crawl speed"
            why = f"road not trusted (fear {f:.2f}): follow the lead at bearing {bearing:+.1f} deg ({gap})"
            plans.append(EmergencyPlan(Strategy.FOLLOW_LEAD, cap, steer, why))
        elif cause is Cause.ROAD:
            why = f"road not trusted (fear {f:.2f}) and no lead to follow: stop, holding {held_steering_deg:+.1f} deg"
            plans.append(EmergencyPlan(Strategy.STOP, 0.0, held_steering_deg, why))
        else:
            cap = cfg.crawl_fraction * vehicle.max_speed_mps
            plans.append(EmergencyPlan(Strategy.CRAWL, cap, None, f"localisation stale (fear {f:.2f}): crawl"))
    best = min(plans, key=lambda p: (p.cap_mps, _Priority[p.strategy.name].value), default=stop)
    road_steer = [p.steering_deg for p in plans if p.steering_deg is not None]
    steering = best.steering_deg if best.steering_deg is not None else (road_steer[0] if road_steer else None)
    return EmergencyPlan(best.strategy, best.cap_mps, steering, best.why)
