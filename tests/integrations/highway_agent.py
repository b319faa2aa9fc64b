"""An aggressive highway-env agent for the shield's tests: full throttle, a random lane change every few seconds.

Steering comes from highway-env's own lane-following law (ControlledVehicle.steering_control), written
against the ego's state so the agent can aim at any lane with ContinuousAction.
"""

from __future__ import annotations

import math

import numpy as np

TAU_HEADING_S = 0.2  # [s] highway-env ControlledVehicle.TAU_HEADING
TAU_LATERAL_S = 0.6  # [s] highway-env ControlledVehicle.TAU_LATERAL
TAU_PURSUIT_S = 0.5 * TAU_HEADING_S


class AggressiveAgent:
    """Full throttle; every ``change_every_s`` (random) a lane change to a random neighbour lane."""

    def __init__(self, env, seed: int, change_every_s: tuple[float, float] = (2.0, 6.0)) -> None:
        self.env, self.rng, self.change_every_s = env, np.random.default_rng(seed), change_every_s
        self.target = None
        self.next_change_s = 0.0

    def __call__(self) -> np.ndarray:
        base = self.env.unwrapped
        ego, road = base.vehicle, base.road
        if self.target is None or base.time >= self.next_change_s:
            lanes = road.network.side_lanes(ego.lane_index) or [ego.lane_index]
            self.target = lanes[int(self.rng.integers(len(lanes)))]
            self.next_change_s = base.time + float(self.rng.uniform(*self.change_every_s))
        _from, _to, _ = ego.lane_index
        target = (_from, _to, self.target[2])
        steering = steering_to_lane(road, ego, target)
        low, high = base.action_type.steering_range
        return np.array([1.0, 2.0 * (steering - low) / (high - low) - 1.0], dtype=np.float32)


def steering_to_lane(road, ego, lane_index) -> float:
    """highway-env's lane-following steering law (rad, + = right), from the ego's state."""
    lane = road.network.get_lane(lane_index)
    s, lateral = lane.local_coordinates(ego.position)
    future_heading = lane.heading_at(s + ego.speed * TAU_PURSUIT_S)
    speed = max(ego.speed, 1e-2)
    heading_command = math.asin(float(np.clip(-lateral / TAU_LATERAL_S / speed, -1, 1)))
    heading_ref = future_heading + float(np.clip(heading_command, -math.pi / 4, math.pi / 4))
    heading_rate = (math.remainder(heading_ref - ego.heading, 2 * math.pi)) / TAU_HEADING_S
    slip = math.asin(float(np.clip(ego.LENGTH / 2 / speed * heading_rate, -1, 1)))
    return math.atan(2 * math.tan(slip))
