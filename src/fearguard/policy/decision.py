"""One frame's decision as named steps over plain values: the speed caps, the steering choice, the explanation.

The supervisor keeps the clock, the state (mode machine, recovery, the steering it trusts) and the faults; each step
here is a pure function of what it is handed, so each can be tested, and read, on its own:

    envelope_step   the stopping envelope for the obstacle range (RSS), and the distance it plans with
    follow_step     a moving object ahead → the time-gap cap that follows it at its speed
    lane_step       the lane check's verdict → the steering wanted, a cap, CAUTION, and whether the estimator is distrusted
    doubt_step      a road picture not trusted, no EMERGENCY yet → the steering last given on a calm picture, held
    emergency_step  an EMERGENCY plan → the strategy, its cap, the steering (a creep steers by the lane seen now)
    motion_reasons  why the obstacle binds: an imminent collision, or a proper response inside the safe distance
    limit_reason    which cap set the speed limit
    rule_reasons    the rules that drove fear, and perception's facts, when fear is up or the mode is not NORMAL

Speed limit = the smallest cap (fear, envelope, follow, lane check, emergency plan, lateral), rate-limited upward
(``speed.rate_limited_mps``): a step can only add a cap, never lift one.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass

from fearguard.fear import Cause, FearLevel, FearResult
from fearguard.policy.config import Mode, PolicyConfig, Strategy
from fearguard.policy.emergency import EmergencyPlan
from fearguard.policy.lane_check import LaneCheck
from fearguard.policy.speed import envelope_speed_mps, lead_speed_mps
from fearguard.readings import finite_reading
from fearguard.vehicle import VehicleLimits

TOP_RULES_IN_REASONS = 3  # [-] rules quoted in a command's reasons


def measured_speed(reading_mps: object, vehicle: VehicleLimits) -> tuple[float | None, float]:
    """(the measured speed, None when it is no speed ≥ 0; the speed to plan with: unknown counts as the top speed)."""
    speed = finite_reading(reading_mps)
    speed = speed if speed is not None and speed >= 0 else None
    return speed, vehicle.max_speed_mps if speed is None else speed


def first_limit_mps(speed_mps: float | None, vehicle: VehicleLimits) -> float:
    """Where the speed limit's ramp starts on the first frame: the car's measured speed (within its top speed), else 0."""
    return min(speed_mps if speed_mps is not None else 0.0, vehicle.max_speed_mps)


@dataclass(frozen=True)
class Envelope:
    """The stopping envelope's speed and the distance it plans with."""

    speed_mps: float  # inf: nothing is known in range
    seen_m: float  # [m] the obstacle's range, or — nothing in range on a car with a range sensor — the sensor's maximum


def envelope_step(range_m: float, speed_mps: float | None, closing_mps: float | None, vehicle: VehicleLimits) -> Envelope:
    """Nothing in range on a car with a range sensor: an obstacle may stand just beyond what it sees, so the car must
    stop within that; a range: the responsibility-sensitive distance to the object at its estimated speed."""
    seen_m = range_m if math.isfinite(range_m) or not vehicle.has_ultrasonic else vehicle.ultrasonic_max_range_m
    lead = lead_speed_mps(speed_mps, closing_mps) if seen_m == range_m else 0.0
    return Envelope(envelope_speed_mps(seen_m, vehicle, lead), seen_m)


def follow_step(range_m: float, speed_mps: float | None, closing_mps: float | None, cfg: PolicyConfig,
                vehicle: VehicleLimits) -> tuple[float, str]:
    """An object ahead that keeps moving is followed, not only braked for (what an ACC does): the car settles behind it
    at its speed v_l with the gap d* = margin + ``follow_time_gap_s`` · v_l, well outside the RSS distance, so the
    range's noise (a camera's box jitters by metres) never brings the gap near the envelope and collision fear. Farther
    than d*, the cap is the speed from which ``follow_decel_mps2`` brakes to v_l within d − d*: √(v_l² + 2a(d − d*));
    nearer, (d − margin) / gap: slower than the lead until the gap is back. An object that stands (no faster than
    ``moving_object_min_mps``), or unknown motion: no cap here (the envelope and fear answer). (cap, reason; inf and
    "" when it does not bind)."""
    if not math.isfinite(range_m) or speed_mps is None:
        return math.inf, ""
    lead = lead_speed_mps(speed_mps, closing_mps)  # unknown closing speed: 0, it stands
    if lead <= cfg.moving_object_min_mps:
        return math.inf, ""
    margin, gap_s = float(vehicle.stop_margin_m), float(cfg.follow_time_gap_s)  # any Real a caller built them from
    wanted = margin + gap_s * lead
    if range_m >= wanted:
        decel = float(min(cfg.follow_decel_mps2, vehicle.max_decel_mps2))
        cap = math.sqrt(lead * lead + 2.0 * decel * (range_m - wanted))
    else:
        cap = max(0.0, range_m - margin) / gap_s
    if cap >= speed_mps:
        return cap, ""
    return cap, (f"following the object ahead at {range_m:.1f} m (its speed {lead:.1f} m/s) with a {gap_s:g} s time gap "
                 f"({wanted:.1f} m): {cap:.2f} m/s")


