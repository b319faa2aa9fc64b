"""Simulated sensors: the ultrasonic sees what is ahead at its true range ± noise; faults; odometer and speed."""

from __future__ import annotations

import math
import textwrap
from pathlib import Path

import numpy as np
import pytest
from hypothesis import given
from hypothesis import strategies as st

from fearguard.sim.boxes import Box, ray_ranges
from fearguard.sim.scenario import Scenario, SensorSpec, UltrasonicFaults, load_scenario
from fearguard.sim.sensors import odometer_step_m, ultrasonic_reading
from fearguard.sim.world import World

ROAD = "[[road.segments]]\nkind = \"straight\"\nlength_m = 30.0\n"
SPEC = SensorSpec(min_range_m=0.15, max_range_m=3.96, cone_deg=15.0, noise_m=0.01, odometer_noise_fraction=0.01, speed_noise_mps=0.01)


def scenario(tmp_path: Path, body: str = "", head: str = "") -> Scenario:
    path = tmp_path / "u.toml"
    path.write_text(textwrap.dedent(head) + ROAD + textwrap.dedent(body))
    return load_scenario(path)


@pytest.mark.parametrize("seed", [1, 2, 3])
def test_ultrasonic_sees_an_obstacle_ahead_at_its_true_range(tmp_path: Path, seed: int) -> None:
    sc = scenario(tmp_path, "[[obstacles]]\ns_m = 2.5\n")
    world = World(sc, seed=seed)
    true_gap = world.truth().gap_m
    readings = []
    for _ in range(20):
        readings.append(world.sense().ultrasonic_range_m)
        world.advance(0.0, 0.0)  # brake to a stop: the range settles
    settled = world.truth().gap_m
    assert readings[0] == pytest.approx(true_gap, abs=4 * SPEC.noise_m)
    assert world.sense().ultrasonic_range_m == pytest.approx(settled, abs=4 * SPEC.noise_m)


def test_ultrasonic_beyond_range_is_inf_and_the_cone_ignores_the_next_lane(tmp_path: Path) -> None:
    far = World(scenario(tmp_path, "[[obstacles]]\ns_m = 6.0\n"))
    assert far.sense().ultrasonic_range_m == math.inf
    beside = World(scenario(tmp_path, "[[obstacles]]\ns_m = 1.5\nlateral_m = 0.6\n"))
    assert beside.sense().ultrasonic_range_m == math.inf


def test_no_ultrasonic_on_the_car_reads_none(tmp_path: Path) -> None:
    world = World(scenario(tmp_path, "[[obstacles]]\ns_m = 2.0\n", head="[vehicle]\nhas_ultrasonic = false\n"))
    assert world.sense().ultrasonic_range_m is None


def test_dropout_interval_reads_none_then_recovers(tmp_path: Path) -> None:
    world = World(scenario(tmp_path, "[[obstacles]]\ns_m = 2.5\n[faults.ultrasonic]\ndropouts = [[0.1, 0.2]]\n"))
    readings = []
    for _ in range(6):
        readings.append(world.sense().ultrasonic_range_m)
        world.advance(0.0, 1.0)
    assert [r is None for r in readings] == [False, False, True, True, False, False]


@given(st.floats(0.0, 10.0), st.integers(0, 2**32 - 1))
def test_readings_stay_in_the_sensors_range(true_m: float, seed: int) -> None:
    rng = np.random.default_rng(seed)
    r = ultrasonic_reading(true_m, 0.0, SPEC, UltrasonicFaults(spike_probability=0.3), rng)
    assert r is not None
    assert r == math.inf or SPEC.min_range_m <= r <= SPEC.max_range_m
    if true_m > SPEC.max_range_m:
        assert r == math.inf or r <= SPEC.max_range_m  # no echo, or a spike


def test_certain_dropout_and_certain_spike() -> None:
    rng = np.random.default_rng(0)
    assert ultrasonic_reading(1.0, 0.0, SPEC, UltrasonicFaults(dropout_probability=1.0), rng) is None
    spikes = [ultrasonic_reading(1.0, 0.0, SPEC, UltrasonicFaults(spike_probability=1.0), rng) for _ in range(50)]
    assert all(SPEC.min_range_m <= s <= SPEC.max_range_m for s in spikes)  # type: ignore[operator]
    assert np.std(spikes) > 0.5  # random, not the true range
    assert ultrasonic_reading(0.05, 0.0, SPEC, UltrasonicFaults(), rng) == SPEC.min_range_m  # too close reads the minimum


def test_ray_ranges_hand_case() -> None:
    box = Box(3.0, 0.0, 0.0, 1.0, 1.0, 0.5, "grey", False)  # faces at x = 2.5 .. 3.5, y = −0.5 .. 0.5
    ranges = ray_ranges((0.0, 0.0), np.array([0.0, math.atan2(0.4, 2.5), math.pi / 2]), [box])
    assert ranges[0] == pytest.approx(2.5)
    assert ranges[1] == pytest.approx(math.hypot(2.5, 0.4))
    assert ranges[2] == math.inf


def test_odometer_and_speed_follow_the_truth(tmp_path: Path) -> None:
    world = World(scenario(tmp_path, head="[ego]\nspeed_mps = 1.0\n"))
    for _ in range(40):
        world.advance(0.0, 1.0)
    sens = world.sense()
    assert sens.odometer_m == pytest.approx(2.0, rel=0.02)
    assert sens.speed_mps == pytest.approx(1.0, abs=0.05)


def test_odometer_step_is_never_negative() -> None:
    rng = np.random.default_rng(3)
    assert all(odometer_step_m(0.01, 0.5, rng) >= 0.0 for _ in range(200))
    assert odometer_step_m(0.0, 0.5, rng) == 0.0
