"""MetaDrive as a world for fearguard: the ego car's camera, its ground truth, traffic, light, a lead and a radar.

``MetaDriveWorld`` is a ``World`` of the one driver loop (``drive/world.py``): ``sense()`` gives the camera frame, the
speed, (with a radar) the range and the navigation's route steering (``route_steering_deg``: where the markings end,
the supervisor may follow it, ``policy.route``) as a ``Sensed``; ``act(sensed, decision)`` drives one 0.1 s step — the
pure-pursuit arc to the controller's aim-point bearing at its speed (``preset.steering_action``), or the expert's own
MetaDrive action (``Decision.action``) — and returns the log's fields of the truth after it; the truth of every step
is kept (``samples``) for the metrics. MetaDrive is imported lazily (``headless.py`` applies every setting that makes
it render on Mesa), so fearguard's core never needs it.

Ground truth from MetaDrive's own objects: the ego's lane (``vehicle.lane``: lateral offset, + = left of the lane
centre — MetaDrive's ``local_coordinates`` lateral is + to the right, measured by steering left in the simulator — and
heading error, + = pointing left of the lane, as fearguard's angles), ``on_lane`` and ``crash_sidewalk``
(out of road), ``crash_vehicle`` / ``crash_object`` / ``crash_building`` / ``crash_human``, the navigation's
``travelled_length`` / ``total_length`` (progress and route completion), and the gap to the nearest vehicle or object
ahead in the ego's path (``path_gap``), with its speed and the time to collision. A drive ends when MetaDrive ends the
episode: a crash, leaving the road, or the destination.
"""

from __future__ import annotations

import contextlib
import io
import math
import time
from collections.abc import Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np

from fearguard.camera import CameraModel
from fearguard.drive.world import Decision, Outcome, Sensed
from fearguard.errors import FearguardError, MapError
from fearguard.supervisor import Observation
from fearguard.worlds.metadrive.headless import ENGINE_SETTINGS, MIN_CAMERA_PX, after_reset, repair_child_environment, simulator
from fearguard.worlds.metadrive.metrics import Sample
from fearguard.worlds.metadrive.preset import (
    AIM_M,
    CAMERA_AHEAD_OF_CENTRE_M,
    CAR_LENGTH_M,
    CAR_WIDTH_M,
    DECISION_REPEAT,
    FRAME_RATE_HZ,
    MAX_STEERING_DEG,
    PHYSICS_STEP_S,
    RADAR_MAX_RANGE_M,
    RADAR_MIN_RANGE_M,
    STEP_S,
    Action,
    lane_aim_m,
    metadrive_camera,
    route_bearing_deg,
    steering_action,
    wrap_rad,
)

DEFAULT_MAP = "SCSC"  # straight, curve, straight, curve: MetaDrive's block string (S straight, C circular curve)
LIGHTING = ("day", "dusk", "night")
LEADS = ("slower", "stopped")
RANGE_SENSORS = ("none", "radar")
TEST_SEEDS = range(5000, 6000)  # the independent test set (../shared/TEST-SET.md): never developed on
BLOCK_LETTERS = frozenset("SCrRXOTyY$PpB")  # MetaDrive's PG block IDs (pg_block ID of each block class)


@dataclass(frozen=True)
class Light:
    """One lighting preset as MetaDrive's renderer takes it (its ``render_pipeline`` daytime is not used headless).

    The sun is Panda3D's directional light (colour × intensity, colour temperature, direction from the scene
    origin); the ambient light colours every model; ``sky`` scales the sky box's colour. MetaDrive's terrain shader
    lights road and verge with the sun alone plus a constant (0.07, 0.07, 0.1): night dims the road through the sun.
    """

    sun: float  # [-] intensity of the directional light (MetaDrive's default: 1)
    sun_kelvin: float  # [K] its colour temperature (MetaDrive's default: 6800)
    sun_position: tuple[float, float, float]  # [m] where the light sits, looking at the origin (default (-100, 100, 100))
    ambient: float  # [-] grey level of the ambient light (default 0.25)
    sky: float  # [-] colour scale of the sky box (default 1)