@dataclass(frozen=True)
class SteeringChoice:
    """What the lane check makes of the wrapped steering this frame."""

    steering_deg: float  # the steering wanted
    caution: bool  # the answer is at least CAUTION (the estimator is overridden)
    cap_mps: float  # inf: no cap
    reason: str  # "" when nothing to say
    distrusted: bool  # remember: the estimator steered out of the lane when last checked


def lane_step(check: LaneCheck | None, distrusted: bool, steering_deg: float, lane_now_deg: float | None, trusted_deg: float,
              cfg: PolicyConfig, vehicle: VehicleLimits) -> SteeringChoice:
    """The lane check's override; while the check cannot run (road not calm, not moving) an estimator it last caught
    steering out of the lane is not trusted again: steer by the lane seen now (a stale angle drives out of a bending
    lane), else hold the last trusted angle."""
    cap = cfg.lane_check_fraction * vehicle.max_speed_mps
    if check is not None and check.override_deg is not None:
        return SteeringChoice(check.override_deg, True, cap, check.why, True)
    if check is None and distrusted:
        wanted = lane_now_deg if lane_now_deg is not None else trusted_deg
        source = "steering by the lane geometry seen now" if lane_now_deg is not None else "holding the lane geometry's last"
        why = f"lane check: the estimator steered out of the lane when last checked: {source} {wanted:+.1f} deg"
        return SteeringChoice(wanted, True, cap, why, True)
    return SteeringChoice(steering_deg, False, math.inf, check.why if check is not None else "", distrusted and check is None)


def doubt_step(road_fear: float, wanted_deg: float, trusted_deg: float, cfg: PolicyConfig) -> tuple[float, str]:
    """While the road picture is not trusted (its fear at or over the emergency threshold) before an EMERGENCY answers
    it — a flicker's grace, the frames the mode machine counts — the steering last given on a calm picture is held:
    the estimator reads the very picture in doubt (MetaDrive, a tight bend: the lane lost for 0.3 s, the lane
    steering's angle fell from 17 to 3 deg and the car left its lane), and the EMERGENCY that may follow holds that
    angle too. A calm picture steers as wanted."""
    if road_fear < cfg.emergency_enter_fear or wanted_deg == trusted_deg:
        return wanted_deg, ""
    return trusted_deg, (f"road picture not trusted (fear {road_fear:.2f}): holding the steering of the last calm picture "
                         f"{trusted_deg:+.1f} deg (the estimator's {wanted_deg:+.1f} deg read the picture in doubt)")


@dataclass(frozen=True)
class EmergencyChoice:
    """The EMERGENCY plan as answered: strategy, the cause it answers, its cap, the steering, and why."""

    strategy: Strategy
    cause: Cause | None
    cap_mps: float
    steering_deg: float
    reasons: tuple[str, ...]


def emergency_step(plan: EmergencyPlan, creep: str, lane_now_deg: float | None, wanted_deg: float, status: str,
                   estimator_deg: float | None = None, max_creep_deg: float = 90.0) -> EmergencyChoice:
    """The plan's steering (else the one wanted); a creep steers closed-loop by the lane seen now, else by the wrapped
    estimator within ±``max_creep_deg`` (``estimator_deg`` None: it is distrusted, the plan holds the last trusted
    heading); a stop says what the recovery is doing (``status``)."""
    steering = plan.steering_deg if plan.steering_deg is not None else wanted_deg
    reasons = [f"EMERGENCY {plan.strategy.name}: {plan.why}"]
    if creep and lane_now_deg is not None:
        steering = lane_now_deg
        reasons.append(f"creep steering by the lane geometry seen now: {lane_now_deg:+.1f} deg")
    elif creep and estimator_deg is not None:
        steering = max(-max_creep_deg, min(max_creep_deg, estimator_deg))
        reasons.append(f"creep steering by the estimator within ±{max_creep_deg:g} deg: {steering:+.1f} deg")
    if not creep and status and plan.strategy is Strategy.STOP:
        reasons.append(status)
    return EmergencyChoice(plan.strategy, plan.cause, plan.cap_mps, steering, tuple(reasons))


