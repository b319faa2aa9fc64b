"""The Duckiebot preset: its camera, limits, rules and the pure-pursuit actuation (no simulator needed)."""

from __future__ import annotations

import math

import pytest
from hypothesis import given
from hypothesis import strategies as st

import fearguard as fg
from fearguard.fuzzy.check import check_rules
from fearguard.fuzzy.loader import bundled_rules_path
from fearguard.worlds.duckietown import preset as p


def test_camera_matches_the_simulator() -> None:
    cam = p.duckiebot_camera(320, 240)
    assert cam.fx_px == cam.fy_px  # square pixels
    assert (cam.cx_px, cam.cy_px) == (160.0, 120.0)
    assert math.degrees(2 * math.atan(cam.cy_px / cam.fy_px)) == pytest.approx(75.0)
    assert (cam.mount_height_m, cam.pitch_deg) == (0.108, 19.15)
    # the optical axis meets the floor at H / tan(pitch) ahead of the camera
    assert cam.ground_range_m(cam.cy_px) == pytest.approx(0.108 / math.tan(math.radians(19.15)))
    assert p.duckiebot_camera(160, 120) == cam.scaled_to(160, 120)


def test_aim_point_is_on_the_floor_the_camera_sees() -> None:
    lane = p.duckietown_lane()
    for w, h in ((160, 120), (320, 240), (640, 480)):
        cam = p.duckiebot_camera(w, h)
        near, far = cam.ground_range_m(h - 1), cam.ground_range_m(0.35 * h)
        assert near is not None and far is not None and near < lane.aim_m < lane.far_m <= far


def test_limits_declare_the_sensors_the_robot_has() -> None:
    db18 = p.duckiebot_limits()
    assert not db18.has_ultrasonic and not db18.has_qr_localisation
    tof = p.duckiebot_limits(time_of_flight=True)
    assert tof.has_ultrasonic and (tof.ultrasonic_min_range_m, tof.ultrasonic_max_range_m) == (p.TOF_MIN_RANGE_M, p.TOF_MAX_RANGE_M)
    assert 0.2 <= db18.max_speed_mps <= p.MAX_SPEED_MPS


@given(st.floats(0.0, p.duckiebot_limits().max_speed_mps))
def test_planned_stop_covers_the_simulated_stop(v: float) -> None:
    """The policy's stopping distance (v·t_r + v²/2a) is never shorter than the DB18's: v·(delay + τ)."""
    lim = p.duckiebot_limits()
    planned = v * lim.reaction_time_s + v * v / (2 * lim.max_decel_mps2)
    assert planned >= v * (p.ACTUATION_DELAY_S + p.SPEED_TIME_CONSTANT_S) - 1e-12


def test_steady_state_gains_invert_the_nominal_dynamics() -> None:
    # DB18 nominal: u = 1.5/5·(V_r+V_l), ω = 15/4·(V_r−V_l); DuckietownEnv: V = (vel ± ω·b/2)/(r·k)
    r, k, b = 0.0318, 27.0, 0.102
    a = p.steering_action(12.0, 0.2, 0.3)
    v_r, v_l = (a.vel + 0.5 * a.omega * b) / (r * k), (a.vel - 0.5 * a.omega * b) / (r * k)
    assert 0.3 * (v_r + v_l) == pytest.approx(a.speed_mps)
    assert 3.75 * (v_r - v_l) == pytest.approx(a.yaw_rate_rps)


@given(st.floats(-45.0, 45.0), st.floats(0.1, 1.0))
def test_pursuit_arc_passes_through_the_aim_point(bearing: float, aim: float) -> None:
    kappa = p.pursuit_curvature_per_m(bearing, aim)
    x, y = p.CAMERA_AHEAD_M + aim * math.cos(math.radians(bearing)), aim * math.sin(math.radians(bearing))
    # the circle through the axle, tangent to the heading, with curvature κ: x² + (y − 1/κ)² = 1/κ²
    assert kappa * (x * x + y * y) == pytest.approx(2 * y, abs=1e-12)
    assert math.copysign(1, kappa) == math.copysign(1, bearing) or kappa == 0  # + = left, as fearguard's angles


@given(st.floats(-45.0, 45.0), st.floats(-1.0, 1.0))
def test_no_reverse_and_no_turning_on_the_spot(bearing: float, speed: float) -> None:
    a = p.steering_action(bearing, speed, 0.3)
    assert a.vel >= 0 and a.speed_mps >= 0
    if speed <= 0:
        assert a.omega == 0 and a.vel == 0


def test_duckiebot_rules_are_complete_and_monotone() -> None:
    rules = fg.load_rules(bundled_rules_path("duckiebot.toml"))
    assert check_rules(rules).ok
    calm = fg.Cues(lane_confidence=0.9, brightness=70.0, occlusion=0.0, obstacle_range_m=math.inf, qr_staleness_s=0.0)
    assert rules.evaluate(calm).level == fg.FearLevel.VERY_LOW  # a well-lit black Duckietown mat is normal
    near = fg.Cues(lane_confidence=0.9, brightness=70.0, occlusion=0.0, obstacle_range_m=0.15, qr_staleness_s=0.0)
    assert rules.evaluate(near).level >= fg.FearLevel.HIGH  # inside the stopping distance at top speed
