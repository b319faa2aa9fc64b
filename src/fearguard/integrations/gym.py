"""A gymnasium shield: fearguard between an agent and the environment, at cue level.

    env = FearGuardShield(gymnasium.make("highway-v0", config={"action": {"type": "ContinuousAction"}}))

For highway-env (detected from the unwrapped environment) the shield builds the observation itself
from the simulator's state, as a radar and a lane map would give it: the range (bumper to bumper) and
range rate of the binding vehicle ahead — of those ahead in the ego lane and in the lanes being entered
(reached within ``LANE_LOOKAHEAD_S`` along the heading now or the one the steering about to be sent gives),
the one with the lowest safe-distance envelope — the ego speed and the env's clock (``env.time``). A
vehicle beside the ego is not ahead. The road picture is perfect in a simulator (lane confidence 1,
brightness mid-band, no occlusion, no QR localisation). The vehicle's numbers are read from the env
(``highway_vehicle``; docs/gym.md). Conventions converted explicitly:

- ContinuousAction is ``[acceleration, steering]`` in [−1, 1], mapped by the env to its
  ``acceleration_range`` (±5 m/s²) and ``steering_range`` (±45°) with **+ = right** (y points down);
  fearguard's steering is degrees with + = left.
- The acceleration is clipped so the speed stays within the limit at the next decision:
  ``a ≤ (limit − v) · policy_frequency`` (the env holds an action for one policy period), never below
  the env's hardest braking.
- **Steering policy:** the agent's steering passes unchanged unless it starts a lane change into a lane
  with a vehicle beside the ego, whose vehicle ahead is inside a safe distance the ego cannot reach
  within one policy period at its hardest braking, or so near that the guard's rules fear it at
  EMERGENCY level: then the shield sends highway-env's own lane-following
  steering toward the current lane and says why in ``info["fearguard_lane_change"]``. fearguard's road
  steering strategies (follow the lead's bearing, hold the last trusted angle) do not apply: a
  simulator's road picture never fails.

The guard is reset on ``reset()`` (a new episode's clock starts again at 0) and every step's
``Command`` is in ``info["fearguard"]``, the action actually sent in ``info["fearguard_action"]``.
Any other environment: pass ``observe(env, obs, info) → fearguard.Observation`` and
``act(action, command, env) → action``.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass, replace
from typing import Any

import gymnasium
import numpy as np

from fearguard.cues import Cues
from fearguard.fuzzy.loader import bundled_rules_path, load_rules
from fearguard.fuzzy.rulebase import RuleBase
from fearguard.policy import envelope_speed_mps
from fearguard.supervisor import Command, FearGuard, Observation
from fearguard.vehicle import VehicleLimits

LANE_LOOKAHEAD_S = 1.0  # [s] a lane the ego's heading reaches within this time is a lane being entered
LOOKAHEAD_FRACTIONS = (0.25, 0.5, 0.75, 1.0)  # [-] of LANE_LOOKAHEAD_S, where the heading is followed
SENSOR_RANGE_M = 150.0  # [m] beyond it nothing ahead is seen (a long-range automotive radar)
ON_LANE_MARGIN_M = 1.0  # [m] beyond the lane's half width a vehicle still counts on it (highway-env's neighbour_vehicles)
DEFAULT_TRAFFIC_DECEL_MPS2 = 6.0  # [m/s²] highway-env IDMVehicle.ACC_MAX, when no other vehicle says
SIM_BRIGHTNESS = 128.0  # [0..255] a simulator's road picture: mid-band, never glare nor dark
HIGHWAY_RULES = "road_car.toml"  # bundled rules for cars at road speeds

Observe = Callable[[Any, Any, dict], Observation]
Act = Callable[[Any, Command, Any], Any]


@dataclass(frozen=True)
class LaneLead:
    """The vehicle ahead in one lane: bumper-to-bumper range and closing speed (+ = getting closer)."""

    lane_index: tuple
    range_m: float
    closing_speed_mps: float
    speed_mps: float


def is_highway_env(env: Any) -> bool:
    """True for a highway-env environment (its unwrapped class lives in the ``highway_env`` package)."""
    base = getattr(env, "unwrapped", env)
    return type(base).__module__.startswith("highway_env.") and hasattr(base, "road") and hasattr(base, "action_type")


def traffic_max_decel_mps2(env: Any) -> float:
    """The hardest braking of the env's other vehicles: their class's ``ACC_MAX`` (IDMVehicle: 6 m/s²)."""
    base = env.unwrapped
    others = [v for v in base.road.vehicles if v is not base.vehicle]
    decels = [float(getattr(type(v), "ACC_MAX", 0.0)) for v in others]
    return max([d for d in decels if d > 0.0], default=DEFAULT_TRAFFIC_DECEL_MPS2)


def highway_vehicle(env: Any) -> VehicleLimits:
    """The ego of a highway-env environment as VehicleLimits, every number read from the env (docs/gym.md).

    highway-env's kinematic bicycle has its axles ``LENGTH`` apart (β = atan(½ tan δ), yaw rate v·sin β / (L/2)),
    applies steering at once and models no tyre grip: the steering rate allows the full range within one
    policy period and the lateral acceleration bound is the one its steering range reaches at top speed, so
    the lateral envelope never brakes for a manoeuvre the env's own vehicles make (its lane changes reach
    ~35 m/s²); a user who wants a real car's limit passes ``vehicle=`` (e.g. ``VehicleLimits.preset("road_car")``'s
    3 m/s²). The vehicle ahead may brake as hard as the env's traffic can (RSS), and the range changes at most
    at the top speed (an obstacle standing, or one at top speed with the ego standing).
    """
    base = env.unwrapped
    action = base.action_type
    ego = base.vehicle
    frequency = float(base.config["policy_frequency"])
    max_speed = float(ego.MAX_SPEED)
    steering_rad = max(abs(float(s)) for s in action.steering_range)
    wheelbase = float(ego.LENGTH)
    return VehicleLimits(
        max_speed_mps=max_speed,
        max_decel_mps2=float(-action.acceleration_range[0]),
        reaction_time_s=1.0 / frequency,  # an action is held for one policy period
        stop_margin_m=2.0,  # [m] bumper-to-bumper gap left at standstill
        max_steering_deg=math.degrees(steering_rad),
        has_ultrasonic=True,  # the range cue is the radar-like range built from the simulator
        has_qr_localisation=False,
        ultrasonic_min_range_m=0.1,
        ultrasonic_max_range_m=SENSOR_RANGE_M,
        wheelbase_m=wheelbase,
        width_m=float(ego.WIDTH),
        max_lateral_accel_mps2=max_speed**2 * math.tan(steering_rad) / wheelbase,
        max_steering_rate_dps=2.0 * math.degrees(steering_rad) * frequency,
        lead_max_decel_mps2=traffic_max_decel_mps2(env),
        max_closing_speed_mps=max_speed,
    )


def lane_vehicles(road: Any, ego: Any, lane_index: tuple) -> list[tuple[float, Any]]:
    """The other vehicles on ``lane_index`` (highway-env's on-lane test, its margin) with the distance of their
    centre ahead of the ego's along that lane (m, − = behind)."""
    lane = road.network.get_lane(lane_index)
    s_ego = lane.local_coordinates(ego.position)[0]
    out = []
    for other in road.vehicles:
        if other is ego:
            continue
        s, lateral = lane.local_coordinates(other.position)
        if lane.on_lane(other.position, s, lateral, margin=ON_LANE_MARGIN_M):
            out.append((float(s - s_ego), other))
    return out


def beside(road: Any, ego: Any, lane_index: tuple) -> bool:
    """A vehicle on ``lane_index`` overlaps the ego along the lane (it is beside it)."""
    return any(abs(ds) < (o.LENGTH + ego.LENGTH) / 2.0 for ds, o in lane_vehicles(road, ego, lane_index))


def lane_lead(road: Any, ego: Any, lane_index: tuple) -> LaneLead | None:
    """The nearest vehicle ahead of the ego in ``lane_index`` within SENSOR_RANGE_M, projected on that lane.

    Ahead means its rear beyond the ego's front: a vehicle beside the ego (overlapping it along the lane, in
    the next lane or straddling the line) is not ahead — braking cannot answer it, and counting it as range 0
    would stop the car on a highway. highway-env's own ``neighbour_vehicles`` picks the nearest centre ahead,
    which may be such a car beside and hide the real one ahead, so the search is done here (same on-lane test).
    """
    gaps = [(ds - (o.LENGTH + ego.LENGTH) / 2.0, o) for ds, o in lane_vehicles(road, ego, lane_index)]
    ahead = [(gap, o) for gap, o in gaps if 0.0 < gap <= SENSOR_RANGE_M]
    if not ahead:
        return None
    gap, front = min(ahead, key=lambda item: item[0])
    lane = road.network.get_lane(lane_index)
    heading = lane.heading_at(lane.local_coordinates(ego.position)[0])
    v_ego = ego.speed * math.cos(ego.heading - heading)
    v_front = front.speed * math.cos(front.heading - heading)
    return LaneLead(lane_index, gap, v_ego - v_front, v_front)


def heading_after(ego: Any, steering_rad: float, dt_s: float) -> float:
    """The ego's heading after holding ``steering_rad`` (highway-env's sign: + = right) for ``dt_s``: its kinematic
    bicycle, β = atan(½ tan δ), yaw rate v·sin β / (L/2)."""
    beta = math.atan(0.5 * math.tan(steering_rad))
    return float(ego.heading + ego.speed * math.sin(beta) / (ego.LENGTH / 2.0) * dt_s)


def entered_lanes(road: Any, ego: Any, steering_rad: float | None = None, period_s: float = 0.0) -> list[tuple]:
    """The lanes the ego reaches within LANE_LOOKAHEAD_S, nearest first (none when it keeps to its lane): along its
    heading now and, given the steering about to be sent, along the heading that steering gives after ``period_s``
    (a lane change is seen the step it is commanded, not one step later when the ego is already across)."""
    lanes: list[tuple] = []
    headings = [float(ego.heading)] + ([heading_after(ego, steering_rad, period_s)] if steering_rad is not None else [])
    for heading in headings:
        direction = np.array([math.cos(heading), math.sin(heading)])
        for fraction in LOOKAHEAD_FRACTIONS:  # sampled so a steep heading does not skip the adjacent lane
            point = ego.position + ego.speed * LANE_LOOKAHEAD_S * fraction * direction
            lane = road.network.get_closest_lane_index(point, heading)
            if lane != ego.lane_index and lane not in lanes:
                lanes.append(lane)
    return lanes


def highway_leads(env: Any, steering_rad: float | None = None) -> list[LaneLead]:
    """The leads in the ego lane and in the lanes being entered (nearest first)."""
    base = env.unwrapped
    road, ego = base.road, base.vehicle
    lanes = [ego.lane_index, *entered_lanes(road, ego, steering_rad, 1.0 / float(base.config["policy_frequency"]))]
    leads = [lead for lane in lanes if (lead := lane_lead(road, ego, lane)) is not None]
    return sorted(leads, key=lambda lead: lead.range_m)


def binding_lead(leads: list[LaneLead], vehicle: VehicleLimits) -> LaneLead | None:
    """The lead whose safe-distance envelope is the lowest (ties: the nearest): the one cue that keeps every lead
    at its RSS distance, since the envelope of the one given is the smallest over all of them."""
    return min(leads, key=lambda lead: (envelope_speed_mps(lead.range_m, vehicle, lead.speed_mps), lead.range_m), default=None)


def sim_cues(range_m: float) -> Cues:
    """A simulator's cues: a perfect road picture, the range given, no QR localisation to go stale."""
    return Cues(lane_confidence=1.0, brightness=SIM_BRIGHTNESS, occlusion=0.0, obstacle_range_m=range_m, qr_staleness_s=0.0)


def highway_observation(env: Any, vehicle: VehicleLimits | None = None, steering_rad: float | None = None) -> Observation:
    """The shield's Observation of a highway-env state (cue level): the binding lead's range and range rate."""
    base = env.unwrapped
    lead = binding_lead(highway_leads(env, steering_rad), vehicle if vehicle is not None else highway_vehicle(env))
    cues = sim_cues(lead.range_m if lead is not None else math.inf)
    return Observation(
        t_s=float(base.time),
        speed_mps=max(0.0, float(base.vehicle.speed)),  # highway-env never reverses here; −1e-15 is rounding
        cues=cues,
        range_rate_mps=-lead.closing_speed_mps if lead is not None else None,  # known in a simulator (radar-like)
    )


def lane_change_refusal(env: Any, vehicle: VehicleLimits, steering_rad: float, rules: RuleBase | None = None) -> str:
    """Why the lane change this steering starts is unsafe ("" when it is not one, or it is safe).

    Unsafe: a vehicle beside the ego in the lane being entered; its vehicle ahead inside a safe distance the ego
    cannot reach within one policy period at its hardest braking (RSS: a cut-in must leave the distance); or,
    with ``rules``, so near that the guard's own fear of that range would reach EMERGENCY (it would then stop
    on the highway for a car it chose to cut in behind, even one pulling away).
    """
    base = env.unwrapped
    road, ego = base.road, base.vehicle
    period = 1.0 / float(base.config["policy_frequency"])
    reachable = float(ego.speed) - vehicle.max_decel_mps2 * period
    for lane in entered_lanes(road, ego, steering_rad, period):
        if beside(road, ego, lane):
            return f"lane change into lane {lane[2]} refused: a vehicle beside the ego there"
        lead = lane_lead(road, ego, lane)
        if lead is None:
            continue
        safe = envelope_speed_mps(lead.range_m, vehicle, lead.speed_mps)
        if safe < reachable:
            return (f"lane change into lane {lane[2]} refused: its vehicle ahead at {lead.range_m:.1f} m "
                    f"({lead.speed_mps:.1f} m/s) allows {safe:.1f} m/s, braking reaches {max(reachable, 0.0):.1f} m/s")
        fear = rules.evaluate(sim_cues(lead.range_m)).fear if rules is not None else 0.0
        if rules is not None and fear >= rules.policy.emergency_enter_fear:
            return (f"lane change into lane {lane[2]} refused: its vehicle ahead at {lead.range_m:.1f} m is feared "
                    f"{fear:.2f} >= {rules.policy.emergency_enter_fear:.2f} (EMERGENCY)")
    return ""


def lane_keeping_steering_rad(env: Any) -> float:
    """highway-env's own lane-following steering (ControlledVehicle.steering_control) toward the ego's lane."""
    from highway_env.vehicle.controller import ControlledVehicle  # highway-env is there: the env is one of its

    base = env.unwrapped
    ego = base.vehicle
    follower = ControlledVehicle(base.road, ego.position, ego.heading, ego.speed)  # not on the road: a controller only
    return float(follower.steering_control(ego.lane_index))


def highway_action(action: Any, cmd: Command, env: Any) -> np.ndarray:
    """The agent's ContinuousAction with its acceleration clipped so the speed stays within the limit."""
    base = env.unwrapped
    act = np.array(action, dtype=float).reshape(-1).copy()
    low, high = base.action_type.acceleration_range
    allowed = (cmd.speed_limit_mps - float(base.vehicle.speed)) * float(base.config["policy_frequency"])
    allowed = min(high, max(low, allowed))
    wanted = float(np.clip(act[0], -1.0, 1.0)) if math.isfinite(act[0]) else -1.0  # garbage: brake
    act[0] = min(wanted, 2.0 * (allowed - low) / (high - low) - 1.0)
    return act.astype(np.float32)


class FearGuardShield(gymnasium.Wrapper):
    """A gymnasium wrapper that passes every action through fearguard (see the module docstring)."""

    def __init__(
        self,
        env: gymnasium.Env,
        vehicle: VehicleLimits | None = None,
        rules: RuleBase | str | None = None,
        *,
        observe: Observe | None = None,
        act: Act | None = None,
    ) -> None:
        super().__init__(env)
        self.highway = is_highway_env(env)
        if self.highway:
            action_type = env.unwrapped.action_type
            if type(action_type).__name__ != "ContinuousAction" or not (action_type.longitudinal and action_type.lateral):
                raise ValueError(
                    f"FearGuardShield needs highway-env's ContinuousAction with throttle and steering, got "
                    f"{type(action_type).__name__}: configure {{'action': {{'type': 'ContinuousAction'}}}}"
                )
            def observe_highway(e: Any, _obs: Any, _info: dict) -> Observation:
                return highway_observation(e, self.guard.vehicle, self._steering_rad)

            observe, act = observe or observe_highway, act or highway_action
            rules = rules if rules is not None else load_rules(bundled_rules_path(HIGHWAY_RULES))
            vehicle = vehicle if vehicle is not None else highway_vehicle(env)
        elif observe is None or act is None:
            raise TypeError(
                f"FearGuardShield: {type(env.unwrapped).__name__} is not a highway-env environment; pass "
                "observe(env, obs, info) -> fearguard.Observation and act(action, command, env) -> action"
            )
        self.observe, self.act = observe, act
        self._steering_rad: float | None = None  # highway-env: the steering about to be sent (rad, + = right)
        self.guard = FearGuard(None, rules=rules, vehicle=vehicle)  # the agent's steering arrives in each Observation
        self._last_obs: Any = None
        self._last_info: dict = {}

    def reset(self, **kwargs: Any) -> tuple[Any, dict]:
        obs, info = self.env.reset(**kwargs)
        self.guard.reset()  # a new episode's clock starts again: a guard with history would call it a fault
        self._last_obs, self._last_info = obs, info
        return obs, info

    def step(self, action: Any) -> tuple[Any, float, bool, bool, dict]:
        action, refusal = self._lane_change(action) if self.highway else (action, "")
        observed = self.observe(self.env, self._last_obs, self._last_info)
        if isinstance(observed, Observation):  # the agent's angle is the wrapped estimator's: the guard validates it
            observed = replace(observed, steering_deg=self._steering_deg(action))
        cmd = self.guard.step(observed)
        sent = self.act(action, cmd, self.env)
        obs, reward, terminated, truncated, info = self.env.step(sent)
        info = {**info, "fearguard": cmd, "fearguard_action": sent, "fearguard_lane_change": refusal}
        self._last_obs, self._last_info = obs, info
        return obs, reward, terminated, truncated, info

    def _lane_change(self, action: Any) -> tuple[Any, str]:
        """The agent's action, or, when its steering starts an unsafe lane change, the same action steering to keep
        the lane (highway-env's own lane-following law) and why."""
        low, high = self.env.unwrapped.action_type.steering_range
        act = np.array(action, dtype=float).reshape(-1).copy()
        s = float(np.clip(act[1], -1.0, 1.0)) if act.size > 1 and math.isfinite(act[1]) else 0.0
        self._steering_rad = low + (s + 1.0) * (high - low) / 2.0
        refusal = lane_change_refusal(self.env, self.guard.vehicle, self._steering_rad, self.guard.rules)
        if not refusal or act.size < 2:
            return action, ""
        self._steering_rad = float(np.clip(lane_keeping_steering_rad(self.env), low, high))
        act[1] = 2.0 * (self._steering_rad - low) / (high - low) - 1.0
        return act.astype(np.float32), refusal

    def _steering_deg(self, action: Any) -> float:
        """The agent's steering in fearguard's convention (degrees, + = left); 0 where there is none."""
        if not self.highway:
            return 0.0
        a = np.asarray(action, dtype=float).reshape(-1)
        low, high = self.env.unwrapped.action_type.steering_range
        s = float(np.clip(a[1], -1.0, 1.0)) if a.size > 1 and math.isfinite(a[1]) else 0.0
        return -math.degrees(low + (s + 1.0) * (high - low) / 2.0)  # highway-env: + = right
