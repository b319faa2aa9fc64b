"""FearGuard: wraps a steering function and answers every frame with a safe Command.

Observation → perception (cues) → fear (rule base) → policy (speed limit, mode, strategy) → Command.
Given ready-made ``cues`` the perception is skipped (cue-level use, no camera needed).
``step`` never raises an ``Exception``: a fault anywhere (steering function raising or returning garbage,
time not increasing, a malformed observation, even values whose ``repr`` raises) becomes EMERGENCY/STOP
with the fault in ``reasons``. KeyboardInterrupt and SystemExit from the steering function propagate,
as Python code expects (they are not faults of the car but requests to stop the program).
"""

from __future__ import annotations

import math
import statistics
from collections import deque
from collections.abc import Callable
from dataclasses import dataclass, field, replace
from pathlib import Path
from typing import Any

from fearguard.camera import CameraModel
from fearguard.cues import CUE_NAMES, OBSTACLE_RANGE, QR_STALENESS, Cues, calm_values, unknown_note, worst_filled
from fearguard.errors import describe, describe_exception
from fearguard.fear import Cause, FearLevel, FearResult
from fearguard.fuzzy.loader import load_rules
from fearguard.fuzzy.rulebase import RuleBase
from fearguard.observation import Lead, Observation  # Observation re-exported: fearguard.supervisor.Observation keeps working
from fearguard.perception import FrameSteering, Perceived, Perception, clamp_to_sensor
from fearguard.policy import (
    Mode,
    ModeState,
    Recovery,
    Strategy,
    active_causes,
    closing_speed_from_ranges,
    creep_clearance,
    emergency_plan,
    fear_speed_mps,
    imminent_collision,
    lane_in_sight,
    lane_reacquired,
    lateral_speed_mps,
    lead_speed_mps,
    next_mode,
    next_recovery,
    oscillating,
    rate_limited_mps,
    rate_limited_steering_deg,
    recovery_eligible,
    recovery_status,
    same_object_after_gap,
    watchdog_s,
)
from fearguard.policy.decision import (
    EmergencyChoice,
    doubt_step,
    emergency_step,
    envelope_step,
    fear_range_m,
    first_limit_mps,
    follow_step,
    lane_step,
    limit_reason,
    measured_speed,
    motion_reasons,
    rule_reasons,
)
from fearguard.policy.lane_check import LaneCheck, lane_check
from fearguard.policy.route import next_route
from fearguard.policy.stop_line import StopLine, next_stop_line
from fearguard.readings import finite_reading
from fearguard.steering_deadline import SteeringDeadline
from fearguard.track.profile import TrackProfile, load_track
from fearguard.vehicle import VehicleLimits

SteeringFunction = Callable[[Any], float]
PERIOD_MEMORY = 9  # [frames] gaps between frames whose median is the typical frame period (watchdog)
RANGE_MEMORY = 16  # [frames] obstacle ranges kept for the closing speed at cue level
CALM_MEMORY = 3  # [frames] the steering held while the road picture is in doubt is the median of the last calm pictures' (as the
#   confidence is of its last 3): one calm frame amid a flicker steered -7.9 deg on a gentle right arc, and held for the
#   flicker's grace it took the car out of the lane (the pale_dashes scenario, seed 9)


@dataclass(frozen=True)
class Command:
    """The supervisor's answer: steering to apply, speed not to exceed, and why."""

    steering_deg: float
    speed_limit_mps: float
    mode: Mode
    strategy: Strategy
    fear: float
    fear_level: FearLevel
    cues: Cues
    reasons: tuple[str, ...]
    fear_limit_mps: float = math.nan  # the fear-based part of the limit
    envelope_mps: float = math.nan  # the stopping envelope for the obstacle range
    cause: Cause | None = None  # the cause with the largest share of the fear; None for a fault
    # what perception measured on THIS frame (lanes, lead box, timings: for logs and overlays); None for cue-level
    # frames and faults before perception. Not part of the decision: excluded from equality and repr.
    perceived: Perceived | None = field(default=None, compare=False, repr=False)
    closing_speed_mps: float = math.nan  # how fast the obstacle ahead comes closer (+), as the envelope used it; NaN unknown


