"""Defaults per scale, in one place: a 1:10 model car on a taped track, or a road car on a public road.

A scenario picks ``scale = "model" | "road"``; every key it leaves out takes its value from here.
Model car: Donkey-Car class, Raspberry Pi camera v2 (62° wide) 0.15 m up, pitched 13° down.
Road car: a mid-size car with a dash-cam 1.3 m up, US-style markings (3 m dashes, 9 m gaps).
"""

from __future__ import annotations

from types import MappingProxyType
from typing import Any

SCALES = ("model", "road")

_MODEL: dict[str, dict[str, Any]] = {
    "rules": {"name": "default"},
    "camera": {
        "fps": 20.0,  # [1/s]
        "width_px": 320,  # [px]
        "height_px": 240,  # [px]
        "hfov_deg": 62.2,  # [deg] Raspberry Pi camera v2
        "mount_height_m": 0.15,  # [m] above the ground
        "pitch_deg": 13.0,  # [deg] down
        "forward_m": 0.25,  # [m] ahead of the rear axle
    },
    "vehicle": {
        "max_speed_mps": 2.0,  # [m/s] VehicleLimits (what the supervisor assumes)
        "max_decel_mps2": 3.0,  # [m/s²] braking the supervisor plans with
        "reaction_time_s": 0.2,  # [s]
        "stop_margin_m": 0.15,  # [m]
        "max_steering_deg": 30.0,  # [deg]
        "has_ultrasonic": True,
        "has_qr_localisation": True,  # only when the scenario has QR boards (the loader decides)
        "wheelbase_m": 0.26,  # [m] 1:10 touring car
        "width_m": 0.19,  # [m]
        "length_m": 0.40,  # [m]
        "height_m": 0.15,  # [m]
        "cruise_speed_mps": 1.5,  # [m/s]
        "max_accel_mps2": 2.0,  # [m/s²] what the motor can do
        "max_brake_mps2": 4.0,  # [m/s²] what the brakes can do (above max_decel_mps2: margin)
        "max_steering_rate_dps": 360.0,  # [deg/s] hobby servo, ~0.17 s per 60°
        "max_lateral_accel_mps2": 4.0,  # [m/s²] VehicleLimits: rubber tyres on a smooth floor (docs/vehicles.md)
        "lead_max_decel_mps2": 4.0,  # [m/s²] VehicleLimits: hardest braking assumed of a car ahead (its brakes)
        "max_closing_speed_mps": 3.0,  # [m/s] VehicleLimits: range filter's bound (model car <= 2 m/s)
    },
    "road": {
        "lane_width_m": 0.45,  # [m] taped track lane (13 cm each side of a 0.19 m car)
        "marking_width_m": 0.04,  # [m] 1.5-inch tape
        "dash_length_m": 0.3,  # [m] 1:10 of a 3 m dash
        "dash_gap_m": 0.6,  # [m] 1:10 of a 6 m gap
        "shoulder_m": 0.06,  # [m] pavement beyond the outermost line
    },
    "traffic": {"length_m": 0.40, "width_m": 0.19, "height_m": 0.14},  # [m] another 1:10 car
    "obstacle": {"length_m": 0.12, "width_m": 0.20, "height_m": 0.20},  # [m] a box on the track
    "qr": {
        "size_m": 0.40,  # [m] board side: ~2.7 px per module at 320×240 while it is still whole in view
        "offset_m": 0.0,  # [m] from the road edge outward to the board's near edge
        "elevation_m": 0.0,  # [m] board bottom above the ground
    },
    "ultrasonic": {
        "min_range_m": 0.15,  # [m] HC-SR04 class; closer reads as this
        "max_range_m": 3.96,  # [m] (156 inches); beyond: inf
        "cone_deg": 15.0,  # [deg] full opening angle
        "noise_m": 0.01,  # [m] Gaussian sigma
    },
    "odometer": {
        "noise_fraction": 0.01,  # [-] sigma of the relative error of each step's distance
        "speed_noise_mps": 0.01,  # [m/s] Gaussian sigma of the speed reading
    },
    "render": {
        "far_m": 10.0,  # [m] draw distance
        "shadow_radius_m": (0.08, 0.30),  # [m] tree-shadow blob radius range
    },
}

_ROAD: dict[str, dict[str, Any]] = {
    "rules": {"name": "road_car"},
    "camera": {
        "fps": 20.0,  # [1/s]
        "width_px": 320,  # [px]
        "height_px": 240,  # [px]
        "hfov_deg": 60.0,  # [deg]
        "mount_height_m": 1.3,  # [m] dash-cam behind the windscreen
        "pitch_deg": 5.0,  # [deg] down
        "forward_m": 1.5,  # [m] ahead of the rear axle
    },
    "vehicle": {
        "max_speed_mps": 14.0,  # [m/s] 50 km/h
        "max_decel_mps2": 6.0,  # [m/s²] planned braking
        "reaction_time_s": 0.5,  # [s]
        "stop_margin_m": 1.0,  # [m]
        "max_steering_deg": 30.0,  # [deg] road-wheel angle
        "has_ultrasonic": True,  # the forward range sensor (radar-like at this scale)
        "has_qr_localisation": False,  # only when the scenario has QR boards (the loader decides)
        "wheelbase_m": 2.7,  # [m]
        "width_m": 1.8,  # [m]
        "length_m": 4.5,  # [m]
        "height_m": 1.45,  # [m]
        "cruise_speed_mps": 11.1,  # [m/s] 40 km/h
        "max_accel_mps2": 3.0,  # [m/s²]
        "max_brake_mps2": 9.0,  # [m/s²] emergency braking on dry asphalt
        "max_steering_rate_dps": 60.0,  # [deg/s] road-wheel rate
        "max_lateral_accel_mps2": 3.0,  # [m/s²] VehicleLimits: ISO 11270 / openpilot lateral limit
        "lead_max_decel_mps2": 8.0,  # [m/s²] VehicleLimits: RSS's assumed hardest braking of the car ahead
        "max_closing_speed_mps": 45.0,  # [m/s] VehicleLimits: range filter's bound (1.5 x max speed)
    },
    "road": {
        "lane_width_m": 3.5,  # [m]
        "marking_width_m": 0.15,  # [m]
        "dash_length_m": 3.0,  # [m] US: 10 ft dash
        "dash_gap_m": 9.0,  # [m] US: 30 ft gap
        "shoulder_m": 0.6,  # [m]
    },
    "traffic": {"length_m": 4.5, "width_m": 1.8, "height_m": 1.45},  # [m] a passenger car
    "obstacle": {"length_m": 0.6, "width_m": 0.8, "height_m": 0.6},  # [m] debris / a box
    "qr": {"size_m": 2.5, "offset_m": 0.2, "elevation_m": 0.6},  # [m] a big sign: ~2.5 px per module when whole in view
    "ultrasonic": {
        "min_range_m": 0.3,  # [m] forward range sensor (radar-like)
        "max_range_m": 80.0,  # [m]
        "cone_deg": 10.0,  # [deg]
        "noise_m": 0.1,  # [m]
    },
    "odometer": {"noise_fraction": 0.01, "speed_noise_mps": 0.05},  # [-], [m/s]
    "render": {"far_m": 120.0, "shadow_radius_m": (0.8, 3.0)},  # [m]
}


def scale_defaults(scale: str) -> MappingProxyType[str, dict[str, Any]]:
    """Read-only defaults of one scale ("model" or "road")."""
    return MappingProxyType(_MODEL if scale == "model" else _ROAD)
