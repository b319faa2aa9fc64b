"""Scenario files (TOML): what the simulated world contains, validated into frozen dataclasses.

A scenario names a scale ("model" 1:10 car or "road" car; see ``scales.py`` for every default), the
camera, the rule file, the ego vehicle's limits, the road as a list of straight/arc segments with
their markings, other vehicles with speed profiles and braking events, static obstacles, QR boards,
lighting zones, sensor faults, a steering-estimator fault, and the expectations a safe run meets.
The format, key by key, is in docs/scenarios.md. Errors name the file, the line and the key path.

This module is the loading half: the values themselves live in ``scenario_values.py`` (the world, the
renderer and the metrics import them from there, without the TOML reader) and are re-exported here.
"""

from __future__ import annotations

import math
import re
from pathlib import Path
from typing import Any

from fearguard.errors import ScenarioError
from fearguard.files.reader import Table, number_list, read_toml
from fearguard.fuzzy.loader import bundled_rules_path
from fearguard.policy import Mode, Strategy
from fearguard.readings import whole_number
from fearguard.sim.scales import SCALES, scale_defaults
from fearguard.sim.scenario_values import (
    COLOURS,
    EXPECTATION_NAMES,
    LANES,
    LIGHTING_KINDS,
    MARKING_COLOURS,
    MARKING_STYLES,
    SIDES,
    STEERING_FAULT_KINDS,
    SURFACES,
    BrakingEvent,
    CameraFaults,
    CameraSpec,
    EgoStart,
    Expectations,
    Faults,
    LightingZone,
    Marking,
    ModeBy,
    ObstacleSpec,
    QrBoardGroup,
    RoadSpec,
    Scenario,
    Segment,
    SensorSpec,
    SpeedCap,
    SteeringFault,
    StrategyBy,
    TrafficVehicle,
    UltrasonicFaults,
    VehicleProfile,
)

__all__ = [
    "BrakingEvent",
    "CameraFaults",
    "CameraSpec",
    "EgoStart",
    "Expectations",
    "Faults",
    "LightingZone",
    "Marking",
    "ModeBy",
    "ObstacleSpec",
    "QrBoardGroup",
    "RoadSpec",
    "Scenario",
    "ScenarioError",
    "Segment",
    "SensorSpec",
    "SpeedCap",
    "SteeringFault",
    "StrategyBy",
    "TrafficVehicle",
    "UltrasonicFaults",
    "VehicleProfile",
    "load_scenario",
]

MAX_DURATION_S = 3600.0  # [s] a longer run is almost surely a unit mistake
ROUTE_NAME = re.compile(r"^[A-Za-z0-9_-]{1,16}$")  # route names go inside QR payloads (no ';' or '=')


_TOP_KEYS = ("name", "description", "seed", "duration_s", "scale", "rules", "camera", "vehicle", "ego", "road", "vehicles",
             "obstacles", "qr_boards", "lighting", "sensors", "faults", "expect")
_EXPECT_KEYS = EXPECTATION_NAMES
_ROAD_KEYS = ("lane_width_m", "marking_width_m", "dash_length_m", "dash_gap_m", "shoulder_m", "lanes_left", "lanes_right",
              "left_marking", "left_colour", "right_marking", "right_colour", "surface", "outer_marking", "outer_colour", "segments")
_SEGMENT_KEYS = ("kind", "length_m", "radius_m", "turn", "left_marking", "left_colour", "right_marking", "right_colour", "surface")

# -- loading -----------------------------------------------------------------------------------
BUNDLED = Path(__file__).resolve().parents[1] / "scenarios"  # the scenario library shipped in the package


def find_scenario(spec: str | Path) -> Path:
    """A scenario's file from what a user types: a path, or the name of a bundled scenario (``night``)."""
    path = Path(spec)
    if path.is_file() or path.suffix == ".toml" or len(path.parts) > 1:
        return path  # a path (load_scenario names it when it is missing)
    bundled = BUNDLED / f"{path.name}.toml"
    if bundled.is_file():
        return bundled
    names = ", ".join(p.stem for p in sorted(BUNDLED.glob("*.toml")))
    raise ScenarioError(str(spec), "", f"no such file, and no bundled scenario of that name; bundled: {names} "
                        "(`fearguard scenarios` lists them)")


