"""Other vehicles: speed over time from a profile and braking events (the World integrates their positions).

Speed follows the piecewise-linear ``speed_profile`` (held before the first and after the last point)
until a braking event starts; from its ``t_s`` on, the speed falls at ``decel_mps2`` from what it was
to ``to_speed_mps`` and stays there (the profile no longer applies), until a later event. This is how
Euro NCAP's CCRb target behaves: steady speed, then a hard, constant deceleration to a stop.
"""

from __future__ import annotations

import numpy as np

from fearguard.sim.scenario_values import TrafficVehicle


def traffic_speed_mps(vehicle: TrafficVehicle, t_s: float) -> float:
    """The vehicle's speed at time t."""
    return _speed(vehicle, t_s, len(vehicle.braking))


def _speed(vehicle: TrafficVehicle, t_s: float, events: int) -> float:
    started = [k for k in range(events) if vehicle.braking[k].t_s <= t_s]
    if not started:
        times, speeds = zip(*vehicle.speed_profile, strict=True)
        return float(np.interp(t_s, times, speeds))
    k = started[-1]
    event = vehicle.braking[k]
    before = _speed(vehicle, event.t_s, k)
    return max(min(before, event.to_speed_mps), before - event.decel_mps2 * (t_s - event.t_s))