@dataclass
class _State:
    mode: ModeState = field(default_factory=ModeState)
    last_t_s: float | None = None
    limit_mps: float | None = None
    calm_steering: deque[float] = field(default_factory=lambda: deque(maxlen=CALM_MEMORY))  # the last calm pictures' steering
    out_steering_deg: float | None = None  # last steering answered (the rate limit starts from it)
    estimator_distrusted: bool = False  # the last lane check overrode the wrapped steering
    recovery: Recovery = field(default_factory=Recovery)
    stop_line: StopLine = field(default_factory=StopLine)  # standing before a stop line, or crossing after one
    range_noted: bool = False  # a range was given to a car that declares no range sensor, and the reasons said so
    raw_steering: deque[float] = field(default_factory=deque)  # the last oscillation_flips + 1 wrapped angles
    periods_s: deque[float] = field(default_factory=lambda: deque(maxlen=PERIOD_MEMORY))
    ranges: deque[tuple[float, float]] = field(default_factory=lambda: deque(maxlen=RANGE_MEMORY))
    range_missed: bool = False  # frames without a range since the last one (policy.speed.same_object_after_gap)
    routed_m: float = 0.0  # [m] driven by the route since the road picture was last trusted (policy.route)
    oncoming_t_s: float | None = None  # a vehicle last came toward the car while it followed the route (policy.route)
    route_noted: bool = False  # a route steering that is no finite number arrived, and the reasons said so

    @property
    def trusted_steering_deg(self) -> float:
        """The steering held when the road picture is lost: the median of the last calm pictures' (0 before any)."""
        return statistics.median(self.calm_steering) if self.calm_steering else 0.0


