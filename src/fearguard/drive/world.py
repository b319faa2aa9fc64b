"""What a world and a controller are to the one driver loop: two small protocols and the plain values between them.

    world.sense()                 → Sensed (an Observation, the picture, when) or None: nothing more to drive
    controller.decide(sensed)     → Decision (a steering angle, a speed, the supervisor's Command if there is one)
    world.act(sensed, decision)   → Outcome (what the log records of this step, and whether the run is over)
    world.close()

A recording is a world whose ``act`` moves nothing (open loop); the built-in simulator, gym-duckietown and MetaDrive
are worlds whose ``act`` drives the car. A world keeps its own truth and metrics (they differ from world to world);
modes, episodes and statistics come from the one recorder the loop writes (``outputs/recorder.py``).
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass, field
from typing import Any, Protocol

import numpy as np

from fearguard.observation import Observation
from fearguard.supervisor import Command
from fearguard.vision.frame import FrameAnalysis


@dataclass(frozen=True, eq=False)  # eq=False: holds a picture
class Sensed:
    """One instant of a world: the frame number the log gives it, its time, the Observation, the picture."""

    index: int
    t_s: float
    observation: Observation
    image: np.ndarray | None = None  # what the annotated video draws on (None: the world renders nothing)
    resumed_after_s: float | None = None  # [s] a recording resumes after a pause this long: nothing before continues here


@dataclass(frozen=True)
class Decision:
    """A controller's answer: steer this much (deg, + = left), drive this fast, and what decided it."""

    steering_deg: float
    speed_mps: float  # the speed asked of the car: a cruise speed capped by the limit, or a baseline's target
    command: Command | None = None  # the supervisor's (None: an unsupervised controller)
    analysis: FrameAnalysis | None = None  # this frame's picture analysis, for the overlay
    action: Any = None  # a world's own actuation, when the controller computed it from the world's truth (an expert)


@dataclass(frozen=True)
class Outcome:
    """What one step did, as the log records it."""

    fields: Mapping[str, Any] = field(default_factory=dict)  # extra log fields (JSON values), in the order they are logged
    caption: str = ""  # the overlay's caption
    speed_mps: float | None = None  # the car's speed after the step, when the world knows it (the timeline draws it)
    done: bool = False  # the run is over (a collision, the end of the road, an invalid pose)
    t_s: float | None = None  # the log's time for this step when it is not the sensed time (a world that logs after its step)
    stamp_ns: int | None = None  # [ns] the recording's own stamp of the frame (a bag's), for run.mcap; None: t_s


class World(Protocol):
    """Anything that produces Observations and consumes a steering angle and a speed."""

    fps: float  # frames per second of the log and the video

    def sense(self) -> Sensed | None: ...

    def act(self, sensed: Sensed, decision: Decision) -> Outcome: ...

    def close(self) -> None: ...


class Controller(Protocol):
    """Observation → steering and speed (and the Command, for the supervised one)."""

    name: str

    def decide(self, sensed: Sensed) -> Decision: ...
