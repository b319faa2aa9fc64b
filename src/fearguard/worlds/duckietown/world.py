"""gym-duckietown as a world for fearguard: the robot's camera, its ground truth, obstacles, a time-of-flight sensor.

The simulator is imported lazily (``open_world``), so fearguard's core never needs it. Running it
here takes three fixes, all applied at run time without editing installed files:
- pyglet 1.5 renders headless through EGL (``pyglet.options["headless"] = True``; needs Mesa's EGL).
- duckietown-world's PWM dynamics pass ``[array([v]), 0.0]`` to ``geometry.se2_from_linear_angular``,
  which numpy ≥ 1.24 rejects as a ragged array: a wrapper flattens the one-element arrays first.
- ``gym_duckietown`` is imported before ``geometry`` (otherwise geometry wants the ``decorator`` package).
- Domain randomisation draws the camera's height, angle and field of view as 1-element arrays, which
  ``gluPerspective`` (ctypes) rejects: they are turned into numbers.

Ground truth uses the simulator's own functions: ``get_lane_pos2`` (its ``dist`` and ``angle_deg`` are
+ to the RIGHT of the lane centre and direction, the opposite of its docstring; fearguard's heading
error is + to the left, as its angles), ``closest_curve_point``, ``_valid_pose`` ("invalid
pose": a wheel off the drivable tiles, or contact) and ``_collision`` (contact with an object).
The renderer is noise-free; the camera frame gets Gaussian sensor noise (σ grey levels, seeded)
so a standing robot does not give byte-identical frames, as no real camera does.
"""

from __future__ import annotations

import contextlib
import difflib
import io
import logging
import math
from dataclasses import dataclass
from typing import Any

import numpy as np

from fearguard.errors import MapError, SimulatorMissing  # defined in errors.py, importable here
from fearguard.worlds.duckietown.preset import (
    CAMERA_AHEAD_M,
    FRAME_RATE_HZ,
    ROBOT_FRONT_M,
    TOF_CONE_DEG,
    TOF_MAX_RANGE_M,
    TOF_MIN_RANGE_M,
    Action,
)

SENSOR_NOISE_GREY = 2.0  # [grey levels] σ of the camera's sensor noise
WALK_STEP_M = 0.05  # [m] step when walking along the lane centre (look-ahead points, obstacle placement)
OBSTACLE_HEIGHT_M = {"duck": 0.06, "cone": 0.08, "duckiebot": 0.12}  # [m] as the bundled maps use them
OBSTACLE_MESH = {"duck": "duckie", "cone": "cone", "duckiebot": "duckiebot"}  # our names → the simulator's kinds
TOF_RAYS = 11  # [-] rays across the time-of-flight cone
ROUTE_LIMIT_M = 60.0  # [m] the longest route measured (a lap of the largest bundled loops is ~30 m)
JUNCTION_KINDS = ("3way", "4way")  # the simulator's intersection tiles (kind prefixes)
ROUTE_BEHIND_DEG = 90.0  # [deg] a route aim point further round than this from the camera's axis lies behind it
JUNCTION_AHEAD_M = 0.3  # [m] the route is known from this far before a junction tile: the stop line and the approach
#   where the lane model loses the lane (a Duckiebot at a stop line knows the junction from its AprilTag sign)


@dataclass(frozen=True)
class Truth:
    """The simulator's ground truth after a step (world axes: x east, y north, yaw + counter-clockwise)."""

    t_s: float
    x_m: float
    y_m: float
    yaw_rad: float
    speed_mps: float
    lane_offset_m: float  # + = right of the lane centre; NaN when not in a lane
    heading_error_deg: float  # + = pointing left of the lane direction; NaN when not in a lane
    progress_m: float  # along the lane direction since the start
    invalid_pose: bool  # the simulator's own check: off the drivable tiles, or in contact
    collided: bool  # contact with an object
    obstacle_gap_m: float  # ground distance from the front bumper to the added obstacle (inf: none)


