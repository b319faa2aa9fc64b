"""Following the route where the markings end: a junction crossed on the map, not stopped at (issues 35 and 38).

A car with a map and a localisation (MetaDrive's navigation, a campus car's waypoints) knows where its route goes when
the paint does not say: across a junction, round a roundabout, through a gap in the lines. The road picture is then
not trusted — rightly: nothing of the lane is seen — but stopping there is no safer than going on at a crossing's speed
(traffic behind runs into a car standing in a junction's mouth). While the picture is not trusted, the path ahead is
known clear (a range reading or the camera's object search, as for a creep) and a route steering arrives, the car
follows it (``Observation.route_steering_deg``) instead of entering EMERGENCY, in CAUTION: at most the doubt speed and
never faster than it can stop within the path known clear, for at most ``route_blind_m`` per loss of the picture (a
junction's width, not a map drive). Past that, or when the path stops being known clear, the emergency machinery takes
over as without a route. The picture trusted again starts a fresh budget.

Crossing a junction on the route, a vehicle seen coming toward the car is yielded to: the car stands (cap 0) until
none has been seen for ``hold_s`` — turning left across the oncoming lanes, the camera sees the oncoming car in its path
for a second before the turn takes it out of view (MetaDrive ``--map SXS --seed 5``: crossing at 6.7 m/s the car
turned into a car it had ranged 26 m ahead coming at 12 m/s).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

from fearguard.policy.config import PolicyConfig
from fearguard.policy.speed import envelope_speed_mps
from fearguard.vehicle import VehicleLimits


@dataclass(frozen=True)
class RouteStep:
    """One frame of route following: the distance driven by the route in this loss of the picture, the steering to
    follow (None: not following now), the speed cap (inf when not following) and the reason ("" when nothing to say)."""

    routed_m: float
    steering_deg: float | None
    cap_mps: float
    why: str
    oncoming_t_s: float | None = None  # when a vehicle was last seen coming toward the car while following the route

    @property
    def following(self) -> bool:
        return self.steering_deg is not None


def next_route(
    routed_m: float, route_deg: float | None, road_calm: bool, clear_m: float, path_doubt: str, speed_mps: float | None,
    dt_s: float, cfg: PolicyConfig, vehicle: VehicleLimits, *, t_s: float = 0.0, object_speed_mps: float | None = None,
    oncoming_t_s: float | None = None,
) -> RouteStep:
    """Advance route following one frame.

    ``routed_m``: driven by the route since the picture was last trusted; ``route_deg``: the route's steering now (None:
    none arrived); ``road_calm``: the road picture is trusted (the budget starts afresh); ``clear_m``: how far ahead the
    path is known clear, ``path_doubt`` why that is not enough for a creep ("" when it is: ``creep_clearance``);
    ``speed_mps`` measured (None: unknown, counted as the top speed, so the budget ends sooner). ``object_speed_mps``:
    the speed along the car's heading of the object in range now (None: none, or unknown; negative: coming toward the
    car), ``oncoming_t_s`` when one last came toward it while following (``t_s``: now)."""
    if road_calm:
        return RouteStep(0.0, None, math.inf, "")
    if route_deg is None or cfg.route_blind_m <= 0.0 or path_doubt:
        return RouteStep(routed_m, None, math.inf, "", oncoming_t_s)
    if routed_m >= cfg.route_blind_m:
        return RouteStep(routed_m, None, math.inf,
                         f"route followed {routed_m:.1f} m with the road picture not trusted (at most {cfg.route_blind_m:g} m): "
                         "no longer", oncoming_t_s)
    v = speed_mps if speed_mps is not None and math.isfinite(speed_mps) else vehicle.max_speed_mps
    routed = routed_m + max(0.0, v) * max(0.0, dt_s)
    if object_speed_mps is not None and object_speed_mps < -cfg.moving_object_min_mps:
        oncoming_t_s = t_s
    if oncoming_t_s is not None and t_s - oncoming_t_s < cfg.hold_s:
        why = (f"road picture not trusted, following the route ({route_deg:+.1f} deg): a vehicle came toward the car "
               f"{t_s - oncoming_t_s:.1f} s ago: yielding, standing until none for {cfg.hold_s:g} s")
        return RouteStep(routed, route_deg, 0.0, why, oncoming_t_s)
    cap = min(cfg.road_doubt_fraction * vehicle.max_speed_mps, envelope_speed_mps(clear_m, vehicle))
    why = (f"road picture not trusted: following the route ({route_deg:+.1f} deg; {routed:.1f} of {cfg.route_blind_m:g} m), "
           f"the path known clear for {clear_m:.1f} m: at most {cap:.2f} m/s")
    return RouteStep(routed, route_deg, cap, why, oncoming_t_s)