LIGHTS = {
    "day": Light(sun=1.0, sun_kelvin=6800.0, sun_position=(-100.0, 100.0, 100.0), ambient=0.25, sky=1.0),  # MetaDrive's own
    "dusk": Light(sun=0.45, sun_kelvin=2800.0, sun_position=(-100.0, 100.0, 18.0), ambient=0.12, sky=0.45),  # low warm sun
    "night": Light(sun=0.06, sun_kelvin=4500.0, sun_position=(-100.0, 100.0, 100.0), ambient=0.03, sky=0.04),  # moonlight
}


@dataclass(frozen=True)
class Scenario:
    """What world to build: MetaDrive's map, traffic, light and seed, the camera size, an added lead, a radar."""

    map_blocks: str = DEFAULT_MAP
    lanes: int = 3
    lane_width_m: float = 3.5
    traffic_density: float = 0.05  # [vehicles per 10 m of lane, about] MetaDrive's traffic_density (its default 0.1)
    lighting: str = "day"
    seed: int = 0
    width_px: int = 320
    height_px: int = 240
    lead: str | None = None  # "slower": a car ahead driving lead_speed_mps; "stopped": a broken-down car
    lead_ahead_m: float = 35.0  # [m] from the ego's front bumper to the lead's rear, along the ego's lane (the first block: ≤ ~40 m)
    lead_speed_mps: float = 5.0  # [m/s] the slower lead's cruise
    range_sensor: str = "none"
    render: bool = True  # False: no camera (a controller that only reads the truth); frames are black
    route: bool = True  # the navigation's route steering in every Observation (``route_steering_deg``); False: none

    def __post_init__(self) -> None:
        blocks = self.map_blocks
        if not blocks or not set(blocks) <= BLOCK_LETTERS:
            raise ValueError(f"map {blocks!r}: a MetaDrive block string of {''.join(sorted(BLOCK_LETTERS))} (e.g. SCSC)")
        if self.lighting not in LIGHTS:
            raise ValueError(f"lighting {self.lighting!r}: choose one of {', '.join(LIGHTS)}")
        if self.lead is not None and self.lead not in LEADS:
            raise ValueError(f"lead {self.lead!r}: choose one of {', '.join(LEADS)}")
        if self.range_sensor not in RANGE_SENSORS:
            raise ValueError(f"range sensor {self.range_sensor!r}: choose one of {', '.join(RANGE_SENSORS)}")
        if not 1 <= self.lanes <= 6:
            raise ValueError(f"lanes must be 1..6, got {self.lanes}")
        if not (0.0 <= self.traffic_density <= 1.0):
            raise ValueError(f"traffic density must be in 0..1, got {self.traffic_density}")
        if self.seed < 0:
            raise ValueError(f"seed must be >= 0, got {self.seed}")
        if self.width_px < MIN_CAMERA_PX[0] or self.height_px < MIN_CAMERA_PX[1]:
            raise ValueError(f"camera {self.width_px}x{self.height_px}: at least {MIN_CAMERA_PX[0]}x{MIN_CAMERA_PX[1]} "
                             "(smaller cameras hang MetaDrive on Mesa)")
        require_positive(self, ("lane_width_m", "lead_ahead_m", "lead_speed_mps"))


def require_positive(values: Any, names: Sequence[str]) -> None:
    """ValueError naming the first of ``names`` whose value (an attribute of ``values``) is not a finite number > 0."""
    bad = next((n for n in names if not (math.isfinite(getattr(values, n)) and getattr(values, n) > 0)), None)
    if bad is not None:
        raise ValueError(f"{bad} must be a positive number, got {getattr(values, bad)!r}")


