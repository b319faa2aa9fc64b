"""The lane-keeping plausibility check: will the wrapped steering take the car over a lane boundary soon?

A policy check beside the fuzzy fear (like the imminent-collision check; the five cues stay five). Input
is the ego lane in metres on the ground, as perception measures it with a camera model (``lane.LaneGeometry``,
``Perceived.lane``): each boundary a
straight ground line y = y0 + slope·x in vehicle axes (x forward from the camera, y left), over the
stretch the camera sees. The car's path under a constant steering angle δ is an arc of curvature
tan δ / L (bicycle model): y(x) ≈ x²·tan δ / (2L). At the look-ahead distance x = v·T (the time to line
crossing T, clamped to what the camera sees) the car's side must stay inside the boundaries. Only a
steering that crosses a boundary *and* points at least ``min_deg`` more toward it than the lane geometry's
own steering is overridden: the lane geometry is the reference, so its own model errors never trigger it.
A departure the car's route asks for is intended — a roundabout's exit, a turn off the lane — as lane departure warning
is silent while the indicator is on (ISO 17361): when the route's own steering crosses the same boundary and the
estimator steers within ``min_deg`` of it, the estimator is not overridden and the reasons say so.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

from fearguard.lane import LaneGeometry
from fearguard.vehicle import VehicleLimits


@dataclass(frozen=True)
class LaneCheck:
    """The check's verdict: ``crossing`` "left"/"right" or "" and, when overriding, the steering to use."""

    crossing: str
    distance_m: float
    override_deg: float | None
    why: str


def path_offset_m(steering_deg: float, distance_m: float, vehicle: VehicleLimits) -> float:
    """Lateral position of the car after ``distance_m`` on a constant steering angle (m, + = left)."""
    return distance_m * distance_m * math.tan(math.radians(steering_deg)) / (2.0 * vehicle.wheelbase_m)


def crossing_side(geometry: LaneGeometry, steering_deg: float, distance_m: float, vehicle: VehicleLimits) -> str:
    """Which boundary the car's side crosses at ``distance_m`` on this steering ("left", "right" or "")."""
    y = path_offset_m(steering_deg, distance_m, vehicle)
    half = vehicle.width_m / 2.0
    if geometry.left is not None and y + half > geometry.left.y_at(distance_m):
        return "left"
    if geometry.right is not None and y - half < geometry.right.y_at(distance_m):
        return "right"
    return ""


def lane_check(
    geometry: LaneGeometry | None, steering_deg: float, speed_mps: float, vehicle: VehicleLimits,
    lookahead_s: float, min_deg: float, route_deg: float | None = None,
) -> LaneCheck | None:
    """None when nothing can be checked (no lane geometry, no reference steering, not moving). ``route_deg``: the
    route's steering (``Observation.route_steering_deg``), when the caller has a map."""
    if geometry is None or geometry.steering_deg is None or not math.isfinite(geometry.steering_deg):
        return None
    if not (geometry.far_m > geometry.near_m > 0.0) or speed_mps <= 0.0:
        return None
    distance = min(max(speed_mps * lookahead_s, geometry.near_m), geometry.far_m)
    side = crossing_side(geometry, steering_deg, distance, vehicle)
    lane = geometry.steering_deg
    toward = steering_deg - lane if side == "left" else lane - steering_deg
    if not side or toward < min_deg:
        return LaneCheck("", distance, None, "")
    if route_deg is not None and abs(steering_deg - route_deg) <= min_deg and crossing_side(geometry, route_deg, distance, vehicle) == side:
        return LaneCheck(side, distance, None, f"lane check: steering {steering_deg:+.1f} deg crosses the {side} boundary within "
                                               f"{distance:.2f} m as the route does ({route_deg:+.1f} deg): an intended departure")
    why = (f"lane check: steering {steering_deg:+.1f} deg crosses the {side} boundary within {distance:.2f} m "
           f"({lookahead_s:.1f} s ahead), {toward:.1f} deg more toward it than the lane geometry: "
           f"steering by the lane geometry {lane:+.1f} deg")
    return LaneCheck(side, distance, lane, why)
