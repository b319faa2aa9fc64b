"""Issue 35, the supervisor's side of stop lines: a line perception reports is stood at, then crossed; while crossing,
a road picture without markings is CAUTION on the path seen clear at the stop, not an emergency. Perception is
scripted here (its own tests and the Duckietown drives measure real frames): the supervisor gets the measured values."""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

import fearguard as fg
from fearguard.perception import Perceived
from tests.conftest import RULES_DIR

FRAME = np.zeros((120, 160, 3), np.uint8)
CLEAR = fg.Cues(0.95, 120.0, 0.0, math.inf, 0.0)
NO_TAPE = fg.Cues(0.05, 120.0, 0.9, math.inf, 0.0)  # the crossing: no markings, the picture measured


@dataclass
class Scripted:
    """Stands in for the camera's perception: this frame's cues, stop line and clear path, as a frame would give them."""

    cues: fg.Cues = CLEAR
    stop_line_m: float | None = None
    clear_m: float = 2.0

    def perceive(self, obs: fg.Observation) -> Perceived:
        return Perceived(cues=self.cues, lead=None, alerts=(), clear_m=self.clear_m, stop_line_m=self.stop_line_m)


def test_stand_at_the_line_then_cross_without_an_emergency() -> None:
    guard = fg.FearGuard(lambda frame: 0.0, rules=fg.load_rules(RULES_DIR / "duckiebot.toml"),
                         vehicle=fg.VehicleLimits.preset("duckiebot"))
    script = Scripted()
    guard.perception = script
    cfg, t, speed, cmds = guard.rules.policy, 0.0, 0.2, []
    for k in range(120):  # 30 Hz: 4 s
        script.stop_line_m = 0.28 if 10 <= k < 14 else None  # seen late, then under the camera
        script.cues, script.clear_m = (NO_TAPE, 0.0) if k >= 50 else (CLEAR, 2.0)  # the intersection: no tape, no search
        cmd = guard.step(fg.Observation(t_s=t, speed_mps=speed, frame=FRAME))
        cmds.append(cmd)
        speed = min(0.2, cmd.speed_limit_mps)  # the robot obeys at once
        t += 1 / 30
    stood = [k for k, c in enumerate(cmds) if any(r.startswith("stop line: standing") for r in c.reasons)]
    served = next(k for k, c in enumerate(cmds) if any(r.startswith("stop line: stood") for r in c.reasons))
    assert stood and cmds[10].speed_limit_mps == 0.0 and (served - stood[0]) / 30 >= cfg.stop_line_wait_s - 0.05
    crossing = cmds[50:]
    assert all(c.mode is not fg.Mode.EMERGENCY for c in crossing)
    assert any(any(r.startswith("crossing after a stop line") for r in c.reasons) for c in crossing)
    assert all(c.speed_limit_mps <= cfg.road_doubt_fraction * guard.vehicle.max_speed_mps + 1e-9 for c in crossing[10:])


def test_without_a_served_stop_the_same_missing_picture_with_nothing_known_is_an_emergency() -> None:
    guard = fg.FearGuard(lambda frame: 0.0, rules=fg.load_rules(RULES_DIR / "duckiebot.toml"),
                         vehicle=fg.VehicleLimits.preset("duckiebot"))
    guard.perception = Scripted(cues=NO_TAPE, clear_m=0.0)
    cmds = [guard.step(fg.Observation(t_s=k / 30, speed_mps=0.2, frame=FRAME)) for k in range(30)]
    assert cmds[-1].mode is fg.Mode.EMERGENCY
