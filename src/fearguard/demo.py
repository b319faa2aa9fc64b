"""A scripted cue-level drive for ``fearguard demo``: each hazard in turn, no camera needed."""

from __future__ import annotations

import math
from collections.abc import Iterator

from fearguard.cues import Cues
from fearguard.fuzzy.rulebase import RuleBase
from fearguard.observation import Lead, Observation
from fearguard.supervisor import FearGuard
from fearguard.vehicle import PRESETS

RATE_HZ = 10.0  # [Hz]
# (from s, label, cues, lead): a 1:10 car on a track with QR markers
SCRIPT: tuple[tuple[float, str, Cues, Lead | None], ...] = (
    (0.0, "clear track", Cues(0.9, 120.0, 0.0, math.inf, 1.0), None),
    (4.0, "tunnel exit glare", Cues(0.35, 245.0, 0.05, math.inf, 1.0), None),
    (7.0, "clear again", Cues(0.9, 130.0, 0.0, math.inf, 1.0), None),
    (11.0, "traffic hides markings, lead ahead", Cues(0.15, 120.0, 0.8, 1.8, 2.0), Lead(4.0, 1.8)),
    (15.0, "clear again", Cues(0.9, 120.0, 0.0, math.inf, 1.0), None),
    (19.0, "box on the track", Cues(0.9, 120.0, 0.1, 0.45, 1.0), None),
    (22.0, "QR markers missing", Cues(0.9, 120.0, 0.0, math.inf, 20.0), None),
    (26.0, "end", Cues(0.9, 120.0, 0.0, math.inf, 1.0), None),
)


def demo_drive(rules: RuleBase) -> Iterator[str]:
    """Yield a table: one row per 0.5 s and one per mode change, the car driving at the limit."""
    guard = FearGuard(lambda frame: 1.5, rules=rules, vehicle=PRESETS["model_car"])  # HC-SR04 and QR markers
    yield f"{'t_s':>5}  {'situation':<36} {'fear':>5} {'level':<9} {'mode':<9} {'strategy':<12} {'limit':>6} {'steer':>6}"
    speed, last_mode = 0.0, None
    end = SCRIPT[-1][0]
    for k in range(int(end * RATE_HZ)):
        t = k / RATE_HZ
        _, label, cues, lead = max((s for s in SCRIPT if s[0] <= t + 1e-9), key=lambda s: s[0])
        cmd = guard.step(Observation(t_s=t, speed_mps=speed, cues=cues, lead=lead))
        speed = cmd.speed_limit_mps  # the car obeys the limit instantly: the worst case for the ramp
        if k % int(RATE_HZ / 2) == 0 or cmd.mode != last_mode:
            yield (f"{t:5.1f}  {label:<36} {cmd.fear:5.2f} {cmd.fear_level.name:<9} {cmd.mode.name:<9} "
                   f"{cmd.strategy.name:<12} {cmd.speed_limit_mps:6.2f} {cmd.steering_deg:+6.1f}")
            if cmd.mode != last_mode and last_mode is not None:
                events = [r for r in cmd.reasons[3:] if r.startswith(("entered EMERGENCY", "left EMERGENCY"))]
                yield "       ↳ " + "; ".join([*cmd.reasons[:3], *events])  # the mode change itself is always shown
        last_mode = cmd.mode