def load_scenario(path: str | Path) -> Scenario:
    """Read and validate a scenario file; a wrong file raises ScenarioError naming the file, line and key."""
    path = Path(path)
    data, src = read_toml(path, ScenarioError, "give the path of a scenario such as scenarios/clear_straight.toml")
    return _build(Table(src, data, "", _TOP_KEYS), path)


def _build(top: Table, path: Path) -> Scenario:
    scale = top.string("scale", "model", choices=SCALES)
    d = scale_defaults(scale)
    duration = top.number("duration_s", 20.0, low=0.0, high=MAX_DURATION_S, strict_low=True, unit="s")
    camera = _camera(top.table("camera", d["camera"]), d["camera"])
    # a car localises by QR only where there are boards to read: absent otherwise (never signalled by NaN)
    vehicle_defaults = {**d["vehicle"], "has_qr_localisation": bool(top.data.get("qr_boards"))}
    vehicle = _vehicle(top.table("vehicle", vehicle_defaults), vehicle_defaults)
    if "road" not in top.data:
        raise top.fail("road", "missing [road] table; add [road] and at least one [[road.segments]] (kind = \"straight\", length_m = ...)")
    road = _road(top.table("road", _ROAD_KEYS), d["road"])
    ego = _ego(top.table("ego", ("start_s_m", "lateral_m", "heading_deg", "speed_mps")), vehicle)
    ego_front_s = ego.start_s_m + vehicle.front_m
    return Scenario(
        path=path,
        name=top.string("name", path.stem),
        description=top.string("description", ""),
        seed=top.integer("seed", 0, low=0),
        duration_s=duration,
        scale=scale,
        camera=camera,
        rules_path=_rules(top, path, d["rules"]["name"]),
        vehicle=vehicle,
        ego=ego,
        road=road,
        vehicles=tuple(_traffic(t, road, d["traffic"], ego_front_s) for t in top.tables("vehicles", _TRAFFIC_KEYS)),
        obstacles=tuple(_obstacle(t, d["obstacle"]) for t in top.tables("obstacles", _OBSTACLE_KEYS)),
        qr_boards=tuple(_qr(t, d["qr"]) for t in top.tables("qr_boards", _QR_KEYS)),
        lighting=tuple(_lighting(t) for t in top.tables("lighting", _LIGHTING_KEYS)),
        sensors=_sensors(top.table("sensors", ("ultrasonic", "odometer")), d),
        faults=_faults(top.table("faults", ("ultrasonic", "camera", "steering"))),
        expectations=_expectations(top.table("expect", _EXPECT_KEYS)),
        render_far_m=float(d["render"]["far_m"]),
        shadow_radius_m=tuple(d["render"]["shadow_radius_m"]),  # type: ignore[arg-type]
    )


def _rules(top: Table, path: Path, default: str) -> Path:
    name = top.string("rules", default)
    bundled = bundled_rules_path(f"{name}.toml")
    if "/" not in name and "\\" not in name and not name.endswith(".toml"):
        if bundled.is_file():
            return bundled
        raise top.fail("rules", f"no bundled rule base {name!r}; use \"default\", \"road_car\" or a path relative to the scenario")
    candidate = (path.parent / name).resolve()
    if not candidate.is_file():
        raise top.fail("rules", f"rule file {candidate} does not exist; give a path relative to the scenario file")
    return candidate


def _camera(t: Table, d: dict[str, Any]) -> CameraSpec:
    return CameraSpec(
        fps=t.number("fps", d["fps"], low=1.0, high=1000.0, unit="1/s"),
        width_px=t.integer("width_px", d["width_px"], low=16, high=4096),
        height_px=t.integer("height_px", d["height_px"], low=16, high=4096),
        hfov_deg=t.number("hfov_deg", d["hfov_deg"], low=10.0, high=170.0, unit="deg"),
        mount_height_m=t.number("mount_height_m", d["mount_height_m"], low=0.0, strict_low=True, unit="m"),
        pitch_deg=t.number("pitch_deg", d["pitch_deg"], low=0.0, high=60.0, unit="deg"),
        forward_m=t.number("forward_m", d["forward_m"], unit="m"),
    )