def fear_range_m(range_m: float, speed_mps: float | None, closing_mps: float | None, moving_min_mps: float = 0.0) -> float:
    """The range collision fear reads. A standing obstacle at D demands v²/(2D) of braking from the ego's speed v; an
    object ahead that keeps moving demands c²/(2d) at its range d and closing speed c — the braking a standing obstacle
    at d·(v/c)² would demand. So a moving object counts as standing that far (an opening or steady gap: nothing ahead);
    a car closing on a slower one is braked to its speed by the envelope (which still allows for the lead's hardest
    braking), not stopped by fear. Unknown speed or closing speed: the range as it is (standing: the worst). Faster
    closing reads nearer, never farther.

    An object whose own speed v − c is at most ``moving_min_mps`` stands: a car stopping in front of a box, its
    speed estimate decaying toward 0 and the gap steady, must not read the box as a lead moving away (it then drove
    on into it)."""
    if not math.isfinite(range_m) or speed_mps is None or closing_mps is None or not math.isfinite(closing_mps) or speed_mps <= 0.0:
        return range_m
    if lead_speed_mps(speed_mps, closing_mps) <= moving_min_mps:
        return range_m  # the object stands (or comes toward the car)
    if closing_mps <= 0.0:
        return math.inf  # a steady or opening gap behind a moving object demands no braking
    ratio = speed_mps / closing_mps
    return range_m * ratio * ratio  # a float product overflows to inf (** raises)


def motion_reasons(imminent: bool, envelope_mps: float, range_m: float, speed_now_mps: float, speed_mps: float | None,
                   closing_mps: float | None, vehicle: VehicleLimits) -> tuple[str, ...]:
    """Why the obstacle binds: no braking avoids it (imminent), or the car is inside its safe distance (brake to it)."""
    if imminent:
        return (f"imminent collision: obstacle at {range_m:.2f} m, no braking within {vehicle.max_decel_mps2:.1f} m/s² "
                f"avoids it from {speed_now_mps:.2f} m/s",)
    if envelope_mps < speed_now_mps and math.isfinite(range_m):
        return (f"proper response: inside the safe distance of the object at {range_m:.2f} m (its speed "
                f"{lead_speed_mps(speed_mps, closing_mps):.2f} m/s): braking to {envelope_mps:.2f} m/s",)
    return ()


def limit_reason(limit: float, fear_limit: float, envelope: float, target: float, range_m: float, lateral: float,
                 follow: float = math.inf) -> str:
    """Which cap set the speed limit (or that it is still rising toward it)."""
    if limit < target - 1e-12:
        return f"speed limit {limit:.2f} m/s: rising at the comfort acceleration toward {target:.2f} m/s"
    if envelope <= fear_limit and envelope <= target + 1e-12 and not math.isinf(envelope):
        return f"speed limit {limit:.2f} m/s: safe distance envelope for an obstacle at {range_m:.2f} m"
    if follow <= fear_limit and follow <= target + 1e-12:
        return f"speed limit {limit:.2f} m/s: the time gap to the object ahead at {range_m:.2f} m"
    if lateral <= target + 1e-12:
        return f"speed limit {limit:.2f} m/s: lateral acceleration at this steering angle"
    if fear_limit <= target + 1e-12:
        return f"speed limit {limit:.2f} m/s: set by fear"
    return f"speed limit {limit:.2f} m/s: set by the emergency strategy"


def rule_reasons(result: FearResult, mode: Mode, facts: Sequence[str]) -> tuple[str, ...]:
    """The rules that drove fear and perception's facts — when fear is above VERY_LOW or the mode is not NORMAL."""
    if result.level <= FearLevel.VERY_LOW and mode is Mode.NORMAL:
        return ()
    return (*(f"rule {text!r} fired {s:.2f}" for text, s in result.top_rules(TOP_RULES_IN_REASONS)), *facts)