_PATCHED = False
_SCALAR_SETTINGS = ("camera_height", "camera_angle", "camera_fov_y")  # drawn as 1-element arrays; GL wants numbers


def _simulator() -> Any:
    """Import gym_duckietown (headless, with the numpy shim) once; a clear error if it is not installed."""
    global _PATCHED
    try:
        import pyglet

        pyglet.options["headless"] = True
        pyglet.options["debug_gl"] = False  # no glGetError after every GL call (~10 % of a step)
        with contextlib.redirect_stderr(io.StringIO()), contextlib.redirect_stdout(io.StringIO()):  # gym's banner, pyglet's options
            import gym_duckietown.simulator as sim  # first: it disables PyContracts, which geometry needs otherwise
        import geometry  # kept out of the block above: an import sorter must not move it before the simulator
    except ImportError as exc:
        raise SimulatorMissing(
            f"the Duckietown simulator is not importable here ({exc}); create its environment with "
            "`bash .ci/duckietown.sh` and run fearguard from it (.venv-duckietown/bin/fearguard)"
        ) from None
    if not _PATCHED:
        original = geometry.se2_from_linear_angular

        def se2_from_linear_angular(linear: Any, angular: Any) -> Any:
            flat = [float(np.asarray(x, dtype=float).reshape(-1)[0]) for x in linear]
            return original(flat, float(np.asarray(angular, dtype=float).reshape(-1)[0]))

        geometry.se2_from_linear_angular = se2_from_linear_angular
        from gym_duckietown.randomization.randomizer import Randomizer

        draw = Randomizer.randomize

        def randomize(self: Any, rng: Any) -> dict:
            settings = draw(self, rng)
            for key in _SCALAR_SETTINGS:
                if key in settings:
                    settings[key] = float(np.asarray(settings[key], dtype=float).reshape(-1)[0])
            return settings

        Randomizer.randomize = randomize
        for name in ("gym-duckietown", "duckietown_world", "geometry", "commons", "typing", "nodes", "aido_schemas", "zuper_ipce"):
            logging.getLogger(name).setLevel(logging.ERROR)
        _PATCHED = True
    return sim


def map_names() -> list[str]:
    """The maps the installed duckietown-world ships."""
    _simulator()
    from duckietown_world.resources import list_maps  # type: ignore[import-not-found]

    return sorted(list_maps())


