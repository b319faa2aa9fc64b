"""Relative motion: the RSS-style safe distance, the imminent check, the lateral envelope, steering limits."""

from __future__ import annotations

import math

import pytest
from hypothesis import given
from hypothesis import strategies as st

import fearguard as fg
from fearguard.policy import (
    PolicyConfig,
    envelope_speed_mps,
    imminent_collision,
    lateral_speed_mps,
    lead_speed_mps,
    oscillating,
    rate_limited_steering_deg,
    stopping_distance_m,
    watchdog_s,
)

ROAD = fg.VehicleLimits.preset("road_car")
cars = st.sampled_from([fg.VehicleLimits.preset(n) for n in ("camera_only", "hc_sr04_pi", "qr_campus", "duckiebot", "road_car")])


def test_standing_obstacle_is_the_special_case() -> None:
    for d in (0.1, 0.5, 2.0, 10.0, 60.0):
        v = envelope_speed_mps(d, ROAD, 0.0)
        assert stopping_distance_m(v, ROAD) <= max(0.0, d - ROAD.stop_margin_m) + 1e-9
        assert envelope_speed_mps(d, ROAD) == v


def test_a_lead_at_the_same_speed_is_followed() -> None:
    # 40 m gap, both at 25 m/s: RSS room = 39 + 25²/(2·8) m, far more than the ego needs at 25 m/s
    assert envelope_speed_mps(40.0, ROAD, 25.0) > 25.0
    assert not imminent_collision(40.0, 25.0, ROAD, closing_speed_mps=0.0)
    assert imminent_collision(40.0, 25.0, ROAD)  # unknown closing speed: a standing obstacle, as before


@given(cars, st.floats(0.0, 100.0), st.floats(0.0, 40.0), st.floats(-10.0, 50.0), st.floats(0.0, 20.0))
def test_faster_closing_never_raises_the_limit_nor_clears_imminent(car, d, v, closing, more) -> None:
    slow, fast = lead_speed_mps(v, closing), lead_speed_mps(v, closing + more)
    assert envelope_speed_mps(d, car, fast) <= envelope_speed_mps(d, car, slow)
    if imminent_collision(d, v, car, closing):
        assert imminent_collision(d, v, car, closing + more)
    assert envelope_speed_mps(d, car, fast) <= envelope_speed_mps(d + more, car, fast)


@given(cars, st.floats(0.0, 100.0), st.floats(0.0, 40.0))
def test_envelope_keeps_the_rss_distance(car, d, v_f) -> None:
    v = envelope_speed_mps(d, car, v_f)
    room = max(0.0, d - car.stop_margin_m + v_f * v_f / (2 * car.lead_max_decel_mps2))
    assert stopping_distance_m(v, car) <= room + 1e-9


def test_unknown_speeds_mean_a_standing_obstacle() -> None:
    assert lead_speed_mps(None, 1.0) == 0.0 and lead_speed_mps(3.0, None) == 0.0 and lead_speed_mps(3.0, math.nan) == 0.0
    assert lead_speed_mps(3.0, 5.0) == 0.0 and lead_speed_mps(3.0, -1.0) == 4.0


def test_opening_gap_is_not_imminent_outside_the_margin() -> None:
    car = fg.VehicleLimits(reaction_time_s=0.0)
    assert not imminent_collision(0.5, 1.0, car, closing_speed_mps=-50.0)
    assert imminent_collision(0.1, 1.0, car, closing_speed_mps=-50.0)  # inside the margin


@given(cars, st.floats(-89.0, 89.0))
def test_lateral_envelope(car, delta) -> None:
    v = lateral_speed_mps(delta, car)
    if math.isfinite(v):
        assert v * v * abs(math.tan(math.radians(delta))) / car.wheelbase_m == pytest.approx(car.max_lateral_accel_mps2)
    else:
        assert abs(math.tan(math.radians(delta))) < 1e-12


def test_lateral_envelope_of_the_issue() -> None:
    # 29° at 2 m/s on a 0.26 m wheelbase is ~8.5 m/s² of lateral acceleration: too much for a 1:10 car (4 m/s²)
    car = fg.VehicleLimits()
    v = lateral_speed_mps(29.0, car)
    assert v < 2.0 and v * v * math.tan(math.radians(29.0)) / 0.26 == pytest.approx(4.0)


@given(st.one_of(st.none(), st.floats(-30, 30)), st.floats(-30, 30), st.floats(0.001, 1.0))
def test_steering_rate_limit_is_the_smallest_change(prev, target, dt) -> None:
    car = fg.VehicleLimits()
    out = rate_limited_steering_deg(prev, target, dt, car)
    if prev is None or abs(target - prev) <= car.max_steering_rate_dps * dt:
        assert out == target
    else:
        assert abs(out - prev) == pytest.approx(car.max_steering_rate_dps * dt)
        assert (out - prev) * (target - prev) >= 0 and abs(target - out) < abs(target - prev)


def test_oscillation_needs_large_flips_in_a_row() -> None:
    cfg = PolicyConfig()
    assert oscillating([29.0, -29.0, 29.0, -29.0], cfg)
    assert not oscillating([29.0, -29.0, 29.0], cfg)
    assert not oscillating([29.0, -29.0, 5.0, -29.0], cfg)
    assert not oscillating([3.0, -3.0, 3.0, -3.0, 3.0], cfg)


def test_watchdog_is_max_of_periods_and_age() -> None:
    cfg = PolicyConfig()
    assert watchdog_s(None, cfg) == 1.0 and watchdog_s(0.05, cfg) == 1.0 and watchdog_s(0.2, cfg) == 2.0