def _vehicle(t: Table, d: dict[str, Any]) -> VehicleProfile:
    values: dict[str, Any] = {}
    for key, default in d.items():
        if isinstance(default, bool):
            values[key] = t.boolean(key, default)
        elif key in ("reaction_time_s", "stop_margin_m"):
            values[key] = t.number(key, default, low=0.0)
        else:
            values[key] = t.number(key, default, low=0.0, strict_low=True)
    profile = VehicleProfile(**values)
    if profile.length_m < profile.wheelbase_m:
        raise t.fail("length_m", f"must be >= wheelbase_m ({profile.wheelbase_m:g} m), got {profile.length_m:g}")
    if profile.max_brake_mps2 < profile.max_decel_mps2:
        raise t.fail("max_brake_mps2", f"must be >= max_decel_mps2 ({profile.max_decel_mps2:g}): the supervisor must not plan "
                                       f"with more braking than the car has, got {profile.max_brake_mps2:g}")
    return profile


def _ego(t: Table, vehicle: VehicleProfile) -> EgoStart:
    return EgoStart(
        start_s_m=t.number("start_s_m", 0.0, low=0.0, unit="m"),
        lateral_m=t.number("lateral_m", 0.0, unit="m"),
        heading_deg=t.number("heading_deg", 0.0, low=-90.0, high=90.0, unit="deg"),
        speed_mps=t.number("speed_mps", vehicle.cruise_speed_mps, low=0.0, unit="m/s"),
    )


def _marking(t: Table, prefix: str, default: Marking) -> Marking:
    return Marking(t.string(f"{prefix}_marking", default.style, choices=MARKING_STYLES),
                   t.string(f"{prefix}_colour", default.colour, choices=MARKING_COLOURS))


def _road(t: Table, d: dict[str, Any]) -> RoadSpec:
    lane = t.number("lane_width_m", d["lane_width_m"], low=0.0, strict_low=True, unit="m")
    mark = t.number("marking_width_m", d["marking_width_m"], low=0.0, strict_low=True, unit="m")
    if mark >= lane / 4:
        raise t.fail("marking_width_m", f"must be below a quarter of lane_width_m ({lane:g} m), got {mark:g}")
    left_default = _marking(t, "left", Marking("solid", "white"))
    right_default = _marking(t, "right", Marking("solid", "white"))
    surface = t.string("surface", "asphalt", choices=SURFACES)
    lanes_left = t.integer("lanes_left", 0, low=0, high=3)
    lanes_right = t.integer("lanes_right", 0, low=0, high=3)
    shoulder = t.number("shoulder_m", d["shoulder_m"], low=0.0, unit="m")
    if "segments" not in t.data:
        raise t.fail("segments", "missing; add at least one [[road.segments]] with kind = \"straight\" or \"arc\" and length_m")
    segments = []
    for s in t.tables("segments", _SEGMENT_KEYS):
        kind = s.string("kind", choices=("straight", "arc"))
        length = s.number("length_m", low=0.0, strict_low=True, unit="m")
        if kind == "straight":
            for key in ("radius_m", "turn"):
                if s.has(key):
                    raise s.fail(key, f"only arcs have {key}; remove it or set kind = \"arc\"")
            radius, turn = math.inf, None
        else:
            radius = s.number("radius_m", low=0.0, strict_low=True, unit="m")
            turn = s.string("turn", choices=("left", "right"))
            inside = (lanes_left if turn == "left" else lanes_right) + 0.5
            inner = radius - inside * lane - shoulder
            if inner <= 0:
                raise s.fail("radius_m", f"too tight: the inner road edge would be at radius {inner:.2f} m; use radius_m > "
                                         f"{inside * lane + shoulder:.2f} for this lane width")
        segments.append(Segment(kind, length, radius, turn, _marking(s, "left", left_default), _marking(s, "right", right_default),
                                s.string("surface", surface, choices=SURFACES)))
    if not segments:
        raise t.fail("segments", "is empty; add at least one [[road.segments]]")
    return RoadSpec(
        lane_width_m=lane, marking_width_m=mark,
        dash_length_m=t.number("dash_length_m", d["dash_length_m"], low=0.0, strict_low=True, unit="m"),
        dash_gap_m=t.number("dash_gap_m", d["dash_gap_m"], low=0.0, strict_low=True, unit="m"),
        shoulder_m=shoulder, lanes_left=lanes_left, lanes_right=lanes_right,
        outer=Marking(t.string("outer_marking", "solid", choices=MARKING_STYLES),
                      t.string("outer_colour", "white", choices=MARKING_COLOURS)),
        segments=tuple(segments),
    )


