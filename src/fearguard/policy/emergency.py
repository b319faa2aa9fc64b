"""Emergency: analyse, then act — the plan each active cause proposes, and the re-acquisition creep after a road stop."""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass, replace
from enum import Enum

import numpy as np

from fearguard.fear import Cause
from fearguard.observation import Lead
from fearguard.policy.config import TIME_EPS_S, Mode, PolicyConfig, Strategy
from fearguard.policy.modes import ModeState
from fearguard.policy.speed import stopping_distance_m
from fearguard.vehicle import VehicleLimits


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
    creep_cap_mps: float | None = None,
) -> EmergencyPlan:
    """Analyse, then act: every active cause proposes a plan; the one with the lowest cap wins.

    Active: latched at or since entry, or now at or above the exit threshold. A cue getting worse can
    only add causes, so it can only lower the cap: the speed limit stays monotone in every cue.
    ``creep`` (the recovery's reason, empty = none): the road-picture stop becomes a bounded CRAWL to
    re-acquire the road (the supervisor allows it only with the range clear and no fault). ``t_s`` (now) lets
    a cause kept by the hold say how long is left. ``creep_cap_mps``: a creep on the caller's route goes at the route's
    own cap (``policy.route``: never faster than the car stops within the path known clear), not at crawl speed.
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
            gap = f"range {rng:.2f} m, {float(cfg.follow_time_gap_s):.1f} s gap" if rng is not None else "no range: crawl speed"
            follow = f"{why}: follow the lead at bearing {bearing:+.1f} deg ({gap})"
            plans.append(EmergencyPlan(Strategy.FOLLOW_LEAD, cap, steer, follow, cause))
        elif cause is Cause.ROAD and creep:
            plans.append(EmergencyPlan(Strategy.CRAWL, crawl_cap if creep_cap_mps is None else creep_cap_mps, held_steering_deg,
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
SIGHT_GAP_S = 0.5  # [s] the lane seen this recently is still in sight: a dash passing in and out of view, a line read on
#   alternate frames (sparse dashes in a bend, at standstill: gaps of 0.05-0.35 s) is no "nothing of the lane in sight";
#   at creep speed (0.3 m/s on a model car) the car has gone 15 cm since, half the blind budget's premise
GUIDE_GAP_S = 0.1  # [s] a boundary missed this long (a frame or two at 20 Hz: glare leaves a line at support 0.25-0.4, and
#   some frames miss it) does not end a spell of frames that found it; a shadow's edge found here and there is no spell


@dataclass(frozen=True)
class Recovery:
    """The re-acquisition memory of one EMERGENCY: creeps done, distance crept, the dwell and the creep under way."""

    creeps: int = 0  # creeps started in this EMERGENCY
    total_m: float = 0.0  # distance crept in this EMERGENCY
    still_since_s: float | None = None  # standing still (eligible) since
    creep_since_s: float | None = None  # the current creep started at (None: not creeping)
    creep_m: float = 0.0  # distance of the current creep
    blind_m: float = 0.0  # distance crept with nothing of the lane in sight, in this EMERGENCY
    guided_since_s: float | None = None  # a boundary found in the frames since, gaps of at most GUIDE_GAP_S (None: no such spell)
    guided_last_s: float | None = None  # the last frame that found one
    guided_m: float = 0.0  # distance crept steered by the lane re-acquired, in this EMERGENCY (reported, not bounded)
    seen_last_s: float | None = None  # the last frame of this EMERGENCY that saw the lane (``lane_in_sight``)


def lane_in_sight(rec: Recovery, t_s: float, seen: bool) -> tuple[Recovery, bool]:
    """Remember a frame that saw the lane; whether the lane is in sight: seen now or within SIGHT_GAP_S. A creep with
    the lane out of sight is blind (``recovery_blind_m``): a picture that shows the lane on every other frame is not."""
    if seen:
        return replace(rec, seen_last_s=t_s), True
    last = rec.seen_last_s
    return rec, last is not None and 0.0 <= t_s - last <= SIGHT_GAP_S + TIME_EPS_S


def recovery_eligible(state: ModeState, active: frozenset[Cause], lead: Lead | None, imminent: bool) -> bool:
    """An EMERGENCY caused by the road picture alone: no fault, no collision cause, nothing imminent, no lead to follow.
    (Whether a creep may run also needs the path ahead known clear: ``creep_clearance``.)"""
    return (
        state.mode is Mode.EMERGENCY and not state.fault and not imminent and Cause.ROAD in active
        and Cause.COLLISION not in active and (lead is None or not lead.usable)
    )


def creep_needs_m(cfg: PolicyConfig, vehicle: VehicleLimits) -> float:
    """How far ahead the path must be known clear for a creep: stopping from the creep speed, plus the margin."""
    return stopping_distance_m(cfg.crawl_fraction * vehicle.max_speed_mps, vehicle) + vehicle.stop_margin_m


def creep_clearance(clear_m: float, cfg: PolicyConfig, vehicle: VehicleLimits) -> str:
    """Why a creep may not run on what is known of the path ahead ("" when it may): a range reading beyond the creep's
    stopping distance, or the camera's object search finding the lane free that far, says the path is clear."""
    need = creep_needs_m(cfg, vehicle)
    if clear_m >= need:
        return ""
    if clear_m > 0.0:
        return f"the path ahead is known clear for {clear_m:.2f} m only, a creep needs {need:.2f} m"
    return "nothing is known about the path ahead (no range reading, no camera object search)"


