"""A gymnasium shield: fearguard between an agent and the environment, at cue level.

    env = FearGuardShield(gymnasium.make("highway-v0", config={"action": {"type": "ContinuousAction"}}))

For highway-env (detected from the unwrapped environment) the shield builds the observation itself
from the simulator's state, as a radar and a lane map would give it: the range (bumper to bumper) and
closing speed to the vehicle ahead in the ego lane and in the lane being entered (the lane the ego's
heading reaches within ``LANE_LOOKAHEAD_S``), the ego speed and the env's clock (``env.time``). The
road picture is perfect in a simulator (lane confidence 1, brightness mid-band, no occlusion, no QR
localisation). Conventions converted explicitly:

- ContinuousAction is ``[acceleration, steering]`` in [−1, 1], mapped by the env to its
  ``acceleration_range`` (±5 m/s²) and ``steering_range`` (±45°) with **+ = right** (y points down);
  fearguard's steering is degrees with + = left.
- The acceleration is clipped so the speed stays within the limit at the next decision:
  ``a ≤ (limit − v) · policy_frequency`` (the env holds an action for one policy period), never below
  the env's hardest braking.
- **Steering policy:** the agent's steering passes unchanged. In a simulator the road picture never
  fails, so fearguard's steering strategies (follow the lead's bearing, hold the last trusted angle
  when the road is lost) do not apply; a lane change toward a lane whose vehicle ahead is too close is
  answered by the speed limit (that vehicle's range is in the cue), not by steering back.

The guard is reset on ``reset()`` (a new episode's clock starts again at 0) and every step's
``Command`` is in ``info["fearguard"]``, the action actually sent in ``info["fearguard_action"]``.
Any other environment: pass ``observe(env, obs, info) → fearguard.Observation`` and
``act(action, command, env) → action``.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass
from typing import Any

import gymnasium
import numpy as np

from fearguard.cues import Cues
from fearguard.fuzzy.loader import bundled_rules_path, load_rules
from fearguard.fuzzy.rulebase import RuleBase
from fearguard.supervisor import Command, FearGuard, Observation
from fearguard.vehicle import VehicleLimits

LANE_LOOKAHEAD_S = 1.0  # [s] a lane the ego's heading reaches within this time is a lane being entered
LOOKAHEAD_FRACTIONS = (0.25, 0.5, 0.75, 1.0)  # [-] of LANE_LOOKAHEAD_S, where the heading is followed
SENSOR_RANGE_M = 150.0  # [m] beyond it nothing ahead is seen (a long-range automotive radar)
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


def highway_vehicle(env: Any) -> VehicleLimits:
    """The ego of a highway-env environment as VehicleLimits: its speed bound, the action's braking and steering."""
    base = env.unwrapped
    action = base.action_type
    ego = base.vehicle
    return VehicleLimits(
        max_speed_mps=float(ego.MAX_SPEED),
        max_decel_mps2=float(-action.acceleration_range[0]),
        reaction_time_s=1.0 / float(base.config["policy_frequency"]),  # an action is held for one policy period
        stop_margin_m=2.0,  # [m] bumper-to-bumper gap left at standstill
        max_steering_deg=math.degrees(max(abs(s) for s in action.steering_range)),
        has_ultrasonic=True,  # the range cue is the radar-like range built from the simulator
        has_qr_localisation=False,
        ultrasonic_min_range_m=0.1,
        ultrasonic_max_range_m=SENSOR_RANGE_M,
    )


def lane_lead(road: Any, ego: Any, lane_index: tuple) -> LaneLead | None:
    """The nearest vehicle ahead of the ego in ``lane_index`` within SENSOR_RANGE_M, projected on that lane."""
    front, _ = road.neighbour_vehicles(ego, lane_index)
    if front is None:
        return None
    lane = road.network.get_lane(lane_index)
    s_ego = lane.local_coordinates(ego.position)[0]
    s_front = lane.local_coordinates(front.position)[0]
    gap = s_front - s_ego - (front.LENGTH + ego.LENGTH) / 2.0
    if gap > SENSOR_RANGE_M:
        return None
    heading = lane.heading_at(s_ego)
    v_ego = ego.speed * math.cos(ego.heading - heading)
    v_front = front.speed * math.cos(front.heading - heading)
    return LaneLead(lane_index, max(0.0, gap), v_ego - v_front, v_front)