_TRAFFIC_KEYS = ("lane", "start_gap_m", "start_s_m", "lateral_m", "speed_mps", "speed_profile", "braking", "length_m", "width_m",
                 "height_m", "colour")


def _traffic(t: Table, road: RoadSpec, d: dict[str, Any], ego_front_s: float) -> TrafficVehicle:
    lane = t.string("lane", "ego", choices=LANES)
    if (lane == "left" and road.lanes_left == 0) or (lane == "right" and road.lanes_right == 0):
        raise t.fail("lane", f"the road has no {lane} lane; set road.lanes_{lane} = 1 or put the vehicle in another lane")
    length = t.number("length_m", d["length_m"], low=0.0, strict_low=True, unit="m")
    if t.has("start_gap_m") == t.has("start_s_m"):
        raise t.fail("start_gap_m", "give exactly one of start_gap_m (ahead of the ego front bumper, rear bumper to bumper) or start_s_m")
    if t.has("start_gap_m"):
        start = ego_front_s + t.number("start_gap_m", unit="m") + length / 2
    else:
        start = t.number("start_s_m", unit="m")
    if t.has("speed_mps") == t.has("speed_profile"):
        raise t.fail("speed_mps", "give exactly one of speed_mps (constant) or speed_profile = [[t_s, speed_mps], ...]")
    if t.has("speed_mps"):
        profile: tuple[tuple[float, float], ...] = ((0.0, t.number("speed_mps", low=0.0, unit="m/s")),)
    else:
        profile = _profile(t)
    braking = []
    for b in t.tables("braking", ("t_s", "decel_mps2", "to_speed_mps")):
        braking.append(BrakingEvent(b.number("t_s", low=0.0, unit="s"), b.number("decel_mps2", low=0.0, strict_low=True, unit="m/s²"),
                                    b.number("to_speed_mps", 0.0, low=0.0, unit="m/s")))
    return TrafficVehicle(
        lane=lane, start_s_m=start, lateral_m=t.number("lateral_m", 0.0, unit="m"), speed_profile=profile,
        braking=tuple(sorted(braking, key=lambda e: e.t_s)), length_m=length,
        width_m=t.number("width_m", d["width_m"], low=0.0, strict_low=True, unit="m"),
        height_m=t.number("height_m", d["height_m"], low=0.0, strict_low=True, unit="m"),
        colour=t.string("colour", "blue", choices=COLOURS),
    )


def _profile(t: Table) -> tuple[tuple[float, float], ...]:
    value = t.data["speed_profile"]
    points: list[tuple[float, float]] = []
    ok = isinstance(value, list) and len(value) > 0
    for i, p in enumerate(value if ok else []):
        xy = number_list(p, 2)
        if xy is None or xy[1] < 0 or (points and xy[0] <= points[-1][0]):
            raise t.src.error(f"{t.path_of('speed_profile')}[{i}]", "each point must be [t_s, speed_mps] with speed >= 0 and t_s "
                                                                    f"increasing, got {p!r}")
        points.append((xy[0], xy[1]))
    if not ok:
        raise t.fail("speed_profile", f"must be a non-empty list of [t_s, speed_mps] points, got {value!r}")
    return tuple(points)