def next_recovery(
    rec: Recovery, eligible: bool, t_s: float, dt_s: float, speed_mps: float, cfg: PolicyConfig, blind: bool = False,
    guided: bool = False, routed: bool = False,
) -> tuple[Recovery, str]:
    """Advance the recovery one frame; returns the new memory and, while creeping, the creep's reason (else "").

    After ``recovery_dwell_s`` at standstill the car creeps at most ``recovery_creep_m`` and ``recovery_creep_s``,
    at most ``recovery_max_creeps`` times and ``recovery_max_total_m`` in all; not eligible = no creep now (a creep
    under way ends: the path stopped being known clear, an obstacle appeared). A creep needs no lane in sight — only the
    path ahead known clear (the caller's ``eligible``): where the markings end (an intersection, a glare zone) a slow
    creep is how the car finds them again; a flicker of the picture during a creep does not end it. But a creep with
    nothing of the lane in sight (``blind``) steers blind, and on a curve any steering error leaves the lane within a few
    metres: blind metres end at ``recovery_blind_m`` per EMERGENCY.
    A boundary found frame after frame for ``recovery_dwell_s`` (``guided``, a frame or two missed at most: a line read
    where the track expected it, in glare or beside a hidden stretch; ``lane_reacquired``) is the lane re-acquired: the
    budget starts afresh (tries, distance, blind metres — a blind stretch's drift counts from where the lane was last seen), a creep
    under way goes on steered by it, and a car standing still creeps again after its dwell. Through 8 m of low sun that
    leaves one line readable the car crawls on with the path known clear, instead of stopping for good after the
    budget's 2 m. A line found in a frame here and there (a shadow's edge) is no re-acquisition.
    The distance is the speed integrated over time (unknown speed counts as the top speed: the creep ends sooner).
    A creep steered by the caller's route (``routed``: ``policy.route``; a known path, not a guess) is one creep that goes on
    while the route's budget lasts (the caller's ``routed``, ``route_blind_m`` in all) — across the rest of a junction after
    a stop in it — not a string of car lengths.
    """
    moved = max(0.0, speed_mps) * max(dt_s, 0.0)
    last = rec.guided_last_s  # set whenever a spell is (guided_since_s)
    spell = rec.guided_since_s is not None and last is not None and t_s - last <= GUIDE_GAP_S + TIME_EPS_S
    since = rec.guided_since_s if spell else (t_s if guided else None)
    rec = replace(rec, guided_since_s=since, guided_last_s=t_s if guided else last)
    creeping = rec.creep_since_s is not None
    if lane_reacquired(rec, t_s, cfg):  # a fresh budget from here
        rec = Recovery(creeps=1 if creeping else 0, still_since_s=rec.still_since_s, creep_since_s=t_s if creeping else None,
                       guided_since_s=since, guided_last_s=rec.guided_last_s, guided_m=rec.guided_m)
        if creeping and eligible:
            guided_m = rec.guided_m + moved
            why = (f"re-acquisition creep guided by the lane boundary seen now ({guided_m:.2f} m so far; the budget counts "
                   f"from where it is lost)")
            return replace(rec, guided_m=guided_m), why
        blind = False
    if creeping:
        blind_m = rec.blind_m + (moved if blind else 0.0)  # only a creep's own metres count (following a lead is no blind creep)
        creep_m, total_m = rec.creep_m + moved, rec.total_m + moved
        done = not routed and (creep_m >= cfg.recovery_creep_m or t_s - rec.creep_since_s >= cfg.recovery_creep_s - TIME_EPS_S
                               or total_m >= cfg.recovery_max_total_m or (blind and blind_m >= cfg.recovery_blind_m))
        if eligible and not done:
            why = (f"re-acquisition creep {rec.creeps} of {cfg.recovery_max_creeps} "
                   f"({creep_m:.2f} of {float(cfg.recovery_creep_m):.2f} m, "
                   f"{t_s - rec.creep_since_s:.1f} of {float(cfg.recovery_creep_s):.1f} s)")
            if routed:
                why = f"re-acquisition creep on the route ({total_m:.2f} of {float(cfg.route_blind_m):.2f} m)"
            return replace(rec, total_m=total_m, still_since_s=None, creep_m=creep_m, blind_m=blind_m), why
        unused = not eligible and creep_m <= 0.0  # ended before the car moved (the path stopped being known clear): no try spent
        return replace(rec, creeps=rec.creeps - 1 if unused else rec.creeps, total_m=total_m, still_since_s=None,
                       creep_since_s=None, creep_m=0.0, blind_m=blind_m), ""
    if speed_mps > cfg.standstill_mps or recovery_exhausted(rec, cfg) or (blind and rec.blind_m >= cfg.recovery_blind_m):
        return replace(rec, still_since_s=None), ""
    still = t_s if rec.still_since_s is None else rec.still_since_s
    if not eligible or t_s - still < cfg.recovery_dwell_s - TIME_EPS_S:
        return replace(rec, still_since_s=still), ""  # the dwell counts standing still; the creep waits
    why = f"re-acquisition creep {rec.creeps + 1} of {cfg.recovery_max_creeps} after {t_s - still:.1f} s at standstill"
    return replace(rec, creeps=rec.creeps + 1, still_since_s=None, creep_since_s=t_s, creep_m=0.0), why


