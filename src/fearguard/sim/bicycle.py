"""Kinematic bicycle model about the rear axle, with the actuator limits of a real car.

One step of dt: the steering angle moves toward the command at most ``max_steering_rate_dps``·dt and
stays within ±``max_steering_deg``; the speed moves toward the target with at most ``max_accel_mps2``
up and ``max_brake_mps2`` down, never below zero (no reverse). The car then drives the step's mean
speed × dt along the arc of curvature κ = tan(δ)/wheelbase, integrated exactly (constant κ over the
step). Lateral acceleration is v²·κ. Written by hand: the model is five lines and no library adds value.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

_EPS_CURVATURE = 1e-9  # [1/m] below this the step is a straight line


@dataclass(frozen=True)
class BicycleLimits:
    wheelbase_m: float
    max_accel_mps2: float
    max_brake_mps2: float
    max_steering_deg: float
    max_steering_rate_dps: float


@dataclass(frozen=True)
class BicycleState:
    """Rear-axle position (world m), heading (rad, + = counter-clockwise), speed and road-wheel angle."""

    x_m: float
    y_m: float
    yaw_rad: float
    speed_mps: float
    steering_deg: float
    accel_mps2: float = 0.0  # over the last step

    def curvature_per_m(self, wheelbase_m: float) -> float:
        return math.tan(math.radians(self.steering_deg)) / wheelbase_m

    def lat_accel_mps2(self, wheelbase_m: float) -> float:
        return self.speed_mps**2 * self.curvature_per_m(wheelbase_m)


def step(state: BicycleState, steering_cmd_deg: float, speed_target_mps: float, dt_s: float, limits: BicycleLimits) -> BicycleState:
    """The state one step of ``dt_s`` later under the (limited) commands."""
    cmd = min(max(steering_cmd_deg, -limits.max_steering_deg), limits.max_steering_deg)
    max_turn = limits.max_steering_rate_dps * dt_s
    delta = state.steering_deg + min(max(cmd - state.steering_deg, -max_turn), max_turn)
    delta = min(max(delta, -limits.max_steering_deg), limits.max_steering_deg)
    target = max(0.0, speed_target_mps)
    accel = min(max((target - state.speed_mps) / dt_s, -limits.max_brake_mps2), limits.max_accel_mps2)
    speed = max(0.0, state.speed_mps + accel * dt_s)
    accel = (speed - state.speed_mps) / dt_s
    distance = 0.5 * (state.speed_mps + speed) * dt_s
    kappa = math.tan(math.radians(delta)) / limits.wheelbase_m
    yaw = state.yaw_rad + kappa * distance
    if abs(kappa) > _EPS_CURVATURE:
        x = state.x_m + (math.sin(yaw) - math.sin(state.yaw_rad)) / kappa
        y = state.y_m - (math.cos(yaw) - math.cos(state.yaw_rad)) / kappa
    else:
        x = state.x_m + distance * math.cos(state.yaw_rad)
        y = state.y_m + distance * math.sin(state.yaw_rad)
    return BicycleState(x, y, yaw, speed, delta, accel)
