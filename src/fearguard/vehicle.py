"""What the vehicle can physically do and which sensors it carries."""

from __future__ import annotations

from dataclasses import dataclass, fields

from fearguard.readings import finite_reading


@dataclass(frozen=True)
class VehicleLimits:
    """Physical limits of the car; defaults are a 1:10 model car (Donkey Car class).

    A sensor the car does not carry is declared absent here (``has_ultrasonic=False``), never by
    sending NaN: an absent sensor's cue is neutral, a failed sensor's cue is the worst case.
    """

    max_speed_mps: float = 2.0
    max_decel_mps2: float = 3.0
    reaction_time_s: float = 0.2
    stop_margin_m: float = 0.15
    max_steering_deg: float = 30.0
    has_ultrasonic: bool = True
    has_qr_localisation: bool = True
    ultrasonic_min_range_m: float = 0.15  # [m] HC-SR04 class (6 in); a radar-like range sensor: set its own
    ultrasonic_max_range_m: float = 3.96  # [m] (156 in); beyond it the sensor reports "nothing in range"

    def __post_init__(self) -> None:
        for f in fields(self):
            value = getattr(self, f.name)
            if f.type == "bool" or isinstance(value, bool):
                continue
            if finite_reading(value) is None:
                raise ValueError(f"VehicleLimits.{f.name} must be a finite number, got {value!r}")
        positive = ("max_speed_mps", "max_decel_mps2", "max_steering_deg")
        for name in positive:
            if getattr(self, name) <= 0:
                raise ValueError(f"VehicleLimits.{name} must be > 0, got {getattr(self, name)}")
        for name in ("reaction_time_s", "stop_margin_m"):
            if getattr(self, name) < 0:
                raise ValueError(f"VehicleLimits.{name} must be >= 0, got {getattr(self, name)}")
        if not 0 < self.ultrasonic_min_range_m < self.ultrasonic_max_range_m:
            raise ValueError(
                f"VehicleLimits needs 0 < ultrasonic_min_range_m < ultrasonic_max_range_m, got "
                f"{self.ultrasonic_min_range_m} and {self.ultrasonic_max_range_m}"
            )
