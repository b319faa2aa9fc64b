"""The simulated world of one scenario: ego car, road, traffic, obstacles, camera and sensors, stepped in time.

    world = World(load_scenario("scenarios/night.toml"), seed=7)
    sens = world.sense()                      # what the car's sensors give now (frame, ultrasonic, odometer, speed)
    world.advance(steering_deg, speed_mps)    # one step of dt = 1 / camera fps under the car's actuator limits
    tr = world.truth()                        # ground truth now (pose, lane, gap, TTC, collision, ...)

Everything random derives from ``np.random.default_rng(seed)`` through SeedSequence children, one per
subsystem (scenery, camera noise, ultrasonic, odometer, speed), so the same scenario and seed give
byte-identical frames and truth whatever else runs. After a collision the ego car stays where it hit
(speed 0): a crash ends the drive, and the metrics count it once.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, replace

import numpy as np

from fearguard.camera import CameraModel
from fearguard.readings import finite_reading
from fearguard.sim import sensors
from fearguard.sim.bicycle import BicycleLimits, BicycleState, step
from fearguard.sim.boxes import Box, footprint, overlaps
from fearguard.sim.lighting import light_at
from fearguard.sim.render import Renderer
from fearguard.sim.road import Road
from fearguard.sim.scenario_values import Scenario
from fearguard.sim.traffic import traffic_speed_mps

SUBSYSTEMS = ("scenery", "camera_noise", "ultrasonic", "odometer", "speed")  # SeedSequence children, in this order
CLOSING_EPS_MPS = 1e-6  # [m/s] below this closing speed the TTC is inf
_BOXES_FROM = 7  # index of the first box centre in ``World._located`` (after 4 corners, axle, bumper, camera)


@dataclass(frozen=True)
class SimSensors:
    """What the car's sensors report at one instant."""

    t_s: float
    frame_bgr: np.ndarray  # H×W×3 uint8
    ultrasonic_range_m: float | None  # inf = nothing in range, None = dropout or no sensor
    odometer_m: float
    speed_mps: float
    qr_visible: tuple[str, ...]  # payloads readable in the frame (truth, for tests)


@dataclass(frozen=True)
class Truth:
    """Ground truth at one instant (ego pose is the rear axle; gaps are bumper to bumper)."""

    t_s: float
    x_m: float
    y_m: float
    yaw_deg: float
    s_m: float
    lateral_m: float  # + = left of the lane centre
    speed_mps: float
    gap_m: float  # nearest vehicle/obstacle ahead in the ego lane, inf if none
    closing_speed_mps: float  # ego speed along the road − that object's speed (+ = closing)
    ttc_s: float  # gap / closing speed, inf when not closing
    collided: bool  # the ego car has hit something (stays True)
    in_lane: bool  # all four corners of the ego car inside the ego lane
    lat_accel_mps2: float
    finished: bool  # end of the route or of the scenario's duration
    lead_visible: bool  # the nearest vehicle ahead in the ego lane is within draw distance and in the image


