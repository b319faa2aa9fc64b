"""What the vehicle can physically do and which sensors it carries; named presets and vehicle.toml files.

``VehicleLimits()`` is a camera-only car (no range sensor, no QR localisation) with the numbers of a
1:10 model car: a stock car that only has a camera works with the defaults. The presets in ``PRESETS``
describe the cars this field drives (numbers and where they come from: docs/vehicles.md); a
``vehicle.toml`` file starts from a preset (``preset = "road_car"``) or the default and overrides keys.
Every sensor constant the supervisor uses — the range sensor's limits, the closing-speed bound of its
filter, the QR localiser's speed bound and route — comes from here.
"""

from __future__ import annotations

import math
import re
from dataclasses import dataclass, fields, replace
from pathlib import Path
from types import MappingProxyType
from typing import Any

from fearguard.errors import VehicleFileError  # defined in errors.py, importable here
from fearguard.files.reader import Table, TomlSource, read_toml

ROUTE_NAME = re.compile(r"[A-Za-z0-9_-]+")  # the QR payload's route name (sensors/localisation.py)
LOCALISER_SPEED_MARGIN = 1.2  # [-] without odometer a QR fix may move at most 1.2 × max speed since the last one



@dataclass(frozen=True)
class VehicleLimits:
    """Physical limits of the car; defaults: a camera-only 1:10 model car (Donkey Car class numbers).

    A sensor the car does not carry is declared absent here (``has_ultrasonic=False``), never by
    sending NaN: an absent sensor's cue is neutral, a failed sensor's cue is the worst case.
    ``has_ultrasonic`` means any forward range sensor (HC-SR04 on a model car, radar on a road car).
    """

    max_speed_mps: float = 2.0
    max_decel_mps2: float = 3.0  # [m/s²] braking the supervisor plans with
    reaction_time_s: float = 0.2  # [s] from command to braking (loop period + actuator)
    stop_margin_m: float = 0.15  # [m] kept free in front of the car when stopped
    max_steering_deg: float = 30.0
    has_ultrasonic: bool = False
    has_qr_localisation: bool = False
    ultrasonic_min_range_m: float = 0.15  # [m] HC-SR04 class (6 in); a radar-like range sensor: set its own
    ultrasonic_max_range_m: float = 3.96  # [m] (156 in); beyond it the sensor reports "nothing in range"
    wheelbase_m: float = 0.26  # [m] 1:10 touring car
    width_m: float = 0.19  # [m] body width, for the lane-keeping check
    max_lateral_accel_mps2: float = 4.0  # [m/s²] v ≤ √(a_lat·L/|tan δ|); 1:10 rubber tyres on a smooth floor
    max_steering_rate_dps: float = 360.0  # [deg/s] hobby servo, about 0.17 s per 60°
    lead_max_decel_mps2: float = 4.0  # [m/s²] hardest braking assumed of the object ahead (RSS)
    max_closing_speed_mps: float = 3.0  # [m/s] fastest plausible change of the range (range filter's bound)
    qr_route: str | None = None  # the QR route to localise on; None: the first route read is locked

    def __post_init__(self) -> None:
        for f in fields(self):
            value = getattr(self, f.name)
            if f.name == "qr_route":
                if value is not None and not (isinstance(value, str) and ROUTE_NAME.fullmatch(value)):
                    raise ValueError(f"VehicleLimits.qr_route must be letters, digits, '_' or '-' (or None), got {value!r}")
                continue
            if f.type == "bool":
                if not isinstance(value, bool):
                    raise ValueError(f"VehicleLimits.{f.name} must be true or false, got {value!r}")
                continue
            if isinstance(value, bool) or not (isinstance(value, int | float) and math.isfinite(value)):
                raise ValueError(f"VehicleLimits.{f.name} must be a finite number, got {value!r}")
        positive = ("max_speed_mps", "max_decel_mps2", "max_steering_deg", "wheelbase_m", "width_m",
                    "max_lateral_accel_mps2", "max_steering_rate_dps", "lead_max_decel_mps2", "max_closing_speed_mps")
        for name in positive:
            if getattr(self, name) <= 0:
                raise ValueError(f"VehicleLimits.{name} must be > 0, got {getattr(self, name)}")
        for name in ("reaction_time_s", "stop_margin_m"):
            if getattr(self, name) < 0:
                raise ValueError(f"VehicleLimits.{name} must be >= 0, got {getattr(self, name)}")
        if not self.max_steering_deg < 90.0:
            raise ValueError(f"VehicleLimits.max_steering_deg must be < 90, got {self.max_steering_deg}")
        if not 0 < self.ultrasonic_min_range_m < self.ultrasonic_max_range_m:
            raise ValueError(
                f"VehicleLimits needs 0 < ultrasonic_min_range_m < ultrasonic_max_range_m, got "
                f"{self.ultrasonic_min_range_m} and {self.ultrasonic_max_range_m}"
            )

    @property
    def localiser_max_speed_mps(self) -> float:
        """Without odometer, a QR fix may lie at most this fast × time from the last one."""
        return LOCALISER_SPEED_MARGIN * self.max_speed_mps

    @classmethod
    def preset(cls, name: str) -> VehicleLimits:
        """A named preset (``PRESETS``): camera_only, donkey, model_car, hc_sr04_pi, qr_campus, duckiebot, road_car."""
        if name not in PRESETS:
            raise ValueError(f"unknown vehicle preset {name!r}; choose one of {', '.join(PRESETS)}")
        return PRESETS[name]


