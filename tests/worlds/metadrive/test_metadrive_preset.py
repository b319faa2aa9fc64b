"""The MetaDrive preset: its camera, its limits and the pure-pursuit actuation (no simulator needed)."""

from __future__ import annotations

import math

import numpy as np
import pytest
from hypothesis import given
from hypothesis import strategies as st

from fearguard.vehicle import PRESETS
from fearguard.worlds.metadrive import preset as p


def test_camera_is_metadrives_rgb_camera() -> None:
    cam = p.metadrive_camera(320, 240)
    assert cam.fx_px == cam.fy_px and (cam.cx_px, cam.cy_px) == (160.0, 120.0)  # square pixels, centred
    assert math.degrees(2 * math.atan(cam.cx_px / cam.fx_px)) == pytest.approx(60.0)  # lens.setFov(60): horizontal
    assert math.degrees(2 * math.atan(cam.cy_px / cam.fy_px)) == pytest.approx(46.83, abs=0.01)  # Panda3D's vertical at 4:3
    assert (cam.mount_height_m, cam.pitch_deg) == (2.095, -0.59681)  # 2.1 m up, pitched slightly up
    assert cam.horizon_v_px() > cam.cy_px  # looking up: the horizon lies below the image centre
    assert p.metadrive_camera(640, 480) == cam.scaled_to(640, 480)


def test_aim_point_is_on_the_road_the_camera_sees() -> None:
    for w, h in ((160, 120), (320, 240), (640, 480)):
        cam = p.metadrive_camera(w, h)
        assert p.lane_aim_m(cam) == pytest.approx(p.AIM_M, rel=1e-6)  # the steering's aim: inside the road region
        assert 10.0 < p.lane_aim_m(cam, None) < 25.0  # the image lane model's own look-ahead row: about 16 m ahead


def test_limits_are_the_road_car_where_metadrive_agrees() -> None:
    lim, road = p.metadrive_limits(), PRESETS["road_car"]
    assert lim.max_speed_mps == pytest.approx(80 / 3.6) and lim.width_m == 1.852 and p.WHEELBASE_M == pytest.approx(2.469, abs=1e-3)
    assert not lim.has_ultrasonic and p.metadrive_limits(radar=True).has_ultrasonic
    for same in ("max_decel_mps2", "reaction_time_s", "stop_margin_m", "max_lateral_accel_mps2", "lead_max_decel_mps2"):
        assert getattr(lim, same) == getattr(road, same)
    radar = p.metadrive_limits(radar=True)
    assert (radar.ultrasonic_min_range_m, radar.ultrasonic_max_range_m) == (p.RADAR_MIN_RANGE_M, p.RADAR_MAX_RANGE_M)


@given(st.floats(-30.0, 30.0), st.floats(5.0, 30.0))
def test_pursuit_arc_passes_through_the_aim_point(bearing: float, aim: float) -> None:
    delta = math.radians(p.pursuit_wheel_angle_deg(bearing, aim))
    kappa = math.tan(delta) / p.WHEELBASE_M
    x = p.REAR_AXLE_TO_CAMERA_M + aim * math.cos(math.radians(bearing))
    y = aim * math.sin(math.radians(bearing))
    assert kappa * (x * x + y * y) == pytest.approx(2 * y, abs=1e-9)  # the circle through the rear axle and the aim point


@given(st.floats(-30.0, 30.0))
def test_a_left_bearing_steers_left(bearing: float) -> None:
    a = p.steering_action(bearing, 10.0, 10.0, 16.0)
    assert -1.0 <= a.steer <= 1.0
    assert a.steer == 0.0 or math.copysign(1, a.steer) == math.copysign(1, bearing)  # + = left, as MetaDrive's steer


def test_speed_controller_brakes_to_stand_and_never_exceeds_full_pedal() -> None:
    assert p.throttle_for(0.0, 5.0) == -1.0 and p.throttle_for(0.2, 0.0) == -1.0  # stand still: full brake
    assert p.throttle_for(10.0, 0.0) == 1.0 and p.throttle_for(10.0, 20.0) == -1.0
    assert p.throttle_for(10.0, 9.0) == pytest.approx(p.ROLLING_THROTTLE + p.SPEED_GAIN)
    assert p.steering_action(0.0, -3.0, 2.0, 16.0).speed_target_mps == 0.0  # no reverse


@pytest.mark.parametrize("bearing_deg", [1.0, 5.0, 10.0, -10.0])
def test_the_limits_wheelbase_turns_the_aim_bearing_into_the_arc_the_car_drives(bearing_deg: float) -> None:
    """The policy's bicycle model (κ = tan δ / L) with the preset's wheelbase gives the curvature of the pure-pursuit
    arc the actuation drives for that bearing (within 2 % up to 10°), not a 4× tighter turn."""
    aim = 16.0
    wheel = p.pursuit_wheel_angle_deg(bearing_deg, aim)
    driven = math.tan(math.radians(wheel)) / p.WHEELBASE_M
    assumed = math.tan(math.radians(bearing_deg)) / p.metadrive_limits(aim_m=aim).wheelbase_m
    assert assumed == pytest.approx(driven, rel=0.02)


def _lane_path(radius_m: float, angle_deg: float) -> np.ndarray:
    """A lane centre: 40 m straight, a left curve of ``radius_m`` over ``angle_deg``, 60 m straight (0.05 m apart)."""
    ds, heading = 0.05, np.zeros(1)
    turn = np.full(int(radius_m * math.radians(angle_deg) / ds), ds / radius_m)
    heading = np.concatenate([np.zeros(int(40 / ds)), np.cumsum(turn), np.full(int(60 / ds), turn.sum())])
    return np.column_stack([np.cumsum(ds * np.cos(heading)), np.cumsum(ds * np.sin(heading))])