def lane_reacquired(rec: Recovery, t_s: float, cfg: PolicyConfig) -> bool:
    """A boundary has been found frame after frame (gaps of at most ``GUIDE_GAP_S``) for ``recovery_dwell_s``: the lane is
    re-acquired, and a creep steers by it."""
    return rec.guided_since_s is not None and t_s - rec.guided_since_s >= cfg.recovery_dwell_s - TIME_EPS_S


def recovery_exhausted(rec: Recovery, cfg: PolicyConfig) -> bool:
    """No creep left in this EMERGENCY: the car stays stopped."""
    return rec.creeps >= cfg.recovery_max_creeps or rec.total_m >= cfg.recovery_max_total_m


def recovery_status(rec: Recovery, road_stop: bool, cfg: PolicyConfig, t_s: float, unclear: str = "", blind: bool = False) -> str:
    """What the recovery is doing while the car is stopped by the road picture (for the reasons); ``unclear``: why the
    path ahead is not known clear (``creep_clearance``), when it is not."""
    if not road_stop:
        return ""
    if recovery_exhausted(rec, cfg):
        return (f"recovery exhausted: {rec.creeps} creep(s), {rec.total_m:.2f} m crept, the road is still not seen: "
                f"staying stopped")
    if unclear:
        return f"recovery: {unclear}: a creep could not stop for what it cannot see, staying stopped"
    if blind and rec.blind_m >= cfg.recovery_blind_m:
        return (f"recovery: {rec.blind_m:.2f} m crept with nothing of the lane in sight (at most {cfg.recovery_blind_m:.2f} m "
                f"blind), the lane is still not seen: staying stopped")
    if rec.still_since_s is not None:
        return f"recovery: analysing at standstill ({t_s - rec.still_since_s:.1f} of {float(cfg.recovery_dwell_s):.1f} s before a creep)"
    return "recovery: waiting for standstill before a creep"