@dataclass(frozen=True)
class Truth:
    """MetaDrive's ground truth after a step (world axes: x, y in metres; heading + counter-clockwise)."""

    t_s: float
    x_m: float
    y_m: float
    heading_rad: float
    speed_mps: float
    lane_offset_m: float  # + = left of the ego lane's centre
    heading_error_deg: float  # + = pointing left of the lane direction
    lane_index: int  # 0 = the leftmost lane of the road
    lane_width_m: float
    out_of_road: bool  # MetaDrive: not on a lane of the road, or on the sidewalk
    on_solid_line: bool  # a wheel over a solid (continuous) line: the road edge or the yellow centre line
    over_centre_line: bool  # the car's centre beyond the yellow centre line (left of lane 0): in the oncoming lanes
    crashed_vehicle: bool
    crashed_object: bool  # cones, barriers, warning triangles, broken-down... MetaDrive's "object"
    crashed_other: bool  # a building, a pedestrian
    progress_m: float  # along the route since the start (MetaDrive's travelled_length)
    route_m: float  # the route's length to the destination
    route_completion: float  # [0..1]
    gap_m: float  # bumper to bumper to the nearest vehicle or object ahead in the ego's path (inf: none within range)
    lead_speed_mps: float  # its speed along the lane (NaN: none)
    ttc_s: float  # gap / closing speed (inf: not closing, or none)
    arrived: bool

    @property
    def crashed(self) -> bool:
        return self.crashed_vehicle or self.crashed_object or self.crashed_other


ROUTE_STEP_M = 0.5  # [m] the route's lanes sampled this finely for its aim point (0.5 m at 9 m: 3° at most)
ROUTE_REACH = 3.0  # [-] the route sampled this many aim distances ahead along its lanes (a U-turn's arc is π/2 of its chord)
GAP_RANGE_M = 150.0  # [m] the truth looks this far ahead for the vehicle ahead (the radar sees to RADAR_MAX_RANGE_M)