_OBSTACLE_KEYS = ("s_m", "lateral_m", "length_m", "width_m", "height_m", "colour")


def _obstacle(t: Table, d: dict[str, Any]) -> ObstacleSpec:
    return ObstacleSpec(
        s_m=t.number("s_m", low=0.0, unit="m"), lateral_m=t.number("lateral_m", 0.0, unit="m"),
        length_m=t.number("length_m", d["length_m"], low=0.0, strict_low=True, unit="m"),
        width_m=t.number("width_m", d["width_m"], low=0.0, strict_low=True, unit="m"),
        height_m=t.number("height_m", d["height_m"], low=0.0, strict_low=True, unit="m"),
        colour=t.string("colour", "orange", choices=COLOURS),
    )


_QR_KEYS = ("start_m", "spacing_m", "count", "route", "missing", "side", "size_m", "offset_m", "elevation_m")


def _qr(t: Table, d: dict[str, Any]) -> QrBoardGroup:
    count = t.integer("count", low=1, high=10_000)
    route = t.string("route", "A")
    if not ROUTE_NAME.match(route):
        raise t.fail("route", f"must be 1-16 letters, digits, '_' or '-' (it goes inside the QR payload), got {route!r}")
    missing = t.data.get("missing", [])
    if not isinstance(missing, list) or not all(whole_number(i) is not None and 0 <= i < count for i in missing):
        raise t.fail("missing", f"must be a list of board indices in [0, {count - 1}], got {missing!r}")
    return QrBoardGroup(
        start_m=t.number("start_m", low=0.0, unit="m"), spacing_m=t.number("spacing_m", low=0.0, strict_low=True, unit="m"),
        count=count, route=route, missing=tuple(sorted(set(missing))), side=t.string("side", "right", choices=SIDES),
        size_m=t.number("size_m", d["size_m"], low=0.0, strict_low=True, unit="m"),
        offset_m=t.number("offset_m", d["offset_m"], low=0.0, unit="m"),
        elevation_m=t.number("elevation_m", d["elevation_m"], low=0.0, unit="m"),
    )


_LIGHTING_KEYS = ("kind", "from_m", "to_m", "from_s", "to_s", "strength", "density")


def _lighting(t: Table) -> LightingZone:
    kind = t.string("kind", choices=LIGHTING_KINDS)
    bounds = {k: t.optional_number(k, low=0.0) for k in ("from_m", "to_m", "from_s", "to_s")}
    by_m = bounds["from_m"] is not None or bounds["to_m"] is not None
    by_s = bounds["from_s"] is not None or bounds["to_s"] is not None
    if by_m and by_s:
        raise t.fail("from_s", "give the zone over distance (from_m, to_m) or over time (from_s, to_s), not both")
    for lo, hi, unit in (("from_m", "to_m", "m"), ("from_s", "to_s", "s")):
        if (bounds[lo] is None) != (bounds[hi] is None):
            raise t.fail(hi if bounds[hi] is None else lo, f"give both {lo} and {hi} [{unit}]")
        if bounds[lo] is not None and bounds[hi] is not None and bounds[hi] <= bounds[lo]:  # type: ignore[operator]
            raise t.fail(hi, f"must be > {lo} ({bounds[lo]:g}), got {bounds[hi]:g}")
    if t.has("density") and kind != "shadows":
        raise t.fail("density", "only shadows zones have a density; remove it")
    return LightingZone(kind, **bounds, strength=t.number("strength", 1.0, low=0.0, high=1.0),
                        density=t.number("density", 0.3, low=0.0, high=1.0))


