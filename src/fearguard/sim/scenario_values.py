"""What a scenario holds, as frozen values: the road, the cars, the light, the faults, the expectations.

These are the plain values the simulated world (road, traffic, renderer, sensors, metrics) is built
from; ``scenario.py`` reads and validates a TOML file into them. The tuples of names below are the
kinds each value allows (the loader offers them as choices). Units are in the field names.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from pathlib import Path

from fearguard.camera import CameraModel
from fearguard.vehicle import VehicleLimits

MARKING_STYLES = ("solid", "dashed", "none")
MARKING_COLOURS = ("white", "yellow")
SURFACES = ("asphalt", "pale")
LANES = ("ego", "left", "right")
SIDES = ("left", "right")
LIGHTING_KINDS = ("normal", "night", "glare", "tunnel_exit", "shadows")
STEERING_FAULT_KINDS = ("raise", "nan", "stuck", "bias")
COLOURS = ("red", "blue", "white", "black", "silver", "green", "yellow", "orange", "grey")
EXPECTATION_NAMES = ("no_collision", "no_lane_departure", "max_time_outside_lane_s", "min_mean_speed_mps", "max_mean_speed_mps",
                "min_distance_m", "max_distance_m", "no_emergency", "max_emergency_entries", "max_mode_switches",
                "stopped_before_obstacle", "min_gap_m", "min_ttc_s", "max_lat_accel_mps2", "mode_by", "strategy_by",
                "mode_not_before", "max_speed_between")  # every expectation, in the order they are checked


@dataclass(frozen=True)
class CameraSpec:
    """The simulated forward camera: frame rate, size, field of view, and where it sits on the car."""

    fps: float
    width_px: int
    height_px: int
    hfov_deg: float
    mount_height_m: float
    pitch_deg: float
    forward_m: float  # ahead of the rear axle

    def model(self) -> CameraModel:
        """The pinhole CameraModel (no distortion) used to render and to analyse frames."""
        return CameraModel.default(self.width_px, self.height_px, self.hfov_deg, self.mount_height_m, self.pitch_deg)


@dataclass(frozen=True)
class VehicleProfile:
    """The ego car: what the supervisor assumes (VehicleLimits fields) and what the car physically does."""

    max_speed_mps: float
    max_decel_mps2: float
    reaction_time_s: float
    stop_margin_m: float
    max_steering_deg: float
    has_ultrasonic: bool
    has_qr_localisation: bool
    wheelbase_m: float
    width_m: float
    length_m: float
    height_m: float
    cruise_speed_mps: float
    max_accel_mps2: float
    max_brake_mps2: float
    max_steering_rate_dps: float
    max_lateral_accel_mps2: float
    lead_max_decel_mps2: float
    max_closing_speed_mps: float

    @property
    def limits(self) -> VehicleLimits:
        """The supervisor's view of this car."""
        return VehicleLimits(
            self.max_speed_mps, self.max_decel_mps2, self.reaction_time_s, self.stop_margin_m, self.max_steering_deg,
            self.has_ultrasonic, self.has_qr_localisation, wheelbase_m=self.wheelbase_m, width_m=self.width_m,
            max_lateral_accel_mps2=self.max_lateral_accel_mps2, max_steering_rate_dps=self.max_steering_rate_dps,
            lead_max_decel_mps2=self.lead_max_decel_mps2, max_closing_speed_mps=self.max_closing_speed_mps,
        )

    @property
    def rear_overhang_m(self) -> float:
        """Rear bumper behind the rear axle (overhangs are taken equal front and back)."""
        return (self.length_m - self.wheelbase_m) / 2.0

    @property
    def front_m(self) -> float:
        """Front bumper ahead of the rear axle."""
        return self.length_m - self.rear_overhang_m


@dataclass(frozen=True)
class EgoStart:
    start_s_m: float  # rear axle, along the route
    lateral_m: float  # + = left of the lane centre
    heading_deg: float  # relative to the road
    speed_mps: float


@dataclass(frozen=True)
class Marking:
    style: str  # solid | dashed | none
    colour: str  # white | yellow


@dataclass(frozen=True)
class Segment:
    """One piece of road: straight, or an arc of ``radius_m`` turning left/right."""

    kind: str
    length_m: float
    radius_m: float = math.inf
    turn: str | None = None
    left: Marking = Marking("solid", "white")
    right: Marking = Marking("solid", "white")
    surface: str = "asphalt"

    @property
    def curvature_per_m(self) -> float:
        """Signed curvature (+ = left)."""
        if self.kind == "straight":
            return 0.0
        return (1.0 if self.turn == "left" else -1.0) / self.radius_m


@dataclass(frozen=True)
class RoadSpec:
    lane_width_m: float
    marking_width_m: float
    dash_length_m: float
    dash_gap_m: float
    shoulder_m: float
    lanes_left: int
    lanes_right: int
    outer: Marking  # edge lines of the extra lanes (if any)
    segments: tuple[Segment, ...]

    @property
    def length_m(self) -> float:
        return sum(seg.length_m for seg in self.segments)

    def lane_offset_m(self, lane: str) -> float:
        """Lateral position of a lane's centre (+ = left of the ego lane centre)."""
        return {"ego": 0.0, "left": self.lane_width_m, "right": -self.lane_width_m}[lane]


@dataclass(frozen=True)
class BrakingEvent:
    t_s: float
    decel_mps2: float
    to_speed_mps: float


@dataclass(frozen=True)
class TrafficVehicle:
    """Another car: its lane, start position (centre, along the route) and speed over time."""

    lane: str
    start_s_m: float
    lateral_m: float  # offset from its lane centre
    speed_profile: tuple[tuple[float, float], ...]  # (t_s, speed_mps), linear in between, held outside
    braking: tuple[BrakingEvent, ...]
    length_m: float
    width_m: float
    height_m: float
    colour: str