class MetaDriveWorld:
    """One ego car in one MetaDrive scenario, as a ``World``: ``sense`` its camera, ``act`` on a controller's decision.

    ``seconds`` bounds the drive (``sense`` returns None after it); MetaDrive ending the episode (a crash, off the
    road, arrived) ends it too (``Outcome.done``). ``samples`` holds the truth after every step, ``sim_ms`` the
    simulator's time per step (physics + rendering), for the metrics and the cost table. ``aim_m``: how far ahead the
    controller's lane steering aims (the value its ``HoughLaneSteering`` was given: the preset's 9 m; None: the road
    region's own row), the distance ``act`` turns an aim-point bearing into the pure-pursuit arc with.
    """

    fps: float = FRAME_RATE_HZ

    def __init__(self, scenario: Scenario, seconds: float = math.inf, aim_m: float | None = AIM_M) -> None:
        simulator()
        from metadrive.envs.metadrive_env import MetaDriveEnv

        self.scenario = s = scenario
        self.camera: CameraModel = metadrive_camera(s.width_px, s.height_px)
        self.aim_m = lane_aim_m(self.camera, aim_m)  # the lane steering's aim point: give it the same aim_m
        self.total = math.ceil(seconds * FRAME_RATE_HZ) if math.isfinite(seconds) else None  # steps; None: until MetaDrive ends
        self.env = MetaDriveEnv(_config(s))
        try:
            with contextlib.redirect_stdout(io.StringIO()):
                obs, _ = self.env.reset()
        except Exception as exc:  # MetaDrive's map generator asserts on impossible block strings
            self.close()
            raise MapError(f"MetaDrive could not build map {s.map_blocks!r} with {s.lanes} lanes (seed {s.seed}): "
                           f"{type(exc).__name__}: {exc}") from None
        finally:
            repair_child_environment()  # the engine has started: MetaDrive set PYTHONUTF8=on
        self.ego = self.env.agent
        if s.render:
            after_reset(self.env.engine)
        self._image = _image_of(obs, s)
        self._steps = 0
        self._ended = False
        self._end_info: dict[str, Any] = {}
        self.lead: Any = None
        if s.render and s.lighting != "day":  # day is MetaDrive's own light: nothing to change
            self._apply_light(LIGHTS[s.lighting])
        if s.lead is not None:
            self.lead = self._spawn_lead(s.lead, s.lead_ahead_m, s.lead_speed_mps)
        if s.render:
            self._image = self._render()  # the first frame with the light, the shadows off and the lead
        self._expert: Any = None
        self.route_now: float | None = None  # the route's steering at the last ``sense`` (vision/navigated.py reads it)
        self.start: Truth = self.truth()
        self.samples: list[Sample] = []
        self.sim_ms: list[float] = []

    # -- the World protocol --------------------------------------------------------------------------------------
    @property
    def done(self) -> bool:
        """MetaDrive ended the episode (a crash, off the road, arrived)."""
        return self._ended

    def sense(self) -> Sensed | None:
        """The camera frame (BGR uint8; None without a camera), the speed, the radar range and the route's steering
        (``Scenario.route``); None once the drive's time is up or MetaDrive ended the episode."""
        if self._ended or (self.total is not None and self._steps >= self.total):
            return None
        truth = self.truth()
        radar = radar_range_m(truth.gap_m) if self.scenario.range_sensor == "radar" else None
        frame = self._image if self.scenario.render else None
        route = self.route_now = self.route_steering_deg() if self.scenario.route else None
        obs = Observation(t_s=truth.t_s, speed_mps=truth.speed_mps, frame=frame, ultrasonic_range_m=radar,
                          route_steering_deg=route)
        return Sensed(self._steps, truth.t_s, obs, frame)

    def act(self, sensed: Sensed, decision: Decision) -> Outcome:
        """One step (0.1 s): the expert's own action when it gave one, else the pure-pursuit arc to the decision's
        aim-point bearing at its speed; the truth after it is kept and logged."""
        if isinstance(decision.action, Action):
            action = decision.action
        else:
            action = steering_action(decision.steering_deg, decision.speed_mps, float(self.ego.speed), self.aim_m)
        began = time.perf_counter()
        self.step(action.as_list())
        self.sim_ms.append(1e3 * (time.perf_counter() - began))
        t = self.truth()
        self.samples.append(Sample(t.t_s, t.speed_mps, t.lane_offset_m, t.on_solid_line, t.out_of_road, t.crashed_vehicle,
                                   t.crashed_object, t.crashed_other, t.progress_m, t.gap_m, t.ttc_s, t.over_centre_line))
        fields = dict(
            speed_target_mps=decision.speed_mps, applied_steering_deg=decision.steering_deg, steer=action.steer,
            throttle=action.throttle, speed_mps=t.speed_mps, progress_m=t.progress_m, route_completion=t.route_completion,
            lane_offset_m=t.lane_offset_m, heading_error_deg=t.heading_error_deg, lane_index=t.lane_index, x_m=t.x_m, y_m=t.y_m,
            out_of_road=t.out_of_road, on_solid_line=t.on_solid_line, over_centre_line=t.over_centre_line,
            crashed_vehicle=t.crashed_vehicle,
            crashed_object=t.crashed_object, gap_m=t.gap_m, lead_speed_mps=t.lead_speed_mps, ttc_s=t.ttc_s,
            radar_m=sensed.observation.ultrasonic_range_m, route_steering_deg=sensed.observation.route_steering_deg,
        )
        return Outcome(fields, f"v {t.speed_mps:.1f} m/s", t.speed_mps, self._ended)

    def close(self) -> None:
        with contextlib.suppress(Exception):  # closing a headless GL context can fail harmlessly at exit
            self.env.close()

    # -- stepping ------------------------------------------------------------------------------------------------
    def step(self, action: Sequence[float]) -> None:
        """One MetaDrive step with a raw [steer, throttle] action; a simulator error ends the drive with a clear error."""
        if self._ended:
            raise FearguardError("the MetaDrive episode has ended (crash, off the road or arrived); open a new world")
        try:
            obs, _, terminated, truncated, info = self.env.step([float(action[0]), float(action[1])])
        except Exception as exc:  # a simulator hiccup: the caller gets one clear error, not a Panda3D traceback
            self._ended = True
            raise FearguardError(f"MetaDrive failed at step {self._steps} ({type(exc).__name__}: {exc})") from exc
        self._steps += 1
        self._image = _image_of(obs, self.scenario)
        if terminated or truncated:
            self._ended = True
            self._end_info = dict(info)

    def expert_action(self, cruise_mps: float) -> Action:
        """MetaDrive's own IDM policy (lane keeping on the map's lanes, car following, lane changes) at ``cruise_mps``:
        the action it takes now (``act`` applies it)."""
        if self._expert is None:
            self._expert = _idm_policy(self.ego, self.scenario.seed, cruise_mps, lane_change=True)
        steer, throttle = (float(x) for x in self._expert.act())
        return Action(steer, throttle, steer * MAX_STEERING_DEG, cruise_mps)

    @property
    def t_s(self) -> float:
        return self._steps * STEP_S

    @property
    def end_reason(self) -> str | None:
        """Why MetaDrive ended the episode (crash_vehicle, out_of_road, arrive_dest, ...), None while it runs."""
        if not self._ended:
            return None
        keys = ("crash_vehicle", "crash_object", "crash_building", "crash_human", "crash_sidewalk", "out_of_road", "arrive_dest")
        return next((k for k in keys if self._end_info.get(k)), "ended")

    # -- truth ---------------------------------------------------------------------------------------------------
    def truth(self) -> Truth:
        v = self.ego
        lane = v.lane
        long, lat = lane.local_coordinates(v.position)
        lane_heading = lane.heading_theta_at(long)
        nav = v.navigation
        route = float(nav.total_length) if nav is not None else math.nan
        travelled = float(nav.travelled_length) if nav is not None else math.nan
        gap, lead_speed = self.path_gap()
        speed = float(v.speed)
        closing = speed - lead_speed if math.isfinite(lead_speed) else math.nan
        ttc = gap / closing if math.isfinite(gap) and math.isfinite(closing) and closing > 1e-3 else math.inf
        return Truth(
            t_s=self.t_s, x_m=float(v.position[0]), y_m=float(v.position[1]), heading_rad=float(v.heading_theta),
            speed_mps=speed, lane_offset_m=-float(lat), heading_error_deg=math.degrees(wrap_rad(float(v.heading_theta) - lane_heading)),
            lane_index=int(v.lane_index[-1]), lane_width_m=float(lane.width), out_of_road=bool((not v.on_lane) or v.crash_sidewalk),
            on_solid_line=bool(v.on_yellow_continuous_line or v.on_white_continuous_line),
            over_centre_line=int(v.lane_index[-1]) == 0 and -float(lat) > 0.5 * float(lane.width),
            crashed_vehicle=bool(v.crash_vehicle), crashed_object=bool(v.crash_object),
            crashed_other=bool(v.crash_building or v.crash_human), progress_m=travelled, route_m=route,
            route_completion=min(1.0, max(0.0, travelled / route)) if route > 0 else math.nan,
            gap_m=gap, lead_speed_mps=lead_speed, ttc_s=ttc, arrived=self._end_info.get("arrive_dest", False) is True,
        )

    def path_gap(self) -> tuple[float, float]:
        """Bumper-to-bumper gap (m) to the nearest vehicle or object ahead in the ego's path, and its speed along it.

        Each object is placed in the coordinates of the ego's lane and of the route's next lanes of the same index
        (MetaDrive's lane objects: straight and circular); it is in the path when its centre lies within half the two
        widths of the ego's lateral position; the gap is measured along the lanes. (inf, NaN) when nothing is within
        GAP_RANGE_M.
        """
        v = self.ego
        lanes = self._lanes_ahead()
        if not lanes:
            return math.inf, math.nan
        ego_long, ego_lat = lanes[0].local_coordinates(v.position)
        best, speed = math.inf, math.nan
        for obj in self._others():
            for offset, lane in _cumulative(lanes, ego_long):
                long, lat = lane.local_coordinates(obj.position)
                if not (-0.5 * CAR_LENGTH_M <= long <= lane.length + 0.5 * CAR_LENGTH_M):
                    continue
                width = float(getattr(obj, "WIDTH", CAR_WIDTH_M) or CAR_WIDTH_M)
                length = float(getattr(obj, "LENGTH", 1.0) or 1.0)
                if abs(lat - ego_lat) > 0.5 * (CAR_WIDTH_M + width):
                    continue
                gap = offset + long - 0.5 * (CAR_LENGTH_M + length)
                if -0.5 * CAR_LENGTH_M < gap < min(best, GAP_RANGE_M):
                    heading = lane.heading_theta_at(long)
                    velocity = np.asarray(getattr(obj, "velocity", (0.0, 0.0)), dtype=float)
                    best = max(0.0, gap)
                    speed = float(velocity[0] * math.cos(heading) + velocity[1] * math.sin(heading))
                break
        return best, speed

    def route_steering_deg(self) -> float | None:
        """The route's aim-point bearing (deg, + = left) ``aim_m`` from the camera: the centre of the route's lane at
        the ego's lane index, as MetaDrive's navigation knows it (the map and a perfect localisation: what MetaDrive's own
        agents observe as navigation). None when the known route ends nearer."""
        v = self.ego
        lanes = self._lanes_ahead()
        ego_long, _ = lanes[0].local_coordinates(v.position)
        heading = float(v.heading_theta)
        camera = (float(v.position[0]) + CAMERA_AHEAD_OF_CENTRE_M * math.cos(heading),
                  float(v.position[1]) + CAMERA_AHEAD_OF_CENTRE_M * math.sin(heading))
        reach = ROUTE_REACH * (CAMERA_AHEAD_OF_CENTRE_M + self.aim_m)  # along the lanes: enough for the tightest turn
        points = []
        for offset, lane in _cumulative(lanes, ego_long):
            points.extend(lane.position(float(s), 0.0) for s in np.arange(max(0.0, -offset), float(lane.length), ROUTE_STEP_M))
            if offset + float(lane.length) >= reach:
                break
        if not points:
            return None
        return route_bearing_deg(np.asarray(points, dtype=float)[:, :2], camera, heading, self.aim_m)

    def _others(self) -> list[Any]:
        objects = self.env.engine.get_objects(lambda o: o is not self.ego and hasattr(o, "position"))
        return [o for o in objects.values() if o is not self.ego]

    def _lanes_ahead(self) -> list[Any]:
        """The ego's lane, then the route's next lanes with the same index (as far as the navigation knows them)."""
        v = self.ego
        lanes = [v.lane]
        nav = v.navigation
        index = int(v.lane_index[-1])
        for ref in (getattr(nav, "current_ref_lanes", None), getattr(nav, "next_ref_lanes", None)):
            if ref:
                candidate = ref[min(index, len(ref) - 1)]
                if all(candidate is not lane for lane in lanes):
                    lanes.append(candidate)
        return lanes

    # -- scene set-up ----------------------------------------------------------------------------------------------
    def _apply_light(self, light: Light) -> None:
        from panda3d.core import LVector4

        engine = self.env.engine
        world_light = getattr(engine, "world_light", None)
        if world_light is None:
            return
        sun = world_light.direction_np
        sun.node().setColorTemperature(light.sun_kelvin)
        base = sun.node().getColor()
        sun.node().setColor(LVector4(base[0] * light.sun, base[1] * light.sun, base[2] * light.sun, 1.0))
        sun.setPos(*light.sun_position)
        sun.lookAt(0, 0, 0)
        world_light.ambient_np.node().setColor(LVector4(light.ambient, light.ambient, light.ambient, 1.0))
        if getattr(engine, "sky_box", None) is not None:
            engine.sky_box.origin.setColorScale(light.sky, light.sky, light.sky, 1.0)
        pssm = getattr(engine, "pssm", None)
        if pssm is not None:
            engine.render.set_shader_input("light_direction", light.sun_position)

    def _spawn_lead(self, kind: str, ahead_m: float, speed_mps: float) -> Any:
        """A car on the ego's lane ``ahead_m`` ahead of its bumper: standing (broken down) or driving slower (IDM)."""
        from metadrive.component.vehicle.vehicle_type import DefaultVehicle

        v = self.ego
        ego_long, _ = v.lane.local_coordinates(v.position)
        target = ego_long + 0.5 * CAR_LENGTH_M + ahead_m + 0.5 * CAR_LENGTH_M
        lane, long = None, target
        for offset, candidate in _cumulative(self._lanes_ahead(), 0.0):
            if target - offset <= candidate.length:
                lane, long = candidate, target - offset
                break
        if lane is None:
            raise MapError(f"the ego's lane ends before {ahead_m:g} m ahead; no room for the {kind} car (a longer first block?)")
        engine = self.env.engine
        manager = engine.traffic_manager
        config = {"spawn_lane_index": lane.index, "spawn_longitude": float(long), "enable_reverse": False}
        if kind == "stopped":
            car = manager.spawn_object(DefaultVehicle, vehicle_config=config)  # no policy: it stands
            car.set_break_down()
            car.set_static(True)
            return car
        config["spawn_velocity"] = [speed_mps, 0.0]
        config["spawn_velocity_car_frame"] = True
        car = manager.spawn_object(DefaultVehicle, vehicle_config=config)
        manager.add_policy(car.id, _idm_class(speed_mps, lane_change=False), car, self.scenario.seed + 1)
        manager._traffic_vehicles.append(car)
        return car

    def _render(self) -> np.ndarray:
        sensor = self.env.engine.get_sensor("rgb_camera")
        self.env.engine.taskMgr.step()
        return np.ascontiguousarray(sensor.perceive(to_float=False))