class DuckietownWorld:
    """One robot in one map: step it with an Action, read its camera and its ground truth.

    ``render=False`` skips the rendering of every step (90 % of its cost) for a controller that uses
    only the ground truth; ``frame_bgr`` then keeps returning the first frame.
    """

    def __init__(self, map_name: str, *, width_px: int, height_px: int, seed: int = 0, domain_rand: bool = False,
                 noise_grey: float = SENSOR_NOISE_GREY, start_tile: tuple[int, int] | None = None, render: bool = True) -> None:
        sim = _simulator()
        from gym_duckietown.envs import DuckietownEnv

        known = map_names()
        if map_name not in known:
            close = difflib.get_close_matches(map_name, known, n=3)
            hint = f"did you mean {', '.join(close)}? " if close else ""
            raise MapError(f"map {map_name!r} is not one of the simulator's {len(known)} maps; {hint}"
                           "see `fearguard duckietown --list-maps`")
        self._sim = sim
        with contextlib.redirect_stderr(io.StringIO()):
            self.env = DuckietownEnv(
                map_name=map_name, domain_rand=domain_rand, camera_width=width_px, camera_height=height_px,
                seed=seed, max_steps=10**9, frame_rate=FRAME_RATE_HZ, accept_start_angle_deg=4,
            )
        self.map_name = map_name
        self.dt_s = 1.0 / FRAME_RATE_HZ
        self._noise = np.random.default_rng(np.random.SeedSequence([seed, 20]))
        self._noise_grey = noise_grey
        self._obstacle: Any = None
        self._start_tile = start_tile
        self.obs_rgb = self._reset()
        if not render:  # a controller that never looks (the ground-truth expert): physics only, the first frame kept
            self.env.render_obs = lambda *args, **kwargs: self.obs_rgb
        self._progress_m = 0.0
        self._last_pos = np.array(self.env.cur_pos, dtype=float)

    # -- start ----------------------------------------------------------------------------------
    def _reset(self) -> np.ndarray:
        """Reset, then place the robot on the lane centre of the start tile, heading along the lane."""
        env = self.env
        tile = self._pick_start_tile()
        point, tangent = self._best_start(tile)
        i, j = tile["coords"]
        ts = env.road_tile_size
        env.start_pose = [[float(point[0] - i * ts), 0.0, float(point[2] - j * ts)], _angle_of(tangent)]
        env.user_tile_start = (i, j)
        with contextlib.redirect_stderr(io.StringIO()):
            return env.reset()

    def _pick_start_tile(self) -> dict:
        env = self.env
        if self._start_tile is not None:
            tile = env._get_tile(*self._start_tile)
            if tile is None or not tile["drivable"]:
                raise MapError(f"start tile {self._start_tile} of map {self.map_name!r} is not a drivable tile")
            return tile
        if env.start_tile is not None:
            return env.start_tile
        straights = [t for t in env.drivable_tiles if t["kind"].startswith("straight")]
        return (straights or env.drivable_tiles)[0]

    def _best_start(self, tile: dict) -> tuple[np.ndarray, np.ndarray]:
        """The middle of the tile's lane curve that leads furthest along drivable road (a dead end: the other way)."""
        best: tuple[float, np.ndarray, np.ndarray] | None = None
        for cps in tile["curves"]:
            t = 0.5
            point = self._sim.bezier_point(cps, t)
            tangent = self._sim.bezier_tangent(cps, t)
            tangent = tangent / np.linalg.norm(tangent)
            reach = self._reach_m(point, tangent, 15.0)
            if best is None or reach > best[0] + 1e-9:
                best = (reach, point, tangent)
        assert best is not None  # a drivable tile has curves
        return best[1], best[2]

    def _reach_m(self, point: np.ndarray, tangent: np.ndarray, limit_m: float) -> float:
        walked = 0.0
        while walked < limit_m:
            nxt = self.walk(point, tangent, WALK_STEP_M * 4)
            if nxt is None:
                break
            point, tangent = nxt
            walked += WALK_STEP_M * 4
        return walked

    def route_m(self, limit_m: float = ROUTE_LIMIT_M) -> tuple[float, bool]:
        """Length of the lane ahead from the start: (one lap, True) on a loop, (to the lane's end, False) otherwise."""
        env = self.env
        start, tangent = env.closest_curve_point(env.cur_pos, env.cur_angle)
        point, walked = np.asarray(start, dtype=float), 0.0
        while walked < limit_m:
            nxt = self.walk(point, tangent, WALK_STEP_M)
            if nxt is None:
                return walked, False
            point, tangent = nxt
            walked += WALK_STEP_M
            if walked > 1.0 and np.linalg.norm(point - start) < WALK_STEP_M:
                return walked, True
        return walked, False

    def walk(self, point: np.ndarray, tangent: np.ndarray, distance_m: float) -> tuple[np.ndarray, np.ndarray] | None:
        """The lane-centre point and tangent ``distance_m`` further along the lane (None: the lane ends)."""
        env = self.env
        p, tan = np.asarray(point, dtype=float), np.asarray(tangent, dtype=float)
        steps = max(1, math.ceil(distance_m / WALK_STEP_M))
        for _ in range(steps):
            guess = p + tan * (distance_m / steps)
            cp, ct = env.closest_curve_point(guess, _angle_of(tan))
            if cp is None:
                return None
            p, tan = np.asarray(cp, dtype=float), np.asarray(ct, dtype=float) / np.linalg.norm(ct)
        return p, tan

    # -- obstacles --------------------------------------------------------------------------------
    def add_obstacle(self, kind: str, ahead_m: float) -> tuple[float, float]:
        """A static duck, cone or Duckiebot on the lane centre ``ahead_m`` ahead of the front bumper; its (x, z)."""
        if kind not in OBSTACLE_MESH:
            raise ValueError(f"obstacle {kind!r}: choose one of {', '.join(OBSTACLE_MESH)}")
        env = self.env
        point, tangent = env.closest_curve_point(env.cur_pos, env.cur_angle)
        found = self.walk(point, tangent, ahead_m + ROBOT_FRONT_M)
        if found is None:
            raise MapError(f"map {self.map_name!r}: the lane ends before {ahead_m} m ahead; no room for the obstacle")
        pos, tan = found
        from gym_duckietown.objects import WorldObj
        from gym_duckietown.objmesh import get_mesh

        mesh = get_mesh(OBSTACLE_MESH[kind]) if kind != "duckiebot" else self._sim.get_duckiebot_mesh("red")
        desc = {"kind": OBSTACLE_MESH[kind], "mesh": mesh, "pos": np.array([pos[0], 0.0, pos[2]]),
                "angle": _angle_of(tan) + math.pi / 2, "scale": OBSTACLE_HEIGHT_M[kind] / mesh.max_coords[1],
                "optional": False, "static": True}
        obj = WorldObj(desc, False, self._sim.SAFETY_RAD_MULT)
        obj.color = [1.0, 1.0, 1.0, 1.0]
        env.objects.append(obj)
        self._obstacle = obj
        self._rebuild_collidables()
        self.obs_rgb = env.render_obs()
        return float(pos[0]), float(pos[2])

    def remove_obstacle(self) -> None:
        """Take the added obstacle away (a person picking the duck up)."""
        if self._obstacle is not None:
            self.env.objects.remove(self._obstacle)
            self._obstacle = None
            self._rebuild_collidables()

    @property
    def has_obstacle(self) -> bool:
        return self._obstacle is not None

    def _rebuild_collidables(self) -> None:
        """The simulator's collision arrays (built once at map load) for the objects there are now."""
        env = self.env
        static = [o for o in env.objects if o.static and o.kind != "trafficlight"]
        env.collidable_centers = np.array([o.pos for o in static]) if static else []
        env.collidable_corners = np.stack([o.obj_corners.T for o in static]) if static else []
        env.collidable_norms = np.stack([o.obj_norm for o in static]) if static else []
        env.collidable_safety_radii = np.array([o.safety_radius for o in static]) if static else []

    # -- stepping and sensing ---------------------------------------------------------------------
    def step(self, action: Action) -> Truth:
        """Apply the action for one simulator step; the new camera frame is in ``frame_bgr()``."""
        env = self.env
        before = np.array(env.cur_pos, dtype=float)
        _, tangent = env.closest_curve_point(env.cur_pos, env.cur_angle)
        with contextlib.redirect_stderr(io.StringIO()):
            self.obs_rgb, _, _, _ = env.step(action.as_list())
        after = np.array(env.cur_pos, dtype=float)
        if tangent is not None:
            self._progress_m += float(np.dot(after - before, np.asarray(tangent) / np.linalg.norm(tangent)))
        return self.truth()

    def frame_bgr(self) -> np.ndarray:
        """The camera frame as fearguard takes it (BGR uint8), with the sensor noise."""
        frame = self.obs_rgb[:, :, ::-1].astype(np.float32)
        if self._noise_grey > 0:
            frame += self._noise.normal(0.0, self._noise_grey, frame.shape).astype(np.float32)
        return np.clip(np.rint(frame), 0, 255).astype(np.uint8)

    def truth(self) -> Truth:
        env, sim = self.env, self._sim
        pos, angle = env.cur_pos, env.cur_angle
        try:
            lp = env.get_lane_pos2(pos, angle)
            offset, heading = float(lp.dist), -float(lp.angle_deg)  # its angle is + to the right, like its dist
        except sim.NotInLane:
            offset = heading = math.nan
        corners = sim.get_agent_corners(pos, angle)
        return Truth(
            t_s=float(env.timestamp), x_m=float(pos[0]), y_m=float(-pos[2]), yaw_rad=float(angle), speed_mps=float(env.speed),
            lane_offset_m=offset, heading_error_deg=heading, progress_m=self._progress_m,
            invalid_pose=not env._valid_pose(pos, angle), collided=bool(env._collision(corners)),
            obstacle_gap_m=self._gap_m(corners),
        )

    def _gap_m(self, agent_corners: np.ndarray) -> float:
        if self._obstacle is None:
            return math.inf
        return polygon_gap_m(np.asarray(agent_corners, dtype=float), np.asarray(self._obstacle.obj_corners, dtype=float))

    def tof_range_m(self) -> float:
        """A front time-of-flight reading from the ground truth: nearest object in its cone (inf: none in range)."""
        env = self.env
        origin = np.array([env.cur_pos[0], env.cur_pos[2]]) + CAMERA_AHEAD_M * _dir2(env.cur_angle)
        half = math.radians(TOF_CONE_DEG / 2)
        dirs = np.array([_dir2(env.cur_angle + a) for a in np.linspace(-half, half, TOF_RAYS)])
        best = math.inf
        for obj in env.objects:
            if obj.visible:
                best = min(best, ray_polygon_range_m(origin, dirs, np.asarray(obj.obj_corners, dtype=float)))
        if best > TOF_MAX_RANGE_M:
            return math.inf
        return max(TOF_MIN_RANGE_M, best)

    def expert_curvature(self, lookahead_m: float) -> float:
        """Ground-truth pure pursuit: curvature (1/m, + left) of the arc to the lane centre ``lookahead_m`` ahead."""
        aim = self._lane_point_ahead(lookahead_m)
        if aim is None:
            return 0.0
        x, y = aim
        dist2 = x * x + y * y
        return 0.0 if dist2 < 1e-9 else 2.0 * y / dist2

    def _lane_point_ahead(self, distance_m: float) -> tuple[float, float] | None:
        """The lane-centre point ``distance_m`` along the simulator's curve from the robot's nearest, in the robot's axes
        (ahead of the axle, left; m); None off the lane. The expert's pure-pursuit target and the route's aim point."""
        env = self.env
        point, tangent = env.closest_curve_point(env.cur_pos, env.cur_angle)
        if point is None:
            return None
        found = self.walk(point, tangent, distance_m)
        target = found[0] if found is not None else point
        # cartesian axes (x east, y = −z north), heading a counter-clockwise
        dx, dy = float(target[0] - env.cur_pos[0]), -float(target[2] - env.cur_pos[2])
        c, s = math.cos(env.cur_angle), math.sin(env.cur_angle)
        return c * dx + s * dy, -s * dx + c * dy

    def route_bearing_deg(self, aim_m: float) -> float | None:
        """The route's steering through a junction: the bearing (deg, + left) from the camera of the lane-centre point
        ``aim_m`` further along the simulator's curve — the way the expert goes — while the robot is on a junction tile
        or ``JUNCTION_AHEAD_M`` before one; None elsewhere (between junctions the robot has its lane to follow).

        It stands in for a Duckiebot's intersection navigation: at the stop line the AprilTag sign says which junction
        this is, and the chosen turn is driven from the map (the Duckietown stack's open-loop or tag-localised turn)."""
        env = self.env
        point, tangent = env.closest_curve_point(env.cur_pos, env.cur_angle)
        if point is None:
            return None
        ahead = self.walk(point, tangent, JUNCTION_AHEAD_M)
        if not (self._on_junction(env.cur_pos) or (ahead is not None and self._on_junction(ahead[0]))):
            return None
        aim = self._lane_point_ahead(aim_m)
        return None if aim is None else route_bearing_of(aim)

    def _on_junction(self, pos: np.ndarray) -> bool:
        tile = self.env._get_tile(*self.env.get_grid_coords(pos))
        return tile is not None and str(tile["kind"]).startswith(JUNCTION_KINDS)

    def close(self) -> None:
        with contextlib.suppress(Exception):  # closing a headless GL context can fail harmlessly at exit
            self.env.close()