@dataclass(frozen=True)
class ObstacleSpec:
    s_m: float  # centre, along the route
    lateral_m: float
    length_m: float
    width_m: float
    height_m: float
    colour: str


@dataclass(frozen=True)
class QrBoardGroup:
    """Boards every ``spacing_m`` from ``start_m``; indices in ``missing`` are not there."""

    start_m: float
    spacing_m: float
    count: int
    route: str
    missing: tuple[int, ...]
    side: str
    size_m: float
    offset_m: float
    elevation_m: float


@dataclass(frozen=True)
class LightingZone:
    """A lighting condition over a stretch of route (from_m..to_m) or a time window (from_s..to_s)."""

    kind: str
    from_m: float | None = None
    to_m: float | None = None
    from_s: float | None = None
    to_s: float | None = None
    strength: float = 1.0  # [0..1] 0 = normal light, 1 = the full effect
    density: float = 0.3  # [0..1] shadows: share of the ground covered

    def active(self, s_m: float, t_s: float) -> bool:
        if self.from_m is not None and self.to_m is not None:
            return self.from_m <= s_m < self.to_m
        if self.from_s is not None and self.to_s is not None:
            return self.from_s <= t_s < self.to_s
        return True

    def progress(self, s_m: float, t_s: float) -> float:
        """How far through the zone (0..1) the car is; 0 for an unbounded zone."""
        if self.from_m is not None and self.to_m is not None:
            return min(1.0, max(0.0, (s_m - self.from_m) / (self.to_m - self.from_m)))
        if self.from_s is not None and self.to_s is not None:
            return min(1.0, max(0.0, (t_s - self.from_s) / (self.to_s - self.from_s)))
        return 0.0


@dataclass(frozen=True)
class SensorSpec:
    min_range_m: float
    max_range_m: float
    cone_deg: float
    noise_m: float
    odometer_noise_fraction: float
    speed_noise_mps: float


@dataclass(frozen=True)
class UltrasonicFaults:
    dropouts: tuple[tuple[float, float], ...] = ()  # [s] intervals reading None
    dropout_probability: float = 0.0  # [-] per reading, None
    spike_probability: float = 0.0  # [-] per reading, a random range


@dataclass(frozen=True)
class CameraFaults:
    black: tuple[tuple[float, float], ...] = ()  # [s] intervals of all-zero frames
    frozen: tuple[tuple[float, float], ...] = ()  # [s] intervals repeating the last good frame


@dataclass(frozen=True)
class SteeringFault:
    """The wrapped steering estimator misbehaves from t_s to until_s (the closed loop applies it)."""

    t_s: float
    until_s: float
    kind: str  # raise | nan | stuck (returns value) | bias (adds value)
    value: float = 0.0  # [deg]

    def active(self, t_s: float) -> bool:
        return self.t_s <= t_s < self.until_s


@dataclass(frozen=True)
class Faults:
    ultrasonic: UltrasonicFaults = UltrasonicFaults()
    camera: CameraFaults = CameraFaults()
    steering: tuple[SteeringFault, ...] = ()


@dataclass(frozen=True)
class ModeBy:
    t_s: float
    mode: str


@dataclass(frozen=True)
class StrategyBy:
    t_s: float
    strategy: str


@dataclass(frozen=True)
class SpeedCap:
    """Speed stays at or below ``max_speed_mps`` over a time window or a stretch of route."""

    max_speed_mps: float
    t_s: float | None = None
    until_s: float | None = None
    from_m: float | None = None
    to_m: float | None = None


@dataclass(frozen=True)
class Expectations:
    """What a safe run must achieve; None = not checked. Each is documented in docs/scenarios.md."""

    no_collision: bool | None = None
    no_lane_departure: bool | None = None
    max_time_outside_lane_s: float | None = None
    min_mean_speed_mps: float | None = None
    max_mean_speed_mps: float | None = None
    min_distance_m: float | None = None
    max_distance_m: float | None = None
    no_emergency: bool | None = None
    max_emergency_entries: int | None = None
    max_mode_switches: int | None = None
    stopped_before_obstacle: bool | None = None
    min_gap_m: float | None = None
    min_ttc_s: float | None = None
    max_lat_accel_mps2: float | None = None
    mode_by: tuple[ModeBy, ...] = ()
    strategy_by: tuple[StrategyBy, ...] = ()
    mode_not_before: tuple[ModeBy, ...] = ()
    max_speed_between: tuple[SpeedCap, ...] = ()

    def names(self) -> list[str]:
        """The expectations that are set, in the order they are checked."""
        return [f for f in EXPECTATION_NAMES if getattr(self, f) not in (None, ())]


@dataclass(frozen=True)
class Scenario:
    path: Path
    name: str
    description: str
    seed: int
    duration_s: float
    scale: str
    camera: CameraSpec
    rules_path: Path
    vehicle: VehicleProfile
    ego: EgoStart
    road: RoadSpec
    vehicles: tuple[TrafficVehicle, ...] = ()
    obstacles: tuple[ObstacleSpec, ...] = ()
    qr_boards: tuple[QrBoardGroup, ...] = ()
    lighting: tuple[LightingZone, ...] = ()
    sensors: SensorSpec | None = None
    faults: Faults = Faults()
    expectations: Expectations = Expectations()
    render_far_m: float = 10.0  # [m] draw distance (from the scale)
    shadow_radius_m: tuple[float, float] = field(default=(0.08, 0.3))  # [m] tree-shadow blob radii

    @property
    def dt_s(self) -> float:
        return 1.0 / self.camera.fps

    @property
    def cruise_speed_mps(self) -> float:
        return self.vehicle.cruise_speed_mps
