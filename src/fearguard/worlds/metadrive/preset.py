"""The MetaDrive road-car preset: its camera, its limits, and how a fearguard command drives MetaDrive's car.

Pure values and functions (no simulator import), usable and testable without MetaDrive.

**Camera** (MetaDrive 0.4.3's RGB camera as its environment mounts it, ``BaseEnv.setup_sensors``): on the ego's
chassis node at (0, 0.8, 1.5) m (right, forward, up) with HPR (0, 0.59681, 0) — 0.8 m ahead of the car's centre,
pitched 0.597° *up* — through a Panda3D lens set to ``setFov(60)``: 60° horizontal, the vertical from the buffer's
aspect (46.83° at 4:3), square pixels, principal point centred. The chassis node rides 0.595 m above the road, so
the camera is 2.095 m up (read off the scene graph of a reset world: camera at z = 2.095, the road at z = 0).
Verified by projecting the lane lines of a straight road through this model and finding them in the rendered frame
(tests/worlds/metadrive/test_metadrive_sim.py). The camera is MetaDrive's, not a choice: a judge's harness sees the
same picture; 2.1 m is a high mount (a van's roof), and the slight upward pitch puts the horizon 2.9 px below the
image centre at 320×240.

**Actuation.** MetaDrive's action is ``[steer, throttle]`` in [−1, 1]: the front road wheels turn
``steer × max_steering`` (40° for its default car; steer > 0 turns left, as fearguard's angles), and throttle > 0
drives the engine (force × throttle, none above 80 km/h), throttle < 0 brakes. fearguard's steering angle is the
*bearing of the aim point* on the lane centre (vision/steering.py: the direction a pure-pursuit driver heads for),
not a wheel angle, so it is turned into one by pure pursuit: the aim point lies ``aim_m`` from the camera at bearing
α, i.e. at (x, y) = (REAR_AXLE_TO_CAMERA_M + aim_m·cos α, aim_m·sin α) from the rear axle; the arc through it has
κ = 2y / (x² + y²), and a bicycle model needs the wheel angle δ = atan(WHEELBASE_M · κ); steer = δ / 40°.
Speed: a proportional controller on the speed error with a feed-forward, throttle = clip(ROLLING_THROTTLE +
SPEED_GAIN · (v_target − v), −1, 1), held at full brake once the target is (near) zero — MetaDrive's car has no speed input, only forces.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, replace

import numpy as np

from fearguard.camera import CameraModel
from fearguard.vehicle import PRESETS, VehicleLimits

# -- simulation step (MetaDrive's defaults: physics 0.02 s, 5 physics steps per env step) ----------
PHYSICS_STEP_S = 0.02  # [s] physics_world_step_size
DECISION_REPEAT = 5  # [-] physics steps per env step
STEP_S = PHYSICS_STEP_S * DECISION_REPEAT  # [s] one env step: fearguard sees 10 frames/s
FRAME_RATE_HZ = 1.0 / STEP_S  # [1/s]
DEFAULT_FRAME_PX = (320, 240)  # [px] 4:3; 640×480 costs ~25 % more per step on Mesa

# -- camera (MetaDrive's RGB camera as its environment mounts it: see above) ---------------------------------
CAMERA_HFOV_DEG = 60.0  # [deg] lens.setFov(60) in ImageBuffer._create_camera: horizontal, the vertical follows the aspect
CAMERA_HEIGHT_M = 2.095  # [m] chassis node 0.595 m up + the sensor's 1.5 m
CAMERA_PITCH_DEG = -0.59681  # [deg] fearguard's pitch is + down; MetaDrive pitches the camera 0.59681° up
CAMERA_AHEAD_OF_CENTRE_M = 0.8  # [m] the sensor offset along the car

# -- MetaDrive's default car (DefaultVehicle, VehicleParameterSpace.BASE_VEHICLE) -----------------------------
MAX_STEERING_DEG = 40.0  # [deg] front road-wheel angle at |steer| = 1
FRONT_AXLE_M = 1.05234  # [m] centre to front axle (DefaultVehicle.FRONT_WHEELBASE)
REAR_AXLE_M = 1.4166  # [m] centre to rear axle (DefaultVehicle.REAR_WHEELBASE)
WHEELBASE_M = FRONT_AXLE_M + REAR_AXLE_M  # [m] 2.469
REAR_AXLE_TO_CAMERA_M = REAR_AXLE_M + CAMERA_AHEAD_OF_CENTRE_M  # [m]
CAR_LENGTH_M = 4.515  # [m] DefaultVehicle.DEFAULT_LENGTH
CAR_WIDTH_M = 1.852  # [m] DefaultVehicle.DEFAULT_WIDTH
CAMERA_BEHIND_FRONT_M = CAR_LENGTH_M / 2.0 - CAMERA_AHEAD_OF_CENTRE_M  # [m] 1.46: the camera's ranges less this are the gap
MAX_SPEED_MPS = 80.0 / 3.6  # [m/s] max_speed_km_h: the engine gives no force above it

# -- actuation -----------------------------------------------------------------------------------------------
SPEED_GAIN = 0.5  # [1/(m/s)] throttle per m/s of speed error: full throttle / brake from 2 m/s off the target
ROLLING_THROTTLE = 0.2  # [-] added while driving: MetaDrive keeps a brake of 2 on every wheel under throttle (its
#   _apply_throttle_brake), so a small throttle does not start the car (0.1-0.4 left it standing for 0.7 s)
HOLD_BELOW_MPS = 0.3  # [m/s] a target at or below this is "stand still": full brake
AIM_M = 9.0  # [m] from the camera: the lane steering's aim point (``HoughLaneSteering(camera, aim_m=AIM_M)``). Pure
#   pursuit cuts into a curve and swings out of it, more the farther it aims: on MetaDrive's tightest curves (R 25 m,
#   driven at <= 8.7 m/s under road_car's 3 m/s² lateral cap whatever the cruise) a kinematic pursuit leaves the lane
#   centre by 1.3 m aiming 16 m ahead (the image model's own look-ahead row at 320x240: seed 24 at traffic 0.15
#   side-swiped a car in the next lane so), by 0.4 m aiming 9 m ahead. One distance for every cruise: 0.9 s at 10 m/s
#   tracks without weaving at 20 m/s (seed 0: offset max 0.23 m), and 0.9 s of a 15 m/s cruise (13.5 m) swung seed 1
#   out of its R 25 m curve into the next lane's car where 9 m kept it within 0.63 m
CRUISE_MPS = 10.0  # [m/s] the default cruise (36 km/h): MetaDrive's traffic drives at 30 km/h (IDMPolicy.NORMAL_SPEED)

# -- radar-like range sensor (from the simulator's truth) ------------------------------------------------------
RADAR_MIN_RANGE_M = 0.3  # [m] the road_car preset's forward radar
RADAR_MAX_RANGE_M = 80.0  # [m] likewise: beyond it nothing is in range


def metadrive_camera(width_px: int = DEFAULT_FRAME_PX[0], height_px: int = DEFAULT_FRAME_PX[1]) -> CameraModel:
    """MetaDrive's RGB camera at a resolution: 60° horizontal field of view, square pixels, centred, 2.095 m up, 1.46 m
    behind the front bumper (its ranges are gaps, as the simulator's truth measures them)."""
    f = (width_px / 2.0) / math.tan(math.radians(CAMERA_HFOV_DEG) / 2.0)
    return CameraModel(width_px, height_px, f, f, width_px / 2.0, height_px / 2.0, (), CAMERA_HEIGHT_M, CAMERA_PITCH_DEG,
                       front_offset_m=CAMERA_BEHIND_FRONT_M)


def steering_wheelbase_m(aim_m: float = AIM_M) -> float:
    """The wheelbase under which fearguard's steering angle — the aim-point bearing α — obeys the bicycle model the
    policy uses (κ = tan α / L: the lateral speed limit, the lane check's predicted path).

    The car drives the pure-pursuit arc from its rear axle through the aim point, ``aim_m`` from the camera, the
    camera REAR_AXLE_TO_CAMERA_M ahead of the axle: κ = 2·aim·sin α / ((d + aim·cos α)² + (aim·sin α)²), so for small
    α, tan α / κ = (d + aim)² / (2·aim): 7.0 m at the 9 m aim (10.4 m at 16 m). With the car's own 2.469 m a 9.7°
    bearing (a 64 m arc) would read as a 14.5 m turn and cap the car at 6.6 m/s on a gentle curve (measured: seed 0,
    14.7 of 30 s under that cap, progress 79 % of the expert's).
    """
    return (REAR_AXLE_TO_CAMERA_M + aim_m) ** 2 / (2.0 * aim_m)


def metadrive_limits(*, radar: bool = False, aim_m: float = AIM_M) -> VehicleLimits:
    """MetaDrive's default car: the ``road_car`` preset where the two agree, MetaDrive's numbers where they differ.

    - ``max_speed_mps`` 22.2 (MetaDrive: no engine force above 80 km/h; road_car: 30);
    - ``wheelbase_m``: ``steering_wheelbase_m(aim_m)`` (7.0 m at the 9 m aim), the wheelbase for which the steering angle — an
      aim-point bearing, not a wheel angle — gives the true curvature (the car's own is WHEELBASE_M, 2.469 m, which
      the actuation uses); ``width_m`` 1.852 (DefaultVehicle; road_car: 1.8);
    - ``max_steering_deg`` 30: the aim-point bearing, not the wheel angle (the lane model's bearings stay well inside);
    - no range sensor unless ``radar`` (road_car assumes a 0.3–80 m radar; MetaDrive's camera car has none);
    - everything else as road_car: braking planned at 6 m/s² after 0.5 s, 1 m margin, 3 m/s² lateral, 60°/s.
    """
    return replace(PRESETS["road_car"], max_speed_mps=MAX_SPEED_MPS, wheelbase_m=steering_wheelbase_m(aim_m), width_m=CAR_WIDTH_M,
                   max_steering_deg=30.0, has_ultrasonic=radar, ultrasonic_min_range_m=RADAR_MIN_RANGE_M,
                   ultrasonic_max_range_m=RADAR_MAX_RANGE_M)


def lane_aim_m(camera: CameraModel, aim_m: float | None = AIM_M) -> float:
    """Ground distance from the camera to the image lane model's aim row: the row of ``aim_m`` held inside the road
    region (9 m at every MetaDrive resolution; None: the region's own look-ahead row, ~16 m at 320x240), as
    ``HoughLaneSteering(camera, aim_m=aim_m)`` aims."""
    from fearguard.vision.lanes import road_region
    from fearguard.vision.steering import lookahead_row

    region = road_region(camera.width_px, camera.height_px, camera)
    distance = camera.ground_range_m(lookahead_row(region, camera, aim_m))
    return distance if distance is not None else AIM_M


@dataclass(frozen=True)
class Action:
    """What MetaDrive's env.step takes, with the targets it came from."""

    steer: float  # [-1..1] front wheel angle / MAX_STEERING_DEG, + = left
    throttle: float  # [-1..1] + = engine, − = brake
    wheel_angle_deg: float  # [deg] the road-wheel angle asked for (+ = left)
    speed_target_mps: float  # [m/s]

    def as_list(self) -> list[float]:
        return [self.steer, self.throttle]


def pursuit_wheel_angle_deg(bearing_deg: float, aim_m: float) -> float:
    """Front wheel angle (deg, + left) of the bicycle-model arc from the rear axle through the aim point."""
    a = math.radians(max(-89.0, min(89.0, bearing_deg)))
    x = REAR_AXLE_TO_CAMERA_M + aim_m * math.cos(a)
    y = aim_m * math.sin(a)
    kappa = 2.0 * y / (x * x + y * y)
    return math.degrees(math.atan(WHEELBASE_M * kappa))


def route_bearing_deg(points_xy: np.ndarray, camera_xy: tuple[float, float], heading_rad: float, aim_m: float) -> float | None:
    """Pure pursuit's aim on a route: the bearing (deg, + = left) from the camera, heading ``heading_rad``, of the first
    route point (in order along the route) at least ``aim_m`` from it; None when the route ends nearer. MetaDrive's
    angles count left-positive from its x axis, as its steering does."""
    pts = np.asarray(points_xy, dtype=float).reshape(-1, 2)
    rel = pts - np.asarray(camera_xy, dtype=float)
    far = np.flatnonzero(np.hypot(rel[:, 0], rel[:, 1]) >= aim_m)
    if far.size == 0:
        return None
    dx, dy = rel[far[0]]
    return math.degrees(wrap_rad(math.atan2(dy, dx) - heading_rad))


def wrap_rad(angle_rad: float) -> float:
    """The angle in [−π, π)."""
    return (angle_rad + math.pi) % (2.0 * math.pi) - math.pi


def throttle_for(speed_target_mps: float, speed_mps: float) -> float:
    """The proportional speed controller: full brake when the target is standing still."""
    if speed_target_mps <= HOLD_BELOW_MPS:
        return -1.0
    return max(-1.0, min(1.0, ROLLING_THROTTLE + SPEED_GAIN * (speed_target_mps - speed_mps)))


def steering_action(steering_deg: float, speed_target_mps: float, speed_mps: float, aim_m: float) -> Action:
    """fearguard's command (aim-point bearing, speed target) and the car's speed → MetaDrive's action."""
    wheel = pursuit_wheel_angle_deg(steering_deg, aim_m)
    steer = max(-1.0, min(1.0, wheel / MAX_STEERING_DEG))
    target = max(0.0, speed_target_mps)
    return Action(steer, throttle_for(target, speed_mps), wheel, target)
