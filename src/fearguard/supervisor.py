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
from collections.abc import Callable
from dataclasses import dataclass, field, replace
from typing import Any

from fearguard.camera import CameraModel
from fearguard.cues import CUE_NAMES, OBSTACLE_RANGE, QR_STALENESS, Cues, worst_filled
from fearguard.errors import describe, describe_exception
from fearguard.fear import Cause, FearLevel, FearResult
from fearguard.fuzzy.loader import load_rules
from fearguard.fuzzy.rulebase import RuleBase
from fearguard.observation import Lead, Observation  # Observation re-exported: fearguard.supervisor.Observation keeps working
from fearguard.perception import FrameSteering, Perceived, Perception
from fearguard.policy import (
    Mode,
    ModeState,
    Strategy,
    emergency_plan,
    envelope_speed_mps,
    fear_speed_mps,
    imminent_collision,
    next_mode,
    rate_limited_mps,
)
from fearguard.readings import finite_reading
from fearguard.vehicle import VehicleLimits

SteeringFunction = Callable[[Any], float]
TOP_RULES_IN_REASONS = 3  # [-] rules quoted in a command's reasons


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


@dataclass
class _State:
    mode: ModeState = field(default_factory=ModeState)
    last_t_s: float | None = None
    limit_mps: float | None = None
    trusted_steering_deg: float = 0.0  # last steering while the road was trusted, held when it is lost