def _sensors(t: Table, d: Any) -> SensorSpec:
    u = t.table("ultrasonic", d["ultrasonic"])
    o = t.table("odometer", d["odometer"])
    spec = SensorSpec(
        min_range_m=u.number("min_range_m", d["ultrasonic"]["min_range_m"], low=0.0, unit="m"),
        max_range_m=u.number("max_range_m", d["ultrasonic"]["max_range_m"], low=0.0, strict_low=True, unit="m"),
        cone_deg=u.number("cone_deg", d["ultrasonic"]["cone_deg"], low=0.0, high=90.0, strict_low=True, unit="deg"),
        noise_m=u.number("noise_m", d["ultrasonic"]["noise_m"], low=0.0, unit="m"),
        odometer_noise_fraction=o.number("noise_fraction", d["odometer"]["noise_fraction"], low=0.0, high=0.5),
        speed_noise_mps=o.number("speed_noise_mps", d["odometer"]["speed_noise_mps"], low=0.0, unit="m/s"),
    )
    if spec.max_range_m <= spec.min_range_m:
        raise u.fail("max_range_m", f"must be > min_range_m ({spec.min_range_m:g}), got {spec.max_range_m:g}")
    return spec


def _faults(t: Table) -> Faults:
    u = t.table("ultrasonic", ("dropouts", "dropout_probability", "spike_probability"))
    c = t.table("camera", ("black", "frozen"))
    steering = []
    for s in t.tables("steering", ("t_s", "until_s", "kind", "value")):
        start, until = s.number("t_s", low=0.0, unit="s"), s.number("until_s", unit="s")
        if until <= start:
            raise s.fail("until_s", f"must be > t_s ({start:g}), got {until:g}")
        kind = s.string("kind", choices=STEERING_FAULT_KINDS)
        if kind in ("stuck", "bias") and not s.has("value"):
            raise s.fail("value", f"a {kind!r} fault needs value = <degrees>")
        steering.append(SteeringFault(start, until, kind, s.number("value", 0.0, unit="deg")))
    return Faults(
        ultrasonic=UltrasonicFaults(u.intervals("dropouts"), u.number("dropout_probability", 0.0, low=0.0, high=1.0),
                                    u.number("spike_probability", 0.0, low=0.0, high=1.0)),
        camera=CameraFaults(c.intervals("black"), c.intervals("frozen")),
        steering=tuple(steering),
    )


def _expectations(t: Table) -> Expectations:
    values: dict[str, Any] = {}
    for key in ("no_collision", "no_lane_departure", "no_emergency", "stopped_before_obstacle"):
        values[key] = t.optional_bool(key)
    for key in ("max_time_outside_lane_s", "min_mean_speed_mps", "max_mean_speed_mps", "min_distance_m", "max_distance_m",
                "min_gap_m", "min_ttc_s", "max_lat_accel_mps2"):
        values[key] = t.optional_number(key, low=0.0)
    for key in ("max_emergency_entries", "max_mode_switches"):
        values[key] = t.integer(key, low=0) if t.has(key) else None
    modes, strategies = [m.name for m in Mode], [s.name for s in Strategy]
    values["mode_by"] = tuple(ModeBy(x.number("t_s", low=0.0, unit="s"), x.string("mode", choices=modes))
                              for x in t.tables("mode_by", ("t_s", "mode")))
    values["mode_not_before"] = tuple(ModeBy(x.number("t_s", low=0.0, unit="s"), x.string("mode", choices=modes))
                                      for x in t.tables("mode_not_before", ("t_s", "mode")))
    values["strategy_by"] = tuple(StrategyBy(x.number("t_s", low=0.0, unit="s"), x.string("strategy", choices=strategies))
                                  for x in t.tables("strategy_by", ("t_s", "strategy")))
    caps = []
    for x in t.tables("max_speed_between", ("max_speed_mps", "t_s", "until_s", "from_m", "to_m")):
        bounds = {k: x.optional_number(k, low=0.0) for k in ("t_s", "until_s", "from_m", "to_m")}
        by_t = bounds["t_s"] is not None and bounds["until_s"] is not None
        by_m = bounds["from_m"] is not None and bounds["to_m"] is not None
        if by_t == by_m or sum(v is not None for v in bounds.values()) != 2:
            raise x.fail("t_s", "give either t_s and until_s (a time window) or from_m and to_m (a stretch of route)")
        caps.append(SpeedCap(x.number("max_speed_mps", low=0.0, unit="m/s"), **bounds))
    values["max_speed_between"] = tuple(caps)
    return Expectations(**values)
