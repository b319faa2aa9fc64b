"""Kinematic bicycle model: never beyond its acceleration, braking, steering-rate and steering-angle limits."""

from __future__ import annotations

import math

import pytest
from hypothesis import given
from hypothesis import strategies as st

from fearguard.sim.bicycle import BicycleLimits, BicycleState, step

LIMITS = BicycleLimits(wheelbase_m=0.26, max_accel_mps2=2.0, max_brake_mps2=4.0, max_steering_deg=30.0, max_steering_rate_dps=360.0)
DT = 0.05
EPS = 1e-9


@given(speed=st.floats(0.0, 5.0), steer=st.floats(-30.0, 30.0), cmd=st.floats(-90.0, 90.0), target=st.floats(-5.0, 10.0),
       dt=st.floats(0.001, 0.2))
def test_step_never_exceeds_the_limits(speed: float, steer: float, cmd: float, target: float, dt: float) -> None:
    before = BicycleState(0.0, 0.0, 0.0, speed, steer)
    after = step(before, cmd, target, dt, LIMITS)
    assert after.speed_mps >= 0.0
    assert after.speed_mps - before.speed_mps <= LIMITS.max_accel_mps2 * dt + EPS
    assert before.speed_mps - after.speed_mps <= LIMITS.max_brake_mps2 * dt + EPS
    assert abs(after.steering_deg - before.steering_deg) <= LIMITS.max_steering_rate_dps * dt + EPS
    assert abs(after.steering_deg) <= LIMITS.max_steering_deg + EPS
    moved = math.hypot(after.x_m, after.y_m)
    assert moved <= max(before.speed_mps, after.speed_mps) * dt + EPS  # no teleporting


@given(target=st.floats(0.9, 1.05), cmd=st.floats(-15.0, 15.0))
def test_commands_within_one_step_of_the_limits_are_met(target: float, cmd: float) -> None:
    # from 1 m/s and 0 deg, one step of 0.05 s reaches 0.8..1.1 m/s and ±18 deg
    after = step(BicycleState(0.0, 0.0, 0.0, 1.0, 0.0), cmd, target, DT, LIMITS)
    assert after.steering_deg == pytest.approx(cmd)
    assert after.speed_mps == pytest.approx(target)


def test_straight_drive_covers_speed_times_time() -> None:
    s = BicycleState(0.0, 0.0, 0.0, 1.5, 0.0)
    for _ in range(20):
        s = step(s, 0.0, 1.5, DT, LIMITS)
    assert (s.x_m, s.y_m, s.yaw_rad) == pytest.approx((1.5, 0.0, 0.0))


def test_constant_steering_drives_a_circle_of_wheelbase_over_tan() -> None:
    delta = 10.0
    radius = LIMITS.wheelbase_m / math.tan(math.radians(delta))
    s = BicycleState(0.0, 0.0, 0.0, 1.0, delta)
    steps = round(2 * math.pi * radius / (1.0 * DT))
    for _ in range(steps):
        s = step(s, delta, 1.0, DT, LIMITS)
    # a full circle brings the car back to the start, turning left (centre at (0, +radius))
    assert math.hypot(s.x_m, s.y_m) < 1.0 * DT
    assert s.lat_accel_mps2(LIMITS.wheelbase_m) == pytest.approx(1.0 / radius)


def test_braking_stops_at_zero_and_never_reverses() -> None:
    s = BicycleState(0.0, 0.0, 0.0, 1.0, 0.0)
    for _ in range(20):
        s = step(s, 0.0, 0.0, DT, LIMITS)
    assert s.speed_mps == 0.0
    assert s.x_m == pytest.approx(1.0**2 / (2 * LIMITS.max_brake_mps2))