def entered_lanes(road: Any, ego: Any) -> list[tuple]:
    """The lanes the ego's heading reaches within LANE_LOOKAHEAD_S, nearest first (none when it keeps to its lane)."""
    lanes: list[tuple] = []
    direction = np.array([math.cos(ego.heading), math.sin(ego.heading)])
    for fraction in LOOKAHEAD_FRACTIONS:  # sampled so a steep heading does not skip the adjacent lane
        lane = road.network.get_closest_lane_index(ego.position + ego.speed * LANE_LOOKAHEAD_S * fraction * direction, ego.heading)
        if lane != ego.lane_index and lane not in lanes:
            lanes.append(lane)
    return lanes


def highway_leads(env: Any) -> list[LaneLead]:
    """The leads in the ego lane and in the lanes being entered (nearest first)."""
    base = env.unwrapped
    road, ego = base.road, base.vehicle
    lanes = [ego.lane_index, *entered_lanes(road, ego)]
    leads = [lead for lane in lanes if (lead := lane_lead(road, ego, lane)) is not None]
    return sorted(leads, key=lambda lead: lead.range_m)


def highway_observation(env: Any) -> Observation:
    """The shield's Observation of a highway-env state (cue level)."""
    base = env.unwrapped
    leads = highway_leads(env)
    range_m = leads[0].range_m if leads else math.inf
    cues = Cues(lane_confidence=1.0, brightness=SIM_BRIGHTNESS, occlusion=0.0, obstacle_range_m=range_m, qr_staleness_s=0.0)
    return Observation(t_s=float(base.time), speed_mps=float(base.vehicle.speed), cues=cues)


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
            observe, act = observe or (lambda e, _obs, _info: highway_observation(e)), act or highway_action
            rules = rules if rules is not None else load_rules(bundled_rules_path(HIGHWAY_RULES))
            vehicle = vehicle if vehicle is not None else highway_vehicle(env)
        elif observe is None or act is None:
            raise TypeError(
                f"FearGuardShield: {type(env.unwrapped).__name__} is not a highway-env environment; pass "
                "observe(env, obs, info) -> fearguard.Observation and act(action, command, env) -> action"
            )
        self.observe, self.act = observe, act
        self._agent_steering_deg = 0.0
        self.guard = FearGuard(lambda _frame: self._agent_steering_deg, rules=rules, vehicle=vehicle)
        self._last_obs: Any = None
        self._last_info: dict = {}

    def reset(self, **kwargs: Any) -> tuple[Any, dict]:
        obs, info = self.env.reset(**kwargs)
        self.guard.reset()  # a new episode's clock starts again: a guard with history would call it a fault
        self._last_obs, self._last_info = obs, info
        return obs, info

    def step(self, action: Any) -> tuple[Any, float, bool, bool, dict]:
        self._agent_steering_deg = self._steering_deg(action)
        cmd = self.guard.step(self.observe(self.env, self._last_obs, self._last_info))
        sent = self.act(action, cmd, self.env)
        obs, reward, terminated, truncated, info = self.env.step(sent)
        info = {**info, "fearguard": cmd, "fearguard_action": sent}
        self._last_obs, self._last_info = obs, info
        return obs, reward, terminated, truncated, info

    def _steering_deg(self, action: Any) -> float:
        """The agent's steering in fearguard's convention (degrees, + = left); 0 where there is none."""
        if not self.highway:
            return 0.0
        a = np.asarray(action, dtype=float).reshape(-1)
        low, high = self.env.unwrapped.action_type.steering_range
        s = float(np.clip(a[1], -1.0, 1.0)) if a.size > 1 and math.isfinite(a[1]) else 0.0
        return -math.degrees(low + (s + 1.0) * (high - low) / 2.0)  # highway-env: + = right