def radar_range_m(gap_m: float) -> float:
    """A radar-like forward range from the truth's gap: inf beyond RADAR_MAX_RANGE_M, at least RADAR_MIN_RANGE_M."""
    if not math.isfinite(gap_m) or gap_m > RADAR_MAX_RANGE_M:
        return math.inf
    return max(RADAR_MIN_RANGE_M, gap_m)


def _config(s: Scenario) -> dict[str, Any]:
    """MetaDrive's config for a scenario (ENGINE_SETTINGS make it render headless)."""
    from metadrive.component.sensors.rgb_camera import RGBCamera

    config: dict[str, Any] = dict(ENGINE_SETTINGS)
    vehicle: dict[str, Any] = {
        "show_navi_mark": False, "show_navigation_arrow": False, "show_dest_mark": False, "show_line_to_dest": False,
        "lidar": {"num_lasers": 0, "distance": 50}, "side_detector": {"num_lasers": 0}, "lane_line_detector": {"num_lasers": 0},
    }
    from metadrive.component.map.base_map import BaseMap
    from metadrive.component.map.pg_map import MapGenerateMethod

    map_config = {BaseMap.GENERATE_TYPE: MapGenerateMethod.BIG_BLOCK_SEQUENCE, BaseMap.GENERATE_CONFIG: s.map_blocks,
                  BaseMap.LANE_NUM: s.lanes, BaseMap.LANE_WIDTH: s.lane_width_m}
    config.update(
        map_config=map_config, traffic_density=s.traffic_density,
        start_seed=s.seed, num_scenarios=1, physics_world_step_size=PHYSICS_STEP_S, decision_repeat=DECISION_REPEAT,
        horizon=None, out_of_road_done=True, on_continuous_line_done=False, crash_vehicle_done=True, crash_object_done=True,
        crash_human_done=True, random_spawn_lane_index=False, vehicle_config=vehicle,
    )
    if s.render:
        vehicle["image_source"] = "rgb_camera"
        config.update(image_observation=True, norm_pixel=False, stack_size=1, sensors={"rgb_camera": (RGBCamera, s.width_px, s.height_px)})
    else:
        config.update(image_observation=False)
    return config