_DEFAULT = VehicleLimits()
PRESETS: MappingProxyType[str, VehicleLimits] = MappingProxyType({
    # the default: a stock car that has only its camera (numbers of a 1:10 model car)
    "camera_only": _DEFAULT,
    # Donkey Car class 1:10: camera only, ~2 m/s on a taped track, hobby servo
    "donkey": replace(_DEFAULT),
    # the same 1:10 car with an HC-SR04 (0.15-3.96 m) and QR localisation: the default before 0.2, the simulator's model car
    "model_car": replace(_DEFAULT, has_ultrasonic=True, has_qr_localisation=True),
    # the Raspberry-Pi car of the IEEE T-ITS paper: HC-SR04 6-156 in, stops 15 in (0.381 m) from an obstacle,
    # about 5 frames/s (0.23 s per frame: the reaction time), slow
    "hc_sr04_pi": replace(_DEFAULT, max_speed_mps=1.0, max_decel_mps2=2.0, reaction_time_s=0.23, stop_margin_m=0.381,
                          has_ultrasonic=True, ultrasonic_min_range_m=0.1524, ultrasonic_max_range_m=3.9624,
                          lead_max_decel_mps2=3.0, max_closing_speed_mps=2.0),
    # a QR-localised campus prototype (EMO-vehicle class): ~11 km/h, sonar 0.2-6 m, boards every 5 m
    "qr_campus": replace(_DEFAULT, max_speed_mps=3.0, max_decel_mps2=2.5, reaction_time_s=0.3, stop_margin_m=0.5,
                         has_ultrasonic=True, has_qr_localisation=True, ultrasonic_min_range_m=0.2,
                         ultrasonic_max_range_m=6.0, wheelbase_m=1.6, width_m=1.2, max_lateral_accel_mps2=2.0,
                         max_steering_rate_dps=90.0, lead_max_decel_mps2=3.0, max_closing_speed_mps=4.5),
    # a 1:20 Duckiebot-class differential-drive robot, 0.2-0.5 m/s, camera only; wheelbase = axle to caster; speed,
    # braking and delay as measured in gym-duckietown (worlds/duckietown/preset.py: 0.15 s delay + 0.2 s speed lag)
    "duckiebot": replace(_DEFAULT, max_speed_mps=0.5, max_decel_mps2=0.5, reaction_time_s=0.35, stop_margin_m=0.05,
                         max_steering_deg=45.0, wheelbase_m=0.1, width_m=0.13, max_lateral_accel_mps2=1.5,
                         max_steering_rate_dps=360.0, lead_max_decel_mps2=1.5, max_closing_speed_mps=1.0),
    # a full-size road car: forward radar 0.3-80 m, 30 m/s, ISO 11270 / openpilot lateral limit 3 m/s²
    "road_car": replace(_DEFAULT, max_speed_mps=30.0, max_decel_mps2=6.0, reaction_time_s=0.5, stop_margin_m=1.0,
                        has_ultrasonic=True, ultrasonic_min_range_m=0.3, ultrasonic_max_range_m=80.0, wheelbase_m=2.7,
                        width_m=1.8, max_lateral_accel_mps2=3.0, max_steering_rate_dps=60.0, lead_max_decel_mps2=8.0,
                        max_closing_speed_mps=45.0),
})


def load_vehicle(path: str | Path) -> VehicleLimits:
    """Read a vehicle.toml: optional ``preset = "NAME"``, then any VehicleLimits keys (SI units in the names).

    Read by the one strict reader (reader.py): bounded, unknown keys rejected with "did you mean",
    every error naming the file, the line and the key."""
    data, src = read_toml(path, VehicleFileError, f"give a preset ({', '.join(PRESETS)}) or a vehicle.toml path")
    return vehicle_from_table(data, path, src)


def vehicle_from_table(data: dict[str, Any], path: str | Path, src: TomlSource | None = None) -> VehicleLimits:
    """Validate a vehicle table (as read from TOML); errors name the file, the key and (with ``src``) its line.

    The keys stand at the top level; a file whose only key is a ``[vehicle]`` table (a scenario's layout) is read
    the same way.
    """
    key_path = ""
    if set(data) == {"vehicle"} and isinstance(data["vehicle"], dict):
        data, key_path = data["vehicle"], "vehicle"
    known = {f.name: f for f in fields(VehicleLimits)}
    table = Table(src or TomlSource(path, "", VehicleFileError), data, key_path, ("preset", *known))
    base_name = table.string("preset", "camera_only", choices=tuple(PRESETS))
    values: dict[str, Any] = {}
    for key in data:
        if key == "preset":
            continue
        if known[key].type == "bool":
            values[key] = table.boolean(key)
        elif key == "qr_route":
            values[key] = table.string(key)
        else:
            values[key] = table.number(key)
    try:
        return replace(PRESETS[base_name], **values)
    except ValueError as exc:
        raise VehicleFileError(path, "values", str(exc)) from None


def resolve_vehicle(spec: VehicleLimits | str | Path | None) -> VehicleLimits:
    """``--vehicle PRESET|FILE`` (the one resolver: CLI, testing kit): None = ``VehicleLimits()``, a VehicleLimits as
    it is, a preset name, else a vehicle.toml path."""
    if spec is None:
        return VehicleLimits()
    if isinstance(spec, VehicleLimits):
        return spec
    if str(spec) in PRESETS:
        return PRESETS[str(spec)]
    if not Path(spec).is_file():
        raise VehicleFileError(spec, "--vehicle", f"neither a preset ({', '.join(PRESETS)}) nor an existing vehicle file")
    return load_vehicle(spec)
