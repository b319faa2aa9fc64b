"""The controllers a world can be driven by: fearguard, and what fearguard is compared with.

- ``Guarded``: ``FearGuard`` around the world's steering estimator; the car drives min(cruise, speed limit).
- ``Unguarded``: the steering estimator alone at a speed rule (cruise, or a baseline's: ``sim/baselines.py``); an
  estimator that fails keeps the last angle, as a car without a supervisor would.
A world's own expert (its ground truth, e.g. Duckietown's pure pursuit) is a controller of that world.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import replace

from fearguard.drive.world import Decision, Sensed
from fearguard.perception import FrameSteering
from fearguard.supervisor import FearGuard
from fearguard.vision.frame import FrameAnalysis

SpeedRule = Callable[[Sensed], float]  # the speed an unsupervised controller asks for at this instant


class Guarded:
    """fearguard: the supervisor's command steers, and the car drives min(cruise, speed limit)."""

    name = "guarded"

    def __init__(self, guard: FearGuard, cruise_mps: float = math.inf) -> None:
        self.guard = guard
        self.cruise_mps = cruise_mps

    def decide(self, sensed: Sensed) -> Decision:
        if sensed.resumed_after_s is not None:  # a recording's pause: the car stood meanwhile, its supervisor starts afresh
            self.guard.reset()
        cmd = self.guard.step(sensed.observation)
        analysis = cmd.perceived.analysis if cmd.perceived is not None else None
        return Decision(cmd.steering_deg, min(self.cruise_mps, cmd.speed_limit_mps), cmd, analysis)


class Unguarded:
    """The steering estimator alone, at the speed its rule asks for; on a fault it holds the last angle."""

    def __init__(self, name: str, estimator: FrameSteering, speed: SpeedRule, max_steering_deg: float) -> None:
        self.name = name
        self.estimator = estimator
        self.speed = speed
        self.max_steering_deg = max_steering_deg
        self._last_deg = 0.0

    def decide(self, sensed: Sensed) -> Decision:
        frame = sensed.observation.frame
        steering, analysis = unsupervised_steering(self.estimator, frame, self._last_deg, self.max_steering_deg, sensed.t_s)
        self._last_deg = steering
        return Decision(steering, self.speed(sensed), None, analysis)


def unsupervised_steering(
    estimator: FrameSteering, frame: object, last: float, limit: float, t_s: float = math.nan,
) -> tuple[float, FrameAnalysis | None]:
    """What a car without a supervisor does with its estimator's answer: use it; on a fault, keep the last angle.

    Also returns the frame's analysis (for the video), None if the analysis itself failed.
    """
    analysis = None
    try:
        analysis = replace(estimator.pipeline.process(frame), t_s=t_s)  # the world's clock (a fault injector reads it)
        angle = float(estimator.steer_from(analysis))
    except Exception:  # an unsupervised car has no better idea than holding the wheel
        return last, analysis
    return (max(-limit, min(limit, angle)) if math.isfinite(angle) else last), analysis