def _image_of(obs: Any, s: Scenario) -> np.ndarray:
    """The camera frame from MetaDrive's observation (already BGR uint8), or a black frame without a camera."""
    if isinstance(obs, dict) and "image" in obs:
        return np.ascontiguousarray(obs["image"][..., -1], dtype=np.uint8)
    return np.zeros((s.height_px, s.width_px, 3), np.uint8)


def _cumulative(lanes: Sequence[Any], start_long: float) -> list[tuple[float, Any]]:
    """(distance from the start position to each lane's beginning, lane): 0 − start_long for the first."""
    out, offset = [], -start_long
    for lane in lanes:
        out.append((offset, lane))
        offset += float(lane.length)
    return out


def _idm_class(cruise_mps: float, *, lane_change: bool) -> type:
    """MetaDrive's IDMPolicy cruising at ``cruise_mps`` (its own: 30 km/h), lane changes on or off."""
    from metadrive.policy.idm_policy import IDMPolicy

    class CruiseIDM(IDMPolicy):
        NORMAL_SPEED = cruise_mps * 3.6  # [km/h]

        def __init__(self, control_object: Any, random_seed: int) -> None:
            super().__init__(control_object, random_seed)
            self.target_speed = self.NORMAL_SPEED
            self.enable_lane_change = lane_change

    return CruiseIDM


def _idm_policy(vehicle: Any, seed: int, cruise_mps: float, *, lane_change: bool) -> Any:
    return _idm_class(cruise_mps, lane_change=lane_change)(vehicle, seed)
