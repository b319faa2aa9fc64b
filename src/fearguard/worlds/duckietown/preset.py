"""The Duckiebot preset: its camera, its limits, its lane geometry and how a fearguard command drives it.

Pure values and functions (no simulator import), so they are testable and usable on a real robot.

Camera (gym-duckietown's DB18): vertical FOV 75°, square pixels, principal point centred, pitched
19.15° down, 0.108 m above the floor, 0.066 m ahead of the wheel axle, 30 frames/s.

Actuation (the steering angle is the bearing of an aim point, as fearguard's lane steering gives it):
the aim point is the lane centre ``aim_m`` from the camera (the ground-plane lane model's pure-pursuit
point, ``AIM_M``), at the bearing α, i.e. at (x, y) = (CAMERA_AHEAD_M + aim_m · cos α, aim_m · sin α)
from the axle; pure pursuit drives the arc through it, κ = 2·y / (x² + y²), and the yaw rate is
ω = v·κ at the commanded speed v (so a stopped robot does not spin). The simulator's DuckietownEnv
takes [vel, omega]; the nominal DB18 PWM dynamics of duckietown-world (u̇ = −5u + 1.5(V_r + V_l),
ω̇ = −4ω + 15(V_r − V_l), with DuckietownEnv's wheel radius 0.0318 m, motor constant 27, baseline
0.102 m) settle at u = 0.699·vel and ω = 0.4455·omega, so the action is [v / SPEED_GAIN, ω / YAW_RATE_GAIN].
"""

from __future__ import annotations

import math
from dataclasses import dataclass

from fearguard.camera import CameraModel
from fearguard.vehicle import VehicleLimits
from fearguard.vision.ground_lanes import GroundLaneSpec

# -- camera (gym_duckietown.simulator constants) -----------------------------------------------
CAMERA_VFOV_DEG = 75.0  # [deg] vertical field of view
CAMERA_PITCH_DEG = 19.15  # [deg] down
CAMERA_HEIGHT_M = 0.108  # [m] above the floor
CAMERA_AHEAD_M = 0.066  # [m] ahead of the wheel axle (the centre of rotation)
FRAME_RATE_HZ = 30.0  # [1/s] the simulator's step
DEFAULT_FRAME_PX = (320, 240)  # [px] 4:3 as the real camera; 640×480 costs 2.5× the rendering time

# -- actuation (steady state of the nominal DB18 dynamics through DuckietownEnv, see above) ----
_DUTY_PER_MPS = 1.0 / (0.0318 * 27.0)  # [1/(m/s)] DuckietownEnv: duty = wheel speed · radius⁻¹ / k
SPEED_GAIN = 2 * 0.3 * _DUTY_PER_MPS  # [-] steady speed per unit of ``vel`` (u = 1.5/5 · (V_r + V_l)) ≈ 0.699
YAW_RATE_GAIN = 15.0 / 4.0 * 0.102 * _DUTY_PER_MPS  # [-] steady yaw rate per unit of ``omega`` ≈ 0.4455
MAX_SPEED_MPS = 0.6  # [m/s] both wheels at full duty: u = 1.5/5 · 2
ACTUATION_DELAY_S = 0.15  # [s] the simulator's command delay (get_DB18_nominal(delay=0.15))
SPEED_TIME_CONSTANT_S = 0.2  # [s] 1/u1 of the PWM dynamics: the speed settles exponentially

AIM_M = 0.25  # [m] from the camera: the lane-centre point the steering heads for (the simulator's expert looks 0.25 m
#   ahead too). The tightest lane centre (a left curve's, radius ≈ 0.21 m: the expert's curvature there is 4.8/m) is
#   then ≈ 37° off the heading, inside the camera's ±45° view; 0.29 m (the image model's look-ahead) asks for 43°+

MAX_BEARING_DEG = 75.0  # [deg] the steering (aim-point bearing) limit. The tightest lane centre (a right curve's, radius
#   0.175 m) puts the aim AIM_M from the camera ~70° off the heading: pure pursuit then asks for curvature 5.7/m, which
#   the camera's ±45.7° edge (at most 4.0/m) cannot give

# -- body and lane (Duckietown appearance specification; tile 0.585 m) -------------------------
WHEEL_OUTER_HALF_TRACK_M = 0.065  # [m] centre line of the robot to the outer face of a wheel (13 cm wide)
ROBOT_FRONT_M = CAMERA_AHEAD_M  # [m] axle to the front bumper (the simulator's box ends at the camera)
# offsets from the simulator's lane centre, + = right (get_lane_pos2().dist's sign as it really is)
WHITE_INNER_M = 0.128  # [m] inner edge of the white (outer) tape
WHITE_OUTER_M = 0.1755  # [m] outer edge of the white tape: the edge of the road
YELLOW_INNER_M = -0.108  # [m] near edge of the yellow centre line
YELLOW_OUTER_M = -0.126  # [m] far edge of the yellow line: beyond it is the oncoming lane