class FearGuard:
    """Fuzzy affective safety supervisor around a steering function (frame → degrees, + = left).

    ``steer`` may be None when every Observation brings its ``steering_deg`` (a caller that already holds the angle:
    a Donkey pilot, an RL agent); a frame without one is then a fault.

    A ``FrameSteering`` (``HoughLaneSteering``) shares its frame pipeline: each frame is analysed once,
    for the cues and the steering. Its camera is the supervisor's camera; giving another one is a
    ``ValueError`` (``camera=None`` takes the steering's).

    ``steering_deadline_s`` (off by default): the steering function runs in a worker thread and an
    answer later than this counts as a fault. It trades determinism for timeliness — whether a slow
    answer makes the deadline depends on the machine's load — so replays and tests leave it off.

    ``track`` (a ``TrackProfile`` or the path of one written by ``fearguard learn``): each frame is also read against
    the car's own recordings — the familiarity cue, and the light and lane as this track has them (docs/learning.md).
    Without one the familiarity cue does not apply (1); given ``Cues`` always count as given.
    """

    def __init__(
        self,
        steer: SteeringFunction | None,
        rules: RuleBase | str | None = None,
        vehicle: VehicleLimits | None = None,
        camera: CameraModel | None = None,
        steering_deadline_s: float | None = None,
        track: TrackProfile | str | Path | None = None,
    ) -> None:
        self.steer = steer
        self.rules = rules if isinstance(rules, RuleBase) else load_rules(rules)
        self.vehicle = vehicle if vehicle is not None else VehicleLimits()
        self._frame_steering = steer if isinstance(steer, FrameSteering) else None
        shared = self._frame_steering.pipeline if self._frame_steering is not None else None
        self.track = load_track(track) if isinstance(track, str | Path) else track
        self.perception = Perception(self.vehicle, camera, shared, track=self.track, normal_band=self.rules.brightness_band,
                                     occlusion_calm=self._occlusion_calm())
        self.camera = self.perception.camera
        self._deadline = SteeringDeadline(steering_deadline_s) if steering_deadline_s is not None else None
        self._state = _State()

    def _occlusion_calm(self) -> float:
        """The top of the rule file's calm occlusion (a track profile maps normal driving's occlusion onto it)."""
        var = self.rules.variables.get("occlusion")
        return var.calm_core_top(0.0) if var is not None else 0.0

    def reset(self) -> None:
        """Forget all history (mode, timers, speed-limit ramp, trackers)."""
        self._state = _State()
        self.perception.reset()

    def step(self, obs: Observation) -> Command:
        """One frame: never raises; any fault becomes a safe command with a reason."""
        try:
            return self._step(obs)
        except Exception as exc:  # last line of defence: a bug must not crash the car's loop
            return self._fault_command(obs, f"fault: internal error {describe_exception(exc)}", None)

    # -- the frame ----------------------------------------------------------------------------
    def _step(self, obs: Observation) -> Command:
        if not isinstance(obs, Observation):
            return self._fault_command(obs, f"fault: expected an Observation, got {type(obs).__name__}", None)
        t = finite_reading(obs.t_s)
        st = self._state
        if t is None:
            return self._fault_command(obs, f"fault: time t_s={describe(obs.t_s)} is not a finite number", None)
        if st.last_t_s is not None and t <= st.last_t_s:
            return self._fault_command(obs, f"fault: time did not increase ({st.last_t_s:.3f} s → {t:.3f} s)", t)
        if obs.cues is not None and not isinstance(obs.cues, Cues):  # e.g. a dict: not cues the caller meant to be read
            return self._fault_command(obs, f"fault: Observation.cues must be a fearguard.Cues (or None), got "
                                            f"{type(obs.cues).__name__}", t)
        stall = self._watchdog(t)
        cues, cue_notes, perceived, lead = self._cues(obs)
        result = self.rules.evaluate(cues)
        steering, steer_fault = self._steering(obs, perceived, cue_notes)
        fault = stall or steer_fault or self._oscillation(steering)
        if fault:
            return self._fault_command(obs, fault, t, cues, result, perceived)
        return self._decide(obs, t, cues, result, steering, cue_notes, lead, perceived)

    def _watchdog(self, t: float) -> str:
        """A frame later than max(N typical periods, the configured age) after the last one: the input stalled."""
        st = self._state
        if st.last_t_s is None:
            return ""
        gap = t - st.last_t_s
        allowed = watchdog_s(statistics.median(st.periods_s) if st.periods_s else None, self.rules.policy)
        if gap > allowed:
            return f"fault: input stalled {gap:.1f} s (watchdog {allowed:.1f} s)"
        st.periods_s.append(gap)
        return ""

    def _oscillation(self, steering: float) -> str:
        """An estimator flipping between large angles of opposite sign frame after frame is a fault."""
        st, cfg = self._state, self.rules.policy
        st.raw_steering.append(steering)
        while len(st.raw_steering) > cfg.oscillation_flips + 1:
            st.raw_steering.popleft()
        if oscillating(st.raw_steering, cfg):
            return (f"fault: steering estimator oscillates ({cfg.oscillation_flips} sign flips in a row beyond "
                    f"±{cfg.oscillation_deg:.0f} deg: {', '.join(f'{a:+.0f}' for a in st.raw_steering)} deg)")
        return ""

    def _cues(self, obs: Observation) -> tuple[Cues, list[str], Perceived | None, Lead | None]:
        """Cues from the observation (given, or measured by perception); absent sensors neutral, failed ones worst."""
        notes: list[str] = []
        perceived: Perceived | None = None
        lead = obs.lead if isinstance(obs.lead, Lead) else None  # a LeadBox is perception's (Observation.lead_box)
        if isinstance(obs.cues, Cues):
            raw = [getattr(obs.cues, name) for name in CUE_NAMES]
            values = obs.cues.values()
            values[OBSTACLE_RANGE] = self._given_range(values[OBSTACLE_RANGE], notes)
            if not self.vehicle.has_qr_localisation:
                values[QR_STALENESS] = 0.0  # no QR localisation on this car: the cue does not apply
        else:  # perception owns absent sensors: no range sensor is the camera's ground-plane range of an object, or inf
            perceived = self.perception.perceive(obs)
            values, lead = perceived.cues.values(), perceived.lead
            raw = list(values)
            notes.extend(perceived.alerts)
        for name, given, v in zip(CUE_NAMES, raw, values, strict=True):
            note = unknown_note(name, given) or unknown_note(name, v)
            if note:
                notes.append(note)
        return Cues(*values), notes, perceived, lead

    def _given_range(self, range_m: float, notes: list[str]) -> float:
        """A range the caller gave, as policy and fear read it: a finite reading always counts, whatever the vehicle
        declares; one beyond the sensor's maximum counts as "nothing within the maximum" (never as that many metres).

        On a car that declares no range sensor only ``inf`` means "nothing known in range"; a finite reading says there
        is a sensor after all (a one-line note the first time). Unknown values stay unknown (worst)."""
        v, st = self.vehicle, self._state
        if not (0.0 <= range_m < math.inf):
            return range_m
        if not v.has_ultrasonic and not st.range_noted:
            st.range_noted = True
            notes.append(f"obstacle_range_m {range_m:.4g} m given on a car that declares no range sensor "
                         f"(has_ultrasonic = false): counted")
        return clamp_to_sensor(range_m, v, notes)

    def _steering(self, obs: Observation, perceived: Perceived | None, notes: list[str]) -> tuple[float, str]:
        """The wrapped estimator's angle: given in the observation (the caller holds it), else from this frame's analysis
        for a FrameSteering, else the steering function on the frame — each validated the same way."""
        if obs.steering_deg is not None:
            return self._validated(obs.steering_deg, "the given steering_deg", notes)
        if self.steer is None:
            return 0.0, "fault: no steering: give Observation.steering_deg or a steering function"
        analysis = perceived.analysis if perceived is not None else None
        if self._frame_steering is not None and analysis is not None:
            call, arg = self._frame_steering.steer_from, analysis
        else:
            call, arg = self.steer, obs.frame
        try:
            if self._deadline is not None:
                raw, late = self._deadline.call(call, arg)
                if late:
                    return 0.0, late
            else:
                raw = call(arg)
        except Exception as exc:  # the wrapped estimator is foreign code: any failure is a fault
            return 0.0, f"fault: steering function raised {describe_exception(exc)}"
        return self._validated(raw, "steering function returned", notes)

    def _validated(self, raw: object, what: str, notes: list[str]) -> tuple[float, str]:
        """A finite angle, held within the vehicle's steering range (a note says so: the wheels stop at full lock, as a
        route beyond it is clipped — invariant 7's physical limit), or a fault saying what arrived."""
        value = finite_reading(raw)
        if value is None:
            says = f"{what} {describe(raw)}" if what.endswith("returned") else f"{what} is {describe(raw)}"
            return 0.0, f"fault: {says}, not a finite number"
        limit = self.vehicle.max_steering_deg
        if abs(value) > limit:
            held = math.copysign(limit, value)
            notes.append(f"steering {value:+.1f} deg beyond the ±{limit:.1f} deg range: held at full lock {held:+.1f} deg")
            return held, ""
        return value, ""

    def _frame_calm(self, cues: Cues, perceived: Perceived | None) -> bool:
        """Is this frame's own lane reading calm, as the cue (the median of the last frames' confidences) is? The
        steering held when the picture is lost must not come from the odd frame the median hides: a spurious line
        (agreement 0, the frame's own confidence 0.00) under a calm median steered -5.8 deg, and held as the markings
        ended it took the car out of the lane (markings_end, seed 41). Fear never falls as the confidence drops, so only
        a frame below the median is evaluated again."""
        analysis = perceived.analysis if perceived is not None else None
        own = analysis.evidence.confidence if analysis is not None and analysis.evidence is not None else math.nan
        if not math.isfinite(own) or own >= cues.lane_confidence:
            return True
        return self._road_calm(self.rules.evaluate(replace(cues, lane_confidence=own)))

    def _road_calm(self, result: FearResult) -> bool:
        """The road picture is calm: its fear below CAUTION's."""
        return result.cause_fears[Cause.ROAD] < self.rules.policy.caution_fear

    def _route(self, obs: Observation, notes: list[str]) -> float | None:
        """The route steering given (None: none), within the steering range; one that is no finite number is no route,
        and the reasons say so once."""
        value = obs.route_deg(self.vehicle.max_steering_deg)
        if value is None and obs.route_steering_deg is not None and not self._state.route_noted:
            self._state.route_noted = True
            notes.append(f"route_steering_deg {describe(obs.route_steering_deg)} is not a finite number: no route followed")
        return value

    def _decide(
        self, obs: Observation, t: float, cues: Cues, result: FearResult, steering: float, notes: list[str],
        lead: Lead | None, perceived: Perceived | None,
    ) -> Command:
        """Advance the state by one frame and answer: the named steps of ``policy.decision`` over this frame's facts."""
        st, v, cfg = self._state, self.vehicle, self.rules.policy
        speed, speed_now = measured_speed(obs.speed_mps, v)
        range_m = self._range_for_policy(cues)
        closing = self._closing_speed(obs, t, range_m, perceived)
        result, moving = self._moving_object(cues, result, range_m, speed, closing)
        imminent = imminent_collision(range_m, speed_now, v, closing)
        clear_m = max(self._clear_m(cues, perceived, range_m), st.stop_line.clear_left_m())  # crossing: as known at the stop
        over = frozenset(c for c, f in result.cause_fears.items() if f >= cfg.emergency_enter_fear)
        over |= {Cause.COLLISION} if imminent else set()
        path_doubt = creep_clearance(clear_m, cfg, v)  # "" when the path ahead is known clear for a creep
        # how fast the car goes now: measured, else the limit it was last given (never told to move: standing)
        now_mps = speed if speed is not None else (st.limit_mps if st.limit_mps is not None else 0.0)
        dt = 0.0 if st.last_t_s is None else t - st.last_t_s
        road_calm = self._road_calm(result)
        route_deg = self._route(obs, notes)
        object_mps = speed - closing if speed is not None and closing is not None and math.isfinite(range_m) else None
        route = next_route(st.routed_m, route_deg, road_calm, clear_m, path_doubt, speed, dt, cfg, v, t_s=t,
                           object_speed_mps=object_mps, oncoming_t_s=st.oncoming_t_s)
        st.routed_m, st.oncoming_t_s = route.routed_m, route.oncoming_t_s
        grace = self._grace_s(over, imminent, cues, path_doubt, now_mps, lead, route.following)
        st.mode, event = next_mode(st.mode, result.fear, t, at_once=imminent, cfg=cfg, cause_fears=result.cause_fears, over=over,
                                   grace_s=grace)
        fear_limit = fear_speed_mps(result.fear, self.rules.level_anchors, cfg, v)
        envelope = envelope_step(range_m, speed, closing, v)
        cause = self._dominant_cause(result, range_m)
        reasons = [f"fear {result.fear:.2f} ({result.level.name}), dominant cause {cause.value}", *moving]
        lane_now = perceived.lane_steering_deg if perceived is not None else None
        check = self._lane_check(perceived, steering, speed_now, route_deg) if road_calm else None
        choice = lane_step(check, st.estimator_distrusted, steering, lane_now, st.trusted_steering_deg, cfg, v)
        st.estimator_distrusted = choice.distrusted
        wanted, strategy = choice.steering_deg, Strategy.PASS_THROUGH
        follow_cap, follow_why = follow_step(range_m, speed, closing, cfg, v)
        reasons.extend([follow_why] if follow_why else [])
        caps = [fear_limit, envelope.speed_mps, choice.cap_mps, follow_cap, self._grace_cap(grace, t, reasons, path_doubt, now_mps)]
        if route.why and (st.mode.mode is not Mode.EMERGENCY or not route.following):  # in EMERGENCY its plan steers
            caps.append(route.cap_mps if st.mode.mode is not Mode.EMERGENCY else math.inf)
            reasons.append(route.why)
        line_m = perceived.stop_line_m if perceived is not None else None
        st.stop_line, line_cap, line_why = next_stop_line(st.stop_line, line_m, speed_now, t, dt, cfg, v, clear_m)
        caps.append(line_cap)
        reasons.extend([line_why] if line_why else [])
        mode = Mode.CAUTION if choice.caution and st.mode.mode is Mode.NORMAL else st.mode.mode
        reasons.extend([choice.reason] if choice.reason else [])
        if st.mode.mode is Mode.EMERGENCY:
            plan = self._emergency(result, lead, imminent, path_doubt, cues, perceived, t, dt, speed_now, wanted, steering,
                                   route_deg, route.cap_mps if route.following else None)
            strategy, cause, wanted = plan.strategy, plan.cause or cause, plan.steering_deg
            caps.append(plan.cap_mps)
            reasons.extend(plan.reasons)
        else:
            st.recovery = Recovery()  # a new EMERGENCY starts with the full re-acquisition budget
            if road_calm and self._frame_calm(cues, perceived):
                st.calm_steering.append(wanted)  # the road picture is calm: remember its steering (held if it is lost)
            elif route.steering_deg is not None:  # (a frame the median hides is in doubt too)
                wanted = route.steering_deg  # the picture in doubt, the route known: its steering (the reason is the route's)
            elif not choice.caution:
                wanted, why = doubt_step(result.cause_fears[Cause.ROAD], wanted, st.trusted_steering_deg, cfg)
                reasons.extend([why] if why else [])
        out_steering = self._steer_out(wanted, dt, reasons)
        lateral = lateral_speed_mps(max(abs(steering), abs(out_steering)), v)
        caps.append(lateral)
        reasons.extend(motion_reasons(imminent, envelope.speed_mps, range_m, speed_now, speed, closing, v))
        reasons.extend([event] if event else [])
        target = min(caps)
        limit = max(0.0, rate_limited_mps(st.limit_mps if st.limit_mps is not None else first_limit_mps(speed, v), target, dt, cfg))
        st.last_t_s, st.limit_mps = t, limit
        reasons.append(limit_reason(limit, fear_limit, envelope.speed_mps, target, envelope.seen_m, lateral, follow_cap))
        reasons.extend(rule_reasons(result, mode, perceived.facts if perceived is not None else ()))
        reasons.extend(notes)
        return Command(
            steering_deg=out_steering, speed_limit_mps=limit, mode=mode, strategy=strategy, fear=result.fear,
            fear_level=result.level, cues=cues, reasons=tuple(reasons), fear_limit_mps=fear_limit, envelope_mps=envelope.speed_mps,
            cause=cause, perceived=perceived, closing_speed_mps=math.nan if closing is None else closing,
        )

    def _emergency(
        self, result: FearResult, lead: Lead | None, imminent: bool, unclear: str, cues: Cues, perceived: Perceived | None,
        t: float, dt: float, speed_now: float, wanted: float, steering: float, route_deg: float | None = None,
        route_cap: float | None = None,
    ) -> EmergencyChoice:
        """In EMERGENCY: advance the recovery (a creep after a road-picture stop, when the path ahead is known clear), then
        the plan of the active causes. ``unclear``: why the path is not known clear for a creep ("" when it is). A route
        steering (``route_deg``) steers a creep in place of the wrapped estimator, a creep on it is not blind, and goes at
        the route's cap (``route_cap``), not at crawl speed."""
        st, cfg, v = self._state, self.rules.policy, self.vehicle
        active = active_causes(result.cause_fears, st.mode, cfg)
        road_stop = recovery_eligible(st.mode, active, lead, imminent)
        confidence = finite_reading(cues.lane_confidence)
        seen = confidence is not None and confidence >= cfg.recovery_min_confidence  # a lane this faint steers nothing
        st.recovery, in_sight = lane_in_sight(st.recovery, t, seen)  # a flicker of the lane is no blind stretch
        # a boundary found frame after frame steers a creep even when the picture as a whole is not trusted (glare)
        guided = perceived is not None and perceived.lane_guide >= cfg.recovery_min_guide
        routed = route_deg is not None and cfg.route_blind_m > 0.0 and st.routed_m < cfg.route_blind_m  # its budget shared
        blind = not (in_sight or routed)
        st.recovery, creep = next_recovery(st.recovery, road_stop and not unclear, t, dt, speed_now, cfg,
                                           blind=blind, guided=guided, routed=routed)
        seen = seen or lane_reacquired(st.recovery, t, cfg)  # the re-acquired lane steers the creep and is no blind stretch
        plan = emergency_plan(result.cause_fears, st.mode, lead, st.trusted_steering_deg, cfg, v, creep, t,
                              route_cap if routed else None)
        status = "" if creep else recovery_status(st.recovery, road_stop, cfg, t, unclear, blind=blind)
        # a route is the known way across a junction, where the lane seen now may be the crossing road's
        lane_now = perceived.lane_steering_deg if perceived is not None and seen and not routed else None
        estimator = route_deg if routed else None if st.estimator_distrusted else steering
        bound = v.max_steering_deg if routed else cfg.recovery_creep_max_deg  # a route is a known path, not a guess
        return emergency_step(plan, creep, lane_now, wanted, status, estimator, bound)

    def _moving_object(self, cues: Cues, result: FearResult, range_m: float, speed: float | None,
                       closing: float | None) -> tuple[FearResult, tuple[str, ...]]:
        """An object ahead that keeps moving (a measured range, a known speed and closing speed) is read by collision fear
        as the standing obstacle that would demand the same braking (``decision.fear_range_m``): the rules judge that."""
        if unknown_note("obstacle_range_m", cues.obstacle_range_m) is not None:
            return result, ()
        as_standing = fear_range_m(range_m, speed, closing, self.rules.policy.moving_object_min_mps)
        if as_standing == range_m:
            return result, ()
        lead_v = lead_speed_mps(speed, closing)
        read = f"standing at {as_standing:.2f} m" if math.isfinite(as_standing) else "nothing in range (the gap is not closing)"
        why = (f"the object ahead at {range_m:.2f} m moves at {lead_v:.2f} m/s: collision fear reads the braking it demands, "
               f"as {read}")
        return self.rules.evaluate(replace(cues, obstacle_range_m=as_standing)), (why,)

    def _clear_m(self, cues: Cues, perceived: Perceived | None, range_m: float) -> float:
        """How far ahead the path is known clear: perception's answer for a frame; at cue level the range given (with
        nothing in range: as far as a range sensor the car declares reaches; nothing known without one)."""
        if perceived is not None:
            return perceived.clear_m
        if unknown_note("obstacle_range_m", cues.obstacle_range_m) is not None:
            return 0.0
        if math.isfinite(range_m):
            return range_m
        return self.vehicle.ultrasonic_max_range_m if self.vehicle.has_ultrasonic else 0.0

    def _grace_s(
        self, over: frozenset[Cause], imminent: bool, cues: Cues, path_doubt: str, now_mps: float, lead: Lead | None,
        routed: bool = False,
    ) -> float:
        """A road picture that flickers is CAUTION, not a string of emergencies (issue 35): entering EMERGENCY for the road
        picture alone, measured, waits ``road_enter_s``. With the path ahead known clear the car may go on at the doubt
        speed meanwhile; with nothing known about it (no range sensor, no camera object search) only a car already
        moving gets the wait, and only to slow down (``_grace_cap``): a standing car does not start on a picture in
        doubt. An unknown picture (a lost camera) and one whose brightness alone demands an emergency (black, or
        blinding glare) are no flicker. With a lead to follow there is no wait: following it is the better guide than
        a picture in doubt. Following the route (``routed``: ``policy.route``, the path known clear), the wait lasts while
        it does, a lead or not."""
        cfg = self.rules.policy
        measured = all(unknown_note(name, getattr(cues, name)) is None for name in ("lane_confidence", "brightness", "occlusion"))
        following = lead is not None and lead.usable
        if over != {Cause.ROAD} or imminent or not measured:
            return 0.0
        light_alone = replace(Cues(*calm_values(self.rules.brightness_band)), brightness=cues.brightness)
        if self.rules.evaluate(light_alone).fear >= cfg.emergency_enter_fear:
            return 0.0
        if routed:  # the route is the better guide than a lead, which may cross the junction elsewhere
            return math.inf
        if following or (path_doubt and not now_mps > 0.0):
            return 0.0
        if self._state.stop_line.crossed_m is not None and not path_doubt:
            return math.inf  # crossing after a served stop line: the markings are missing there by design
        return cfg.road_enter_s

    def _grace_cap(self, grace: float, t: float, reasons: list[str], path_doubt: str, now_mps: float) -> float:
        """While a grace runs (the picture untrusted for enter_frames and more, not yet for ``road_enter_s``): CAUTION at
        ``road_doubt_fraction`` of the top speed; with nothing known about the path ahead, never faster than now (the
        measured speed; unmeasured: the limit last given, which the car does not exceed)."""
        st, cfg = self._state, self.rules.policy
        if not (grace > 0.0 and st.mode.mode is not Mode.EMERGENCY and st.mode.frames_over >= cfg.enter_frames
                and st.mode.over_since_s is not None):
            return math.inf
        cap = cfg.road_doubt_fraction * self.vehicle.max_speed_mps
        if math.isinf(grace) and st.stop_line.crossed_m is None:
            return math.inf  # following the route: its own cap and reason (policy.route)
        if math.isinf(grace):
            reasons.append(f"crossing after a stop line, the markings missing, the path clear as seen at the stop: {cap:.2f} m/s")
            return cap
        waited = f"road picture not trusted for {t - st.mode.over_since_s:.1f} of {grace:g} s"
        if path_doubt:
            cap = min(cap, now_mps)
            reasons.append(f"{waited}, {path_doubt}: slowing, never faster than now ({cap:.2f} m/s), before an emergency "
                           "(a flicker is not one)")
        else:
            reasons.append(f"{waited} with the path clear: slowing to {cap:.2f} m/s before an emergency (a flicker is not one)")
        return cap

    def _steer_out(self, wanted: float, dt: float, reasons: list[str]) -> float:
        """The steering answered: within ±max, and the smallest change from the last answer the rate limit allows."""
        st, v = self._state, self.vehicle
        wanted = min(max(wanted, -v.max_steering_deg), v.max_steering_deg)
        out = rate_limited_steering_deg(st.out_steering_deg, wanted, dt, v)
        if out != wanted:
            reasons.append(f"steering rate limit {v.max_steering_rate_dps:.0f} deg/s: {out:+.1f} deg toward {wanted:+.1f} deg")
        st.out_steering_deg = out
        return out

    def _closing_speed(self, obs: Observation, t: float, range_m: float, perceived: Perceived | None) -> float | None:
        """How fast the obstacle comes closer (m/s, + = closing): given, from the range filter, or from successive ranges.

        None when unknown (the envelope then treats the obstacle as standing). Never more opening than the
        vehicle's closing-speed bound: a garbage rate cannot buy a larger envelope. A frame without a range (a camera's
        box lost for a frame) does not forget the object: the next reading continues its ranges if it is the same
        object (``same_object_after_gap``).
        """
        st, bound = self._state, self.vehicle.max_closing_speed_mps
        if not math.isfinite(range_m):
            st.range_missed = True  # nothing ahead this frame: the ranges before age out of the closing window by themselves
            return None
        if st.range_missed and st.ranges and not same_object_after_gap(st.ranges[-1], t, range_m):
            st.ranges.clear()  # another object, or the same one gone longer than the window: its speed is unknown
        st.range_missed = False
        shift = perceived.range_shift_m if perceived is not None else 0.0
        if shift < 0.0:  # the camera now ranges the same object better: the earlier ranges were that much too far
            st.ranges = deque(((ts, r + shift) for ts, r in st.ranges), maxlen=RANGE_MEMORY)
        st.ranges.append((t, range_m))
        given = finite_reading(getattr(obs, "range_rate_mps", None))
        estimate = perceived.range_estimate if perceived is not None else None
        if given is not None:
            closing: float | None = -given
        elif estimate is not None and math.isfinite(estimate.closing_speed_mps):
            closing = estimate.closing_speed_mps
        else:
            closing = closing_speed_from_ranges(st.ranges, t, self.vehicle.lead_max_decel_mps2)
        return None if closing is None else max(closing, -bound)

    def _lane_check(self, perceived: Perceived | None, steering: float, speed_now: float, route: float | None) -> LaneCheck | None:
        """The lane-keeping plausibility check on this frame's ground-plane lane (perception measures it: frames with a
        camera model that knows its mounting height only); a departure the route asks for too is intended."""
        if perceived is None or perceived.analysis is None:
            return None
        cfg = self.rules.policy
        return lane_check(perceived.lane, steering, speed_now, self.vehicle, cfg.lane_check_lookahead_s, cfg.lane_check_min_deg,
                          route if cfg.route_blind_m > 0.0 else None)

    def _dominant_cause(self, result: FearResult, range_m: float) -> Cause:
        """The cause with the largest fear among those that can apply to this car: a collision needs a range sensor or
        a range (given, seen by the camera, or unknown); localisation needs QR localisation. Ties: road first, the one
        every car has; then collision, then localisation."""
        applies = [Cause.ROAD]
        if self.vehicle.has_ultrasonic or not math.isinf(range_m):
            applies.append(Cause.COLLISION)
        if self.vehicle.has_qr_localisation:
            applies.append(Cause.LOCALISATION)
        return max(applies, key=lambda c: (result.cause_fears.get(c, 0.0), -applies.index(c)))

    @staticmethod
    def _range_for_policy(cues: Cues) -> float:
        """Obstacle range for the envelope, unknown meaning what it means for fear (worst: 0); a float whatever Real the
        caller gave (a Fraction cannot be formatted into a reason)."""
        return float(worst_filled(cues.values(), 0.0)[0][OBSTACLE_RANGE])

    # -- faults ---------------------------------------------------------------------------------
    def _fault_command(
        self, obs: object, why: str, t: float | None, cues: Cues | None = None, result: FearResult | None = None,
        perceived: Perceived | None = None,
    ) -> Command:
        """EMERGENCY/STOP at once, steering held at the last trusted angle; the clock restarts at t."""
        st = self._state
        prev_t = st.last_t_s
        if t is not None:
            st.mode, _ = next_mode(st.mode, 1.0, t, at_once=True, cfg=self.rules.policy, fault=True)
            st.last_t_s = t
        else:  # no usable clock: latch the stop without touching the timers
            st.mode = replace(st.mode, mode=Mode.EMERGENCY, fault=True)
        st.limit_mps = 0.0
        cues = cues if cues is not None else Cues(*([math.nan] * len(CUE_NAMES)))
        fear = result.fear if result is not None else 1.0
        level = result.level if result is not None else FearLevel.VERY_HIGH
        dt = 0.0 if t is None or prev_t is None else t - prev_t
        extra: list[str] = []
        held = self._steer_out(st.trusted_steering_deg, dt, extra)
        reasons = (why, f"EMERGENCY STOP: fault, holding {held:+.1f} deg", *extra)
        return Command(
            steering_deg=held, speed_limit_mps=0.0, mode=Mode.EMERGENCY, strategy=Strategy.STOP, fear=fear, fear_level=level,
            cues=cues, reasons=reasons, fear_limit_mps=0.0, envelope_mps=0.0, perceived=perceived,
        )
