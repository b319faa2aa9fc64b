"""Simulated sensors: forward ultrasonic ranger, odometer, speed; with the scenario's faults.

Ultrasonic: ``ULTRASONIC_RAYS`` rays across the cone from the front bumper; the nearest hit is the true
range. Beyond ``max_range_m`` the reading is inf (no echo); closer than ``min_range_m`` it reads
``min_range_m`` (the sensor cannot tell nearer); otherwise true range + Gaussian noise. Faults: a
dropout interval or a random dropout gives None; a random spike gives a uniform value in the usable
range. Every reading draws the same random numbers whatever the branch, so a run stays reproducible.
"""

from __future__ import annotations

import math
from collections.abc import Sequence

import numpy as np

from fearguard.sim.boxes import Box, ray_ranges
from fearguard.sim.scenario_values import SensorSpec, UltrasonicFaults

ULTRASONIC_RAYS = 15  # [-] rays across the cone (0.13 m apart at 4 m for a 15° cone: no box slips between)


def true_range_m(origin: tuple[float, float], heading_rad: float, cone_deg: float, boxes: Sequence[Box]) -> float:
    """Distance from the sensor to the nearest box edge inside the cone (inf if none)."""
    half = math.radians(cone_deg) / 2
    angles = heading_rad + np.linspace(-half, half, ULTRASONIC_RAYS)
    return float(ray_ranges(origin, angles, boxes).min())


def in_intervals(t_s: float, intervals: Sequence[tuple[float, float]]) -> bool:
    return any(a <= t_s < b for a, b in intervals)


def ultrasonic_reading(true_m: float, t_s: float, spec: SensorSpec, faults: UltrasonicFaults, rng: np.random.Generator) -> float | None:
    """One ultrasonic reading (m, inf = no echo, None = dropout)."""
    drop_u, spike_u, spike_pick = rng.random(3)
    noise = rng.standard_normal() * spec.noise_m
    if in_intervals(t_s, faults.dropouts) or drop_u < faults.dropout_probability:
        return None
    if spike_u < faults.spike_probability:
        return float(spec.min_range_m + spike_pick * (spec.max_range_m - spec.min_range_m))
    if not true_m <= spec.max_range_m:
        return math.inf
    return float(min(max(true_m + noise, spec.min_range_m), spec.max_range_m))


def odometer_step_m(distance_m: float, noise_fraction: float, rng: np.random.Generator) -> float:
    """Distance the odometer adds for a true step (relative Gaussian error, never negative)."""
    return max(0.0, distance_m * (1.0 + noise_fraction * rng.standard_normal()))


def speed_reading_mps(speed_mps: float, sigma_mps: float, rng: np.random.Generator) -> float:
    """Wheel-speed reading: true speed + Gaussian noise, never negative."""
    return max(0.0, speed_mps + sigma_mps * rng.standard_normal())