def duckiebot_camera(width_px: int = DEFAULT_FRAME_PX[0], height_px: int = DEFAULT_FRAME_PX[1]) -> CameraModel:
    """The simulated Duckiebot camera at a resolution: square pixels, so fx = fy from the vertical FOV."""
    f = (height_px / 2.0) / math.tan(math.radians(CAMERA_VFOV_DEG) / 2.0)
    return CameraModel(width_px, height_px, f, f, width_px / 2.0, height_px / 2.0, (), CAMERA_HEIGHT_M, CAMERA_PITCH_DEG)


def duckietown_lane() -> GroundLaneSpec:
    """The Duckietown road for the ground-plane lane model: 0.236 m between the inner edges of the yellow line and the
    white tape, fitted over the near 0.07-0.5 m, aiming AIM_M ahead."""
    return GroundLaneSpec(lane_width_m=WHITE_INNER_M - YELLOW_INNER_M, near_m=0.07, far_m=0.5, aim_m=AIM_M, max_bearing_deg=MAX_BEARING_DEG)


def duckiebot_limits(*, time_of_flight: bool = False) -> VehicleLimits:
    """A 1:20 Duckiebot: 0.5 m/s top speed, no range sensor (or a front time-of-flight sensor, 0.05–1.2 m).

    Braking: the speed decays with τ = 0.2 s after the 0.15 s delay, so a stop takes v·(0.15 + 0.2) m;
    planning with a 0.35 s reaction and 0.5 m/s² (v·0.35 + v²) covers it at every speed. The steering
    limit is MAX_BEARING_DEG: the ground-plane lane model places its aim point beyond the picture's edge
    (±45.7°) on tight curves; further round than that, the aim would lie beside the axle: no lane does that.
    """
    return VehicleLimits(
        max_speed_mps=0.5, max_decel_mps2=0.5, reaction_time_s=ACTUATION_DELAY_S + SPEED_TIME_CONSTANT_S, stop_margin_m=0.05,
        max_steering_deg=MAX_BEARING_DEG, has_ultrasonic=time_of_flight, has_qr_localisation=False,
        width_m=2 * WHEEL_OUTER_HALF_TRACK_M,  # its own 13 cm: a route's path is searched for objects (and paint) this wide
        ultrasonic_min_range_m=TOF_MIN_RANGE_M, ultrasonic_max_range_m=TOF_MAX_RANGE_M,
    )


TOF_MIN_RANGE_M = 0.05  # [m] VL53L0X-class time-of-flight sensor (newer Duckiebots): closer reads as this
TOF_MAX_RANGE_M = 1.2  # [m] its indoor range; beyond it nothing is in range
TOF_CONE_DEG = 25.0  # [deg] full opening angle


@dataclass(frozen=True)
class Action:
    """What DuckietownEnv.step takes, with the targets it came from."""

    vel: float  # [-] DuckietownEnv's velocity command
    omega: float  # [-] DuckietownEnv's angular command
    speed_mps: float  # [m/s] the speed asked for
    yaw_rate_rps: float  # [rad/s] the yaw rate asked for (+ = left)

    def as_list(self) -> list[float]:
        return [self.vel, self.omega]


def pursuit_curvature_per_m(bearing_deg: float, aim_m: float) -> float:
    """Curvature (1/m, + = left) of the arc from the axle through the aim point ``aim_m`` from the camera at ``bearing_deg``."""
    a = math.radians(max(-89.0, min(89.0, bearing_deg)))
    x = CAMERA_AHEAD_M + aim_m * math.cos(a)
    y = aim_m * math.sin(a)
    return 2.0 * y / (x * x + y * y)


def curvature_action(speed_mps: float, curvature_per_m: float) -> Action:
    """The DuckietownEnv action that settles at ``speed_mps`` on an arc of ``curvature_per_m`` (no reverse)."""
    v = max(0.0, speed_mps)
    omega = v * curvature_per_m
    return Action(v / SPEED_GAIN, omega / YAW_RATE_GAIN, v, omega)


def steering_action(steering_deg: float, speed_mps: float, aim_m: float) -> Action:
    """fearguard's command (steering bearing, speed) → the action: pure pursuit to the aim point."""
    return curvature_action(speed_mps, pursuit_curvature_per_m(steering_deg, aim_m))