def route_bearing_of(aim: tuple[float, float]) -> float | None:
    """The bearing (deg, + left) from the camera of a route's aim point (m, in the robot's axes: ahead of the axle,
    left); None for a point behind the camera. In a junction the simulator's nearest curve can switch to another lane's
    (regress_4way_drivable under randomised light: the aim jumped from +30° to ±175°, and the route, clipped to the
    steering range, swung the robot off the road in 2.5 s): a route behind the robot is no route to drive."""
    bearing = math.degrees(math.atan2(aim[1], aim[0] - CAMERA_AHEAD_M))
    return bearing if abs(bearing) <= ROUTE_BEHIND_DEG else None


def _angle_of(tangent: np.ndarray) -> float:
    """The simulator's heading angle for a direction in its x–z plane (dir = (cos a, 0, −sin a))."""
    return math.atan2(-float(tangent[2]), float(tangent[0]))


def _dir2(angle: float) -> np.ndarray:
    """Heading direction in the simulator's (x, z) plane."""
    return np.array([math.cos(angle), -math.sin(angle)])


def ray_polygon_range_m(origin: np.ndarray, dirs: np.ndarray, corners: np.ndarray) -> float:
    """Nearest hit of rays (unit directions, N×2) from ``origin`` on a polygon's edges (corners K×2); inf if none."""
    best = math.inf
    k = len(corners)
    for n in range(k):
        a, b = corners[n], corners[(n + 1) % k]
        e = b - a
        for d in dirs:
            den = d[0] * e[1] - d[1] * e[0]
            if abs(den) < 1e-12:
                continue
            w = a - origin
            t = (w[0] * e[1] - w[1] * e[0]) / den  # along the ray
            s = (w[0] * d[1] - w[1] * d[0]) / den  # along the edge
            if t >= 0 and 0 <= s <= 1:
                best = min(best, float(t))
    return best


