"""After the lane check caught the estimator steering out of the lane, the car steers by the lane it sees now.

The check runs only while the road picture is calm; between two checks a distrusted estimator is not
trusted again. Holding one stale angle for seconds drove a biased car out of a bending lane
(steering_bias seed 4, before): the lane geometry of the current frame is used while the pipeline has one.
"""

from __future__ import annotations

import math

import pytest
from tests.conftest import RULES_DIR

import fearguard as fg
from fearguard.sim.loop import run_scenario
from fearguard.sim.scenario import load_scenario
from fearguard.sim.world import World

SCENARIOS = RULES_DIR.parent / "scenarios"


@pytest.mark.slow
def test_a_minus_10_deg_biased_estimator_keeps_its_lane_and_most_of_its_progress() -> None:
    sc = load_scenario(SCENARIOS / "steering_bias.toml")
    guarded, unguarded = run_scenario(sc, seed=4), run_scenario(sc, seed=4, controller="unguarded")
    assert unguarded.metrics.lane_departures > 0  # the bias alone leaves the lane
    assert guarded.metrics.lane_departures == 0 and guarded.metrics.collisions == 0
    assert guarded.metrics.distance_m >= 0.6 * unguarded.metrics.distance_m


def test_after_an_override_the_last_lane_geometry_angle_is_held_while_nothing_is_seen() -> None:
    sc = load_scenario(SCENARIOS / "clear_straight.toml")
    world = World(sc, seed=1)
    guard = fg.FearGuard(lambda frame: -20.0, rules=fg.load_rules(sc.rules_path), vehicle=sc.vehicle.limits, camera=world.camera)
    overridden = None
    for _ in range(20):  # a car steering hard toward the right boundary on a clear straight road
        s = world.sense()
        cmd = guard.step(fg.Observation(t_s=s.t_s, speed_mps=1.0, frame=s.frame_bgr))
        world.advance(cmd.steering_deg, 1.0)
        world.truth()
        if any(r.startswith("lane check: steering -20.0 deg crosses the right boundary") for r in cmd.reasons):
            overridden = cmd
    assert overridden is not None and abs(overridden.steering_deg) < 5.0
    t = s.t_s
    for k in range(1, 4):  # then only cues, the road doubtful: no lane geometry to check against or steer by
        cmd = guard.step(fg.Observation(t_s=t + 0.05 * k, speed_mps=1.0, cues=fg.Cues(0.4, 130.0, 0.3, math.inf, 0.0)))
        assert any("holding the lane geometry's last" in r for r in cmd.reasons), cmd.reasons
        assert abs(cmd.steering_deg) < 5.0  # never back to the estimator's -20 deg
