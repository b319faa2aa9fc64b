"""Issue 35's flicker grace on a car that knows nothing of the path ahead (no range sensor, no camera object search:
a dash-cam replay, a camera-only Donkey car): a picture in doubt slows a moving car, never speeds it up, never starts
a standing one, and a picture lost for good is still an EMERGENCY stop once the grace is over."""

from __future__ import annotations

import dataclasses
import math

from hypothesis import given, settings
from hypothesis import strategies as st

import fearguard as fg
from fearguard.fuzzy.loader import bundled_rules_path

RULE_FILES = ["default.toml", "road_car.toml", "duckiebot.toml"]
PRESETS = ["camera_only", "donkey", "duckiebot", "road_car"]


def _camera_only(preset: str) -> fg.VehicleLimits:
    """The preset as a car that declares no range sensor (a road car without its radar)."""
    return dataclasses.replace(fg.VehicleLimits.preset(preset), has_ultrasonic=False)


@settings(max_examples=60, deadline=None)
@given(
    rules_file=st.sampled_from(RULE_FILES), preset=st.sampled_from(PRESETS), speed_share=st.floats(0.0, 1.0),
    lane=st.floats(0.0, 0.2), occlusion=st.floats(0.0, 1.0), lost_s=st.floats(0.1, 3.0), dt=st.sampled_from([0.05, 0.1]),
    measured=st.booleans(),
)
def test_a_flicker_never_raises_the_limit_above_the_speed_and_a_lasting_loss_stops(
    rules_file: str, preset: str, speed_share: float, lane: float, occlusion: float, lost_s: float, dt: float, measured: bool
) -> None:
    """``measured``: the car reports its speed; if not (a Donkey car without an encoder) "now" is the limit it was
    last given."""
    rules = fg.load_rules(bundled_rules_path(rules_file))
    car = _camera_only(preset)
    speed = speed_share * car.max_speed_mps
    guard = fg.FearGuard(lambda frame: 0.0, rules=rules, vehicle=car)
    calm = fg.Cues(0.95, 120.0, 0.0, math.inf, 0.5)
    lost = fg.Cues(lane, 120.0, occlusion, math.inf, 0.5)
    reported = speed if measured else math.nan
    t, before = 0.0, []
    for _ in range(round(2.0 / dt)):
        before.append(guard.step(fg.Observation(t_s=round(t, 6), speed_mps=reported, cues=calm)))
        t += dt
    started, cmds = t, []
    while t - started < lost_s - 1e-9:
        cmds.append(guard.step(fg.Observation(t_s=round(t, 6), speed_mps=reported, cues=lost)))
        t += dt
    previous = [before[-1], *cmds[:-1]]
    for prev, c in zip(previous, cmds, strict=True):
        if any("a flicker is not one" in r for r in c.reasons):
            now = speed if measured else prev.speed_limit_mps
            assert now > 0.0, "a standing car gets no grace"
            assert c.speed_limit_mps <= now + 1e-9
    road_over = rules.evaluate(lost).cause_fears[fg.Cause.ROAD] >= rules.policy.emergency_enter_fear
    enough = rules.policy.road_enter_s + (rules.policy.enter_frames + 1) * dt
    if road_over and lost_s >= enough + dt:
        assert cmds[-1].mode is fg.Mode.EMERGENCY and cmds[-1].speed_limit_mps == 0.0