class FearGuard:
    """Fuzzy affective safety supervisor around a steering function (frame → degrees, + = left).

    A ``FrameSteering`` (``HoughLaneSteering``) shares its frame pipeline: each frame is analysed once,
    for the cues and the steering. Its camera is the supervisor's camera; giving another one is a
    ``ValueError`` (``camera=None`` takes the steering's).
    """

    def __init__(
        self,
        steer: SteeringFunction,
        rules: RuleBase | str | None = None,
        vehicle: VehicleLimits | None = None,
        camera: CameraModel | None = None,
    ) -> None:
        self.steer = steer
        self.rules = rules if isinstance(rules, RuleBase) else load_rules(rules)
        self.vehicle = vehicle if vehicle is not None else VehicleLimits()
        self._frame_steering = steer if isinstance(steer, FrameSteering) else None
        shared = self._frame_steering.pipeline if self._frame_steering is not None else None
        self.perception = Perception(self.vehicle, camera, shared)
        self.camera = self.perception.camera
        self._state = _State()

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
        cues, cue_notes, perceived, lead = self._cues(obs)
        result = self.rules.evaluate(cues)
        steering, steer_fault = self._steering(obs, perceived)
        if steer_fault:
            return self._fault_command(obs, steer_fault, t, cues, result, perceived)
        return self._decide(obs, t, cues, result, steering, cue_notes, lead, perceived)

    def _cues(self, obs: Observation) -> tuple[Cues, list[str], Perceived | None, Lead | None]:
        """Cues from the observation (given, or measured by perception); absent sensors neutral, failed ones worst."""
        notes: list[str] = []
        perceived: Perceived | None = None
        lead = obs.lead if isinstance(obs.lead, Lead) else None
        if isinstance(obs.cues, Cues):
            values = obs.cues.values()
        else:
            perceived = self.perception.perceive(obs)
            values, lead = perceived.cues.values(), perceived.lead
            notes.extend(perceived.alerts)
        if not self.vehicle.has_ultrasonic:
            values[OBSTACLE_RANGE] = math.inf  # no sensor: nothing known in range, declared not faked
        if not self.vehicle.has_qr_localisation:
            values[QR_STALENESS] = 0.0  # no QR localisation on this car: the cue does not apply
        for name, v in zip(CUE_NAMES, values, strict=True):
            if not isinstance(v, float) or math.isnan(v):
                notes.append(f"{name} unknown: counted as its worst value")
        return Cues(*values), notes, perceived, lead

    def _steering(self, obs: Observation, perceived: Perceived | None) -> tuple[float, str]:
        """The wrapped steering's angle: from this frame's analysis for a FrameSteering, else from the frame."""
        analysis = perceived.analysis if perceived is not None else None
        try:
            if self._frame_steering is not None and analysis is not None:
                raw = self._frame_steering.steer_from(analysis)
            else:
                raw = self.steer(obs.frame)
        except Exception as exc:  # the wrapped estimator is foreign code: any failure is a fault
            return 0.0, f"fault: steering function raised {describe_exception(exc)}"
        value = finite_reading(raw)
        if value is None:
            return 0.0, f"fault: steering function returned {describe(raw)}, not a finite number"
        limit = self.vehicle.max_steering_deg
        if abs(value) > limit:
            return 0.0, f"fault: steering {value:+.1f} deg outside ±{limit:.1f} deg"
        return value, ""

    def _decide(
        self, obs: Observation, t: float, cues: Cues, result: FearResult, steering: float, notes: list[str],
        lead: Lead | None, perceived: Perceived | None,
    ) -> Command:
        st, v, cfg = self._state, self.vehicle, self.rules.policy
        speed = finite_reading(obs.speed_mps)
        speed_now = v.max_speed_mps if speed is None or speed < 0 else speed  # unknown speed: assume the worst
        range_m = self._range_for_policy(cues)
        imminent = imminent_collision(range_m, speed_now, v)
        over = frozenset(c for c, f in result.cause_fears.items() if f >= cfg.emergency_enter_fear)
        over |= {Cause.COLLISION} if imminent else set()
        st.mode, event = next_mode(st.mode, result.fear, t, at_once=imminent, cfg=cfg, cause_fears=result.cause_fears, over=over)
        fear_limit = fear_speed_mps(result.fear, self.rules.level_anchors, cfg, v)
        envelope = envelope_speed_mps(range_m, v)
        target = min(fear_limit, envelope)
        mode, strategy, out_steering = st.mode.mode, Strategy.PASS_THROUGH, steering
        reasons = [f"fear {result.fear:.2f} ({result.level.name}), dominant cause {result.dominant_cause.value}"]
        if st.mode.mode is Mode.EMERGENCY:
            plan = emergency_plan(result.cause_fears, st.mode, lead, st.trusted_steering_deg, cfg, v)
            strategy, target = plan.strategy, min(target, plan.cap_mps)
            if plan.steering_deg is not None:
                out_steering = plan.steering_deg
            reasons.append(f"EMERGENCY {strategy.name}: {plan.why}")
        elif result.cause_fears[Cause.ROAD] < cfg.caution_fear:
            st.trusted_steering_deg = steering  # the road picture is calm: remember its steering (held if it is lost)
        if imminent:
            reasons.append(f"imminent collision: obstacle at {range_m:.2f} m, cannot stop from {speed_now:.2f} m/s")
        if event:
            reasons.append(event)
        dt = 0.0 if st.last_t_s is None else t - st.last_t_s
        previous = st.limit_mps if st.limit_mps is not None else min(speed_now if speed is not None else 0.0, v.max_speed_mps)
        limit = max(0.0, rate_limited_mps(previous, target, dt, cfg))
        st.last_t_s, st.limit_mps = t, limit
        reasons.append(self._limit_reason(limit, fear_limit, envelope, target, range_m))
        if result.level > FearLevel.VERY_LOW or mode is not Mode.NORMAL:
            reasons.extend(f"rule {text!r} fired {s:.2f}" for text, s in result.top_rules(TOP_RULES_IN_REASONS))
            reasons.extend(perceived.facts if perceived is not None else ())
        reasons.extend(notes)
        return Command(
            steering_deg=out_steering, speed_limit_mps=limit, mode=mode, strategy=strategy, fear=result.fear,
            fear_level=result.level, cues=cues, reasons=tuple(reasons), fear_limit_mps=fear_limit, envelope_mps=envelope,
            cause=result.dominant_cause, perceived=perceived,
        )

    @staticmethod
    def _range_for_policy(cues: Cues) -> float:
        """Obstacle range for the envelope, unknown meaning what it means for fear (worst: 0)."""
        return worst_filled(cues.values(), 0.0)[0][OBSTACLE_RANGE]

    @staticmethod
    def _limit_reason(limit: float, fear_limit: float, envelope: float, target: float, range_m: float) -> str:
        if limit < target - 1e-12:
            return f"speed limit {limit:.2f} m/s: rising at the comfort acceleration toward {target:.2f} m/s"
        if envelope <= fear_limit and envelope <= target + 1e-12 and not math.isinf(envelope):
            return f"speed limit {limit:.2f} m/s: stopping envelope for an obstacle at {range_m:.2f} m"
        if fear_limit <= target + 1e-12:
            return f"speed limit {limit:.2f} m/s: set by fear"
        return f"speed limit {limit:.2f} m/s: set by the emergency strategy"

    # -- faults ---------------------------------------------------------------------------------
    def _fault_command(
        self, obs: object, why: str, t: float | None, cues: Cues | None = None, result: FearResult | None = None,
        perceived: Perceived | None = None,
    ) -> Command:
        """EMERGENCY/STOP at once, steering held at the last trusted angle; the clock restarts at t."""
        st = self._state
        if t is not None:
            st.mode, _ = next_mode(st.mode, 1.0, t, at_once=True, cfg=self.rules.policy, fault=True)
            st.last_t_s = t
        else:  # no usable clock: latch the stop without touching the timers
            st.mode = replace(st.mode, mode=Mode.EMERGENCY, fault=True)
        st.limit_mps = 0.0
        cues = cues if cues is not None else Cues(*([math.nan] * len(CUE_NAMES)))
        fear = result.fear if result is not None else 1.0
        level = result.level if result is not None else FearLevel.VERY_HIGH
        held = max(-self.vehicle.max_steering_deg, min(self.vehicle.max_steering_deg, st.trusted_steering_deg))
        reasons = (why, f"EMERGENCY STOP: fault, holding {held:+.1f} deg")
        return Command(
            steering_deg=held, speed_limit_mps=0.0, mode=Mode.EMERGENCY, strategy=Strategy.STOP, fear=fear, fear_level=level,
            cues=cues, reasons=reasons, fear_limit_mps=0.0, envelope_mps=0.0, perceived=perceived,
        )

