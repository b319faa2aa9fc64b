"""The plain values that enter the supervisor: one instant's Observation, and the vehicle ahead.

These sit at the bottom of the package (they import only ``cues``), so every layer can use them:
vision produces a ``Lead`` from a ``LeadBox``, perception reads an ``Observation``, policy follows a
``Lead`` — and none of them has to import another layer to name its input (docs/architecture.md).
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any

from fearguard.cues import Cues
from fearguard.readings import finite_reading


@dataclass(frozen=True)
class Lead:
    """The vehicle ahead in the ego lane: bearing (deg, + = left) and range if known (m)."""

    bearing_deg: float
    range_m: float | None = None

    @property
    def usable(self) -> bool:
        """A lead can be followed when its bearing is a finite number (a range is optional)."""
        return finite_reading(self.bearing_deg) is not None

    @property
    def usable_range_m(self) -> float | None:
        r = finite_reading(self.range_m)
        return r if r is not None and r >= 0.0 else None


@dataclass(frozen=True)
class LeadBox:
    """A vehicle's box in image pixels: left, top, width, height (as detectors report it)."""

    x_px: float
    y_px: float
    w_px: float
    h_px: float

    @property
    def usable(self) -> bool:
        vals = (self.x_px, self.y_px, self.w_px, self.h_px)
        return all(finite_reading(v) is not None for v in vals) and self.w_px > 0 < self.h_px

    def scaled(self, factor: float) -> LeadBox:
        return LeadBox(self.x_px * factor, self.y_px * factor, self.w_px * factor, self.h_px * factor)

    def as_int(self) -> tuple[int, int, int, int]:
        return int(self.x_px), int(self.y_px), math.ceil(self.w_px), math.ceil(self.h_px)


@dataclass(frozen=True)
class Observation:
    """What the car knows at one instant. Give ``cues`` to skip perception (cue-level use).

    ``steering_deg``: the wrapped estimator's angle when the caller already holds it (a Donkey pilot's, an RL agent's):
    validated exactly like a steering function's answer, and the steering function is not called. ``lead`` is a
    ``Lead``; a detector's box in frame pixels is ``lead_box`` (a ``LeadBox`` given as ``lead`` is moved there).
    ``route_steering_deg``: the route's steering from a map and localisation (MetaDrive's navigation; a campus car's
    waypoints), a guide only where the picture is not: docs/rules.md, "Following the route where the markings end".
    """

    t_s: float
    speed_mps: float = 0.0
    frame: Any = None
    cues: Cues | None = None
    ultrasonic_range_m: float | None = None
    odometer_m: float | None = None
    qr_payload: str | None = None
    lead: Lead | None = None  # the vehicle ahead (a LeadBox given here is moved to lead_box)
    ultrasonic_echo_s: float | None = None  # raw HC-SR04 echo time, used when ultrasonic_range_m is None
    # rate of change of the obstacle range (m/s, − = approaching) when the caller knows it (radar, simulator: the
    # lead's speed minus the ego's); None: estimated from successive ranges
    range_rate_mps: float | None = None
    steering_deg: float | None = None  # [deg, + = left] the estimator's angle, when the caller holds it (None: ask ``steer``)
    lead_box: LeadBox | None = None  # a box from an external detector (frame pixels): perception turns it into a Lead
    # [deg, + = left] the steering that follows the car's route by a map and its localisation (a navigation's), in the
    # estimator's units, when the caller has one: where the road picture is not trusted and the path is known clear, the
    # car may follow it (``route_blind_m``) instead of stopping — across a junction whose markings end. None: no route
    route_steering_deg: float | None = None

    def route_deg(self, max_steering_deg: float) -> float | None:
        """The route steering as fearguard follows it: a finite reading, clipped to ±``max_steering_deg``; None: no route
        (none given, or no finite number)."""
        value = finite_reading(self.route_steering_deg)
        return None if value is None else min(max(value, -max_steering_deg), max_steering_deg)

    def __post_init__(self) -> None:
        if isinstance(self.lead, LeadBox):  # the contract's ``lead=`` took a box too: it keeps working
            object.__setattr__(self, "lead_box", self.lead if self.lead_box is None else self.lead_box)
            object.__setattr__(self, "lead", None)