def _max_offset_m(aim_m: float, radius_m: float, speed_mps: float = 10.0) -> float:
    """A kinematic bicycle at ``speed_mps`` steered by the preset's pure pursuit (``pursuit_wheel_angle_deg``) to the
    true lane centre ``aim_m`` from its camera, one step late (MetaDrive acts on the last frame): the farthest its centre
    strays from the lane centre."""
    path = _lane_path(radius_m, 90.0)
    x = y = h = 0.0  # rear axle, heading
    pending, worst = 0.0, 0.0
    for _ in range(int(140 / (speed_mps * p.STEP_S))):
        cx, cy = x + p.REAR_AXLE_TO_CAMERA_M * math.cos(h), y + p.REAR_AXLE_TO_CAMERA_M * math.sin(h)
        gx, gy = x + p.REAR_AXLE_M * math.cos(h), y + p.REAR_AXLE_M * math.sin(h)
        near = int(np.argmin(np.hypot(path[:, 0] - gx, path[:, 1] - gy)))
        if near >= len(path) - 2:
            break
        (tx, ty), (dx, dy) = path[near + 1] - path[near], (gx, gy) - path[near]
        worst = max(worst, abs(tx * dy - ty * dx) / math.hypot(tx, ty))
        ahead = np.hypot(path[near:, 0] - cx, path[near:, 1] - cy)
        if ahead.max() < aim_m:
            break
        ax, ay = path[near + int(np.argmax(ahead >= aim_m))] - (cx, cy)
        bearing = math.degrees(math.atan2(-ax * math.sin(h) + ay * math.cos(h), ax * math.cos(h) + ay * math.sin(h)))
        wheel, pending = pending, p.pursuit_wheel_angle_deg(bearing, aim_m)
        h += speed_mps * p.STEP_S * math.tan(math.radians(wheel)) / p.WHEELBASE_M
        x, y = x + speed_mps * p.STEP_S * math.cos(h), y + speed_mps * p.STEP_S * math.sin(h)
    return worst


@pytest.mark.parametrize("radius_m", [25.0, 40.0, 60.0])
def test_the_aim_keeps_the_car_in_its_lane_on_metadrives_tightest_curves(radius_m: float) -> None:
    """MetaDrive's curves have R 25-60 m (its CURVE parameter space). Pure pursuit to the lane centre 9 m ahead (the
    preset's aim) keeps a car at the 10 m/s cruise within 0.5 m of it; aiming at the image model's own row (~16 m at
    320x240) it strays 1.3 m on R 25 m — a 1.85 m car in a 3.5 m lane then brushes the next lane's traffic (seed 24,
    traffic 0.15)."""
    cruise_aim = p.AIM_M
    assert _max_offset_m(cruise_aim, radius_m) <= 0.5
    region_row = p.lane_aim_m(p.metadrive_camera(320, 240), None)
    assert _max_offset_m(region_row, radius_m) > 1.5 * _max_offset_m(cruise_aim, radius_m)
    if radius_m == 25.0:
        assert _max_offset_m(region_row, radius_m) > 1.0


@pytest.mark.parametrize("speed_mps", [15.0, 22.0])
def test_the_near_aim_does_not_weave_at_speed(speed_mps: float) -> None:
    """One aim for every cruise: at 15-22 m/s, one step late, the pursuit to 9 m ahead settles onto a gentle curve
    (R 150 m: 3 m/s² at 21 m/s, road_car's lateral cap) within 0.15 m — no weaving from aiming near at speed."""
    assert _max_offset_m(p.AIM_M, 150.0, speed_mps) <= 0.15


# -- the route's aim (the world's navigation, for policy.route) ------------------------------------------------------
@given(heading=st.floats(-math.pi, math.pi), radius=st.floats(12.0, 400.0), left=st.booleans(), aim=st.floats(4.0, 11.0))
def test_route_bearing_on_a_circular_route_is_pure_pursuits(heading: float, radius: float, left: bool, aim: float) -> None:
    """The camera on a circle of radius R, heading along it: the route point ``aim`` away on the circle lies at
    asin(aim / 2R) from the heading, to the side the route turns (+ = left, as MetaDrive's angles and steering)."""
    sign = 1.0 if left else -1.0
    centre_dir = heading + sign * math.pi / 2.0  # the circle's centre lies to the side of the turn
    centre = np.array([radius * math.cos(centre_dir), radius * math.sin(centre_dir)])
    start = math.atan2(-centre[1], -centre[0])  # the camera (at the origin) seen from the centre
    arc = np.arange(0.0, 3.0 * aim, 0.01) / radius
    points = centre + radius * np.stack([np.cos(start + sign * arc), np.sin(start + sign * arc)], axis=1)
    bearing = p.route_bearing_deg(points, (0.0, 0.0), heading, aim)
    assert bearing is not None
    assert bearing == pytest.approx(sign * math.degrees(math.asin(aim / (2.0 * radius))), abs=0.1)


def test_route_bearing_straight_ahead_is_zero_and_a_short_route_has_none() -> None:
    ahead = np.stack([np.linspace(0.0, 30.0, 61), np.zeros(61)], axis=1)
    assert p.route_bearing_deg(ahead, (0.0, 0.0), 0.0, 9.0) == pytest.approx(0.0)
    assert p.route_bearing_deg(ahead, (0.0, 0.0), math.radians(10.0), 9.0) == pytest.approx(-10.0)  # heading left of it: steer right
    assert p.route_bearing_deg(ahead[:10], (0.0, 0.0), 0.0, 9.0) is None  # the known route ends 4.5 m ahead
    assert p.route_bearing_deg(np.empty((0, 2)), (0.0, 0.0), 0.0, 9.0) is None