class World:
    """One scenario's world, stepped by ``advance``; ``sense`` and ``truth`` describe the current instant."""

    def __init__(self, scenario: Scenario, seed: int | None = None) -> None:
        self.scenario = scenario
        self.seed = scenario.seed if seed is None else seed
        rngs = [np.random.default_rng(child) for child in np.random.SeedSequence(self.seed).spawn(len(SUBSYSTEMS))]
        scenery_rng, noise_rng, self._ultrasonic_rng, self._odometer_rng, self._speed_rng = rngs
        self.road = Road(scenario.road)
        v = scenario.vehicle  # the camera sits forward_m ahead of the rear axle, the front bumper v.front_m
        self.camera: CameraModel = replace(scenario.camera.model(), front_offset_m=max(0.0, v.front_m - scenario.camera.forward_m))
        self.dt_s = scenario.dt_s
        self._limits = BicycleLimits(v.wheelbase_m, v.max_accel_mps2, v.max_brake_mps2, v.max_steering_deg, v.max_steering_rate_dps)
        ego = scenario.ego
        x, y = self.road.point_at(ego.start_s_m, ego.lateral_m)
        yaw = float(self.road.heading_at(ego.start_s_m)) + math.radians(ego.heading_deg)
        self._ego = BicycleState(float(x), float(y), yaw, ego.speed_mps, 0.0)
        self._traffic_s = [t.start_s_m for t in scenario.vehicles]
        self._traffic_v = [traffic_speed_mps(t, 0.0) for t in scenario.vehicles]
        self._obstacles = tuple(self._obstacle_box(i) for i in range(len(scenario.obstacles)))
        self._renderer = Renderer(scenario, self.road, self.camera, scenery_rng, noise_rng)
        self._step = 0
        self._odometer_m = 0.0
        self._collided = False
        self._last_frame: np.ndarray | None = None
        self._sensed: SimSensors | None = None
        self._truth: Truth | None = None
        self._boxes: list[Box] | None = None
        self._where: tuple[np.ndarray, np.ndarray] | None = None
        self._check_collision()

    # -- time ----------------------------------------------------------------------------------
    @property
    def t_s(self) -> float:
        return self._step * self.dt_s

    @property
    def ego(self) -> BicycleState:
        return self._ego

    @property
    def renderer(self) -> Renderer:
        """The camera renderer (benchmarks draw recorded poses with it directly)."""
        return self._renderer

    def advance(self, steering_deg: float, speed_target_mps: float) -> None:
        """One step of dt: the car follows the commands within its limits; traffic follows its profiles.

        A non-finite steering command holds the current angle; a non-finite speed target brakes to 0.
        """
        steer = finite_reading(steering_deg)
        target = finite_reading(speed_target_mps)
        steer = self._ego.steering_deg if steer is None else steer
        target = 0.0 if target is None else target
        t = self.t_s
        before = self._ego
        if self._collided:
            self._ego = BicycleState(before.x_m, before.y_m, before.yaw_rad, 0.0, before.steering_deg)
        else:
            self._ego = step(before, steer, target, self.dt_s, self._limits)
        moved = math.hypot(self._ego.x_m - before.x_m, self._ego.y_m - before.y_m)
        noise = self.scenario.sensors.odometer_noise_fraction if self.scenario.sensors else 0.0
        self._odometer_m += sensors.odometer_step_m(moved, noise, self._odometer_rng)
        after = [traffic_speed_mps(v, t + self.dt_s) for v in self.scenario.vehicles]  # trapezoid rule over the step
        self._traffic_s = [s + 0.5 * (v0 + v1) * self.dt_s for s, v0, v1 in zip(self._traffic_s, self._traffic_v, after, strict=True)]
        self._traffic_v = after
        self._step += 1
        self._sensed, self._truth, self._boxes, self._where = None, None, None, None
        self._check_collision()

    # -- geometry ------------------------------------------------------------------------------
    def _obstacle_box(self, i: int) -> Box:
        o = self.scenario.obstacles[i]
        x, y = self.road.point_at(o.s_m, o.lateral_m)
        return Box(float(x), float(y), float(self.road.heading_at(o.s_m)), o.length_m, o.width_m, o.height_m, o.colour, False)

    def boxes(self) -> list[Box]:
        """Every obstacle and other vehicle now, as boxes on the ground (obstacles first)."""
        if self._boxes is not None:
            return self._boxes
        out = list(self._obstacles)
        vehicles = self.scenario.vehicles
        if vehicles:
            spec = self.scenario.road
            lateral = np.array([spec.lane_offset_m(v.lane) + v.lateral_m for v in vehicles])
            x, y, h = self.road.pose_at(np.array(self._traffic_s))
            x, y = x - lateral * np.sin(h), y + lateral * np.cos(h)
            for k, v in enumerate(vehicles):
                out.append(Box(float(x[k]), float(y[k]), float(h[k]), v.length_m, v.width_m, v.height_m, v.colour, True))
        self._boxes = out
        return out

    def _speeds(self) -> list[float]:
        """Speeds of the boxes (in ``boxes()`` order)."""
        return [0.0] * len(self._obstacles) + list(self._traffic_v)

    def ego_corners(self) -> np.ndarray:
        """The ego car's footprint corners (4, 2) in world x, y."""
        v, e = self.scenario.vehicle, self._ego
        return footprint(e.x_m, e.y_m, e.yaw_rad, -v.rear_overhang_m, v.front_m, v.width_m)

    def _front_m(self) -> tuple[float, float]:
        v, e = self.scenario.vehicle, self._ego
        d = v.front_m
        return e.x_m + d * math.cos(e.yaw_rad), e.y_m + d * math.sin(e.yaw_rad)

    def camera_pose(self) -> tuple[float, float, float]:
        """Camera position (world m) and heading (rad)."""
        e, d = self._ego, self.scenario.camera.forward_m
        return e.x_m + d * math.cos(e.yaw_rad), e.y_m + d * math.sin(e.yaw_rad), e.yaw_rad

    def _check_collision(self) -> None:
        if self._collided:
            return
        corners = self.ego_corners()
        centre = corners.mean(axis=0)
        reach = float(np.hypot(*(corners[0] - centre)))
        for b in self.boxes():
            if math.hypot(b.x_m - centre[0], b.y_m - centre[1]) > reach + math.hypot(b.length_m, b.width_m) / 2:
                continue  # bounding circles apart: no need to intersect the rectangles
            if overlaps(corners, b.corners()):
                self._collided = True
                return

    def _located(self) -> tuple[np.ndarray, np.ndarray]:
        """(s, lateral) of the ego corners (4), rear axle, front bumper centre, camera, then every box centre: one projection."""
        if self._where is None:
            corners = self.ego_corners()
            fx, fy = self._front_m()
            cx, cy, _ = self.camera_pose()
            e = self._ego
            boxes = self.boxes()
            self._where = self.road.project(np.concatenate([corners[:, 0], [e.x_m, fx, cx], [b.x_m for b in boxes]]),
                                            np.concatenate([corners[:, 1], [e.y_m, fy, cy], [b.y_m for b in boxes]]))
        return self._where

    # -- observation ---------------------------------------------------------------------------
    def sense(self) -> SimSensors:
        """The sensors now (computed once per step; calling again returns the same readings)."""
        if self._sensed is not None:
            return self._sensed
        t = self.t_s
        faults = self.scenario.faults
        boxes = self.boxes()
        if sensors.in_intervals(t, faults.camera.black):
            frame, qr = np.zeros((self.camera.height_px, self.camera.width_px, 3), np.uint8), ()
        elif sensors.in_intervals(t, faults.camera.frozen) and self._last_frame is not None:
            frame, qr = self._last_frame.copy(), ()
        else:
            pose = self.camera_pose()
            s_cam = float(self._located()[0][6])
            rendered = self._renderer.render(pose, s_cam, boxes, light_at(self.scenario.lighting, s_cam, t))
            frame, qr = rendered.bgr, rendered.qr_visible
            if faults.camera.frozen:  # kept apart: the caller may draw on the frame it was given
                self._last_frame = frame.copy()
        spec = self.scenario.sensors
        ultrasonic = None
        if spec is not None and self.scenario.vehicle.has_ultrasonic:
            true_m = sensors.true_range_m(self._front_m(), self._ego.yaw_rad, spec.cone_deg, boxes)
            ultrasonic = sensors.ultrasonic_reading(true_m, t, spec, faults.ultrasonic, self._ultrasonic_rng)
        speed_noise = spec.speed_noise_mps if spec is not None else 0.0
        speed = sensors.speed_reading_mps(self._ego.speed_mps, speed_noise, self._speed_rng)
        self._sensed = SimSensors(t, frame, ultrasonic, self._odometer_m, speed, qr)
        return self._sensed

    def truth(self) -> Truth:
        """Ground truth now."""
        if self._truth is not None:
            return self._truth
        sc, e = self.scenario, self._ego
        half_lane = sc.road.lane_width_m / 2
        s_pts, lat_pts = self._located()
        s_m, lateral = float(s_pts[4]), float(lat_pts[4])
        s_front = float(s_pts[5])
        heading = float(self.road.heading_at(s_m))
        along = e.speed_mps * math.cos(e.yaw_rad - heading)
        gap, closing, lead_visible = self._nearest_ahead(s_front, along)
        ttc = 0.0 if gap <= 0.0 else (gap / closing if closing > CLOSING_EPS_MPS else math.inf)
        t = self.t_s
        self._truth = Truth(
            t_s=t, x_m=e.x_m, y_m=e.y_m, yaw_deg=math.degrees(math.remainder(e.yaw_rad, 2 * math.pi)), s_m=s_m, lateral_m=lateral,
            speed_mps=e.speed_mps, gap_m=gap, closing_speed_mps=closing if math.isfinite(gap) else 0.0, ttc_s=ttc,
            collided=self._collided, in_lane=bool(np.all(np.abs(lat_pts[:4]) <= half_lane)),
            lat_accel_mps2=e.lat_accel_mps2(sc.vehicle.wheelbase_m),
            finished=t >= sc.duration_s - 1e-9 or s_front >= self.road.length_m, lead_visible=lead_visible,
        )
        return self._truth

    def _nearest_ahead(self, s_front: float, along_mps: float) -> tuple[float, float, bool]:
        """(gap, closing speed) of the nearest box ahead in the ego lane, and whether the nearest vehicle there is in view."""
        boxes = self.boxes()
        if not boxes:
            return math.inf, 0.0, False
        half_lane = self.scenario.road.lane_width_m / 2
        s_all, lat_all = self._located()
        s_obj, lat_obj = s_all[_BOXES_FROM:], lat_all[_BOXES_FROM:]
        gap, closing = math.inf, 0.0
        lead: tuple[float, Box] | None = None
        for b, s, lat, speed in zip(boxes, s_obj, lat_obj, self._speeds(), strict=True):
            if abs(lat) - b.width_m / 2 >= half_lane or s + b.length_m / 2 <= s_front:
                continue
            g = max(0.0, float(s) - b.length_m / 2 - s_front)
            if g < gap:
                gap, closing = g, along_mps - speed
            if b.is_vehicle and (lead is None or g < lead[0]):
                lead = (g, b)
        visible = lead is not None and lead[0] <= self.scenario.render_far_m and self._in_image(lead[1])
        return gap, closing, visible

    def _in_image(self, box: Box) -> bool:
        """The centre of the box's rear face projects inside the frame."""
        cx, cy, yaw = self.camera_pose()
        rx = box.x_m - box.length_m / 2 * math.cos(box.yaw_rad) - cx
        ry = box.y_m - box.length_m / 2 * math.sin(box.yaw_rad) - cy
        fwd = rx * math.cos(yaw) + ry * math.sin(yaw)
        left = -rx * math.sin(yaw) + ry * math.cos(yaw)
        up = box.height_m / 2 - (self.camera.mount_height_m or 0.0)
        u, v, front = self.camera.project_points(np.array([fwd]), np.array([left]), np.array([up]))
        return bool(front[0] and 0 <= u[0] < self.camera.width_px and 0 <= v[0] < self.camera.height_px)