def polygon_gap_m(a: np.ndarray, b: np.ndarray) -> float:
    """Smallest distance between two convex polygons (corners in order, K×2); 0 when they overlap."""
    if _inside_any(a, b) or _inside_any(b, a):
        return 0.0
    best = math.inf
    for p, q in ((a, b), (b, a)):
        for point in p:
            for n in range(len(q)):
                best = min(best, _point_segment_m(point, q[n], q[(n + 1) % len(q)]))
    return best


def _point_segment_m(p: np.ndarray, a: np.ndarray, b: np.ndarray) -> float:
    e = b - a
    t = 0.0 if not e.any() else float(np.clip(np.dot(p - a, e) / np.dot(e, e), 0.0, 1.0))
    return float(np.linalg.norm(p - (a + t * e)))


def _inside_any(points: np.ndarray, polygon: np.ndarray) -> bool:
    """Whether any point lies inside the convex polygon (either winding)."""
    k = len(polygon)
    for p in points:
        signs = []
        for n in range(k):
            a, b = polygon[n], polygon[(n + 1) % k]
            signs.append((b[0] - a[0]) * (p[1] - a[1]) - (b[1] - a[1]) * (p[0] - a[0]))
        if all(s >= 0 for s in signs) or all(s <= 0 for s in signs):
            return True
    return False
