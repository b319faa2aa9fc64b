"""The closed loop: rendered frames and simulated sensors → real perception and supervisor → the car.

Every frame: the world is sensed (camera frame, ultrasonic, odometer, speed); the steering estimator
(default ``HoughLaneSteering`` on the rendered frame, with the scenario's estimator fault applied)
proposes an angle; ``FearGuard`` (or a baseline) decides; the car follows min(cruise, limit) within
its limits. No cue shortcuts: the cues come from pixels and readings. Same scenario and seed →
identical log, byte for byte (nothing reads the wall clock into the log). What a run leaves behind
(log, video, trace for the plots) goes through ``recorder.Recorder``, as for every driver.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import asdict, dataclass, field, replace
from pathlib import Path
from typing import Any

import numpy as np

from fearguard.camera import CameraModel
from fearguard.errors import EstimatorFault
from fearguard.fuzzy.loader import load_rules
from fearguard.fuzzy.rulebase import RuleBase
from fearguard.interrupt import StopSignal
from fearguard.observation import Observation
from fearguard.recorder import Recorder, Trace
from fearguard.sim.baselines import BASELINES, Baseline
from fearguard.sim.metrics import ExpectationResult, Metrics, Row, RunMetrics, check_expectations
from fearguard.sim.scenario_values import Scenario, SteeringFault
from fearguard.sim.world import World
from fearguard.supervisor import Command, FearGuard
from fearguard.vision.frame import FrameAnalysis
from fearguard.vision.lane_steering import HoughLaneSteering

CONTROLLERS = ("guarded", *BASELINES)


class FaultyEstimator(HoughLaneSteering):
    """The lane steering with the scenario's estimator faults applied at their times (``t_s`` set by the loop)."""

    def __init__(self, faults: tuple[SteeringFault, ...], camera: CameraModel | None = None, fps: float = 20.0) -> None:
        super().__init__(camera, fps)
        self.faults = faults
        self.t_s = 0.0

    def steer_from(self, analysis: FrameAnalysis) -> float:
        angle = super().steer_from(analysis)
        for f in self.faults:
            if f.active(self.t_s):
                if f.kind == "raise":
                    raise EstimatorFault(f"simulated estimator fault at t={self.t_s:.2f} s")
                if f.kind == "nan":
                    return math.nan
                if f.kind == "stuck":
                    return f.value
                if f.kind == "bias":
                    return angle + f.value
        return angle


@dataclass(frozen=True)
class RunResult:
    """A finished (or interrupted) run: its metrics, the expectations checked, and what the plots need."""

    scenario: str
    controller: str
    seed: int
    metrics: RunMetrics
    expectations: tuple[ExpectationResult, ...]
    frames: int
    interrupted: bool = False
    stopped_by: str | None = None  # the signal that interrupted the run (None: Ctrl-C as KeyboardInterrupt, or none)
    rows: tuple[Row, ...] = field(default=(), repr=False)  # per-frame truth and decisions (trajectory plot)
    trace: Trace | None = field(default=None, repr=False, compare=False)  # per-frame cues and decisions (timeline plot)
    video_path: Path | None = None
    rules: RuleBase | None = field(default=None, repr=False, compare=False)  # the supervisor's (None: unsupervised), for the timeline

    @property
    def passed(self) -> bool:
        """Every applicable expectation holds, over a run that was not cut short (an interrupted run never passes).

        A supervisor-only expectation (``mode_by``...) does not apply to a baseline (``ok`` None): it neither passes nor fails it.
        """
        return not self.interrupted and not any(e.failed for e in self.expectations)

    @property
    def summary(self) -> dict[str, Any]:
        """The metrics as JSON values (summary.json's metric keys)."""
        return self.metrics.to_json()

    def to_json(self) -> dict[str, Any]:
        """summary.json: who ran what, the verdict, each expectation, then the metrics."""
        head: dict[str, Any] = {"scenario": self.scenario, "controller": self.controller, "seed": self.seed, "frames": self.frames,
                                "interrupted": self.interrupted}
        if self.stopped_by is not None:
            head["stopped_by"] = self.stopped_by
        return {**head, "passed": self.passed, "expectations": [asdict(e) for e in self.expectations], **self.metrics.to_json()}


def run_scenario(
    scenario: Scenario, seed: int | None = None, controller: str = "guarded", out_dir: Path | None = None, *, video: bool = False,
    on_frame: Callable[[int, int], None] | None = None, stop: StopSignal | None = None, video_kind: str | None = None,
    mcap: bool = False,
) -> RunResult:
    """Run one scenario closed loop; with ``out_dir``, record log.jsonl (flushed per frame) and, if asked, the video.

    ``stop`` (from ``interrupt.stop_on_signals``) ends the run after the current frame; so does a
    KeyboardInterrupt. Either way the result says ``interrupted`` and keeps every frame recorded.
    """
    if controller not in CONTROLLERS:
        raise ValueError(f"unknown controller {controller!r}; choose one of {', '.join(CONTROLLERS)}")
    seed = scenario.seed if seed is None else seed
    world = World(scenario, seed=seed)
    camera = world.camera
    estimator = FaultyEstimator(scenario.faults.steering, camera=camera, fps=scenario.camera.fps)
    profile = scenario.vehicle
    limits = profile.limits
    if scenario.sensors is not None:  # the range sensor the scenario's car carries (HC-SR04 on a model car, radar-like on a road car)
        limits = replace(limits, ultrasonic_min_range_m=scenario.sensors.min_range_m, ultrasonic_max_range_m=scenario.sensors.max_range_m)
    guard = FearGuard(estimator, rules=load_rules(scenario.rules_path), vehicle=limits, camera=camera)
    baseline = None
    if controller != "guarded":
        baseline = Baseline(controller, profile.cruise_speed_mps, limits.ultrasonic_min_range_m, limits.ultrasonic_max_range_m)
    metrics = Metrics()
    total = math.ceil(scenario.duration_s / world.dt_s)
    recorder = Recorder(out_dir, fps=scenario.camera.fps, video=video, video_kind=video_kind, mcap=mcap)
    frame_index, interrupted, last_steer = 0, False, 0.0
    try:
        with recorder:
            while not stop:
                sens = world.sense()
                estimator.t_s = sens.t_s
                cmd: Command | None = None
                analysis: FrameAnalysis | None = None
                if baseline is None:
                    obs = Observation(t_s=sens.t_s, speed_mps=sens.speed_mps, frame=sens.frame_bgr,
                                      ultrasonic_range_m=sens.ultrasonic_range_m, odometer_m=sens.odometer_m)
                    cmd = guard.step(obs)
                    steering, target = cmd.steering_deg, min(profile.cruise_speed_mps, cmd.speed_limit_mps)
                    analysis = cmd.perceived.analysis if cmd.perceived is not None else None
                else:
                    steering, analysis = _unsupervised_steering(estimator, sens.frame_bgr, last_steer, profile.max_steering_deg)
                    target = baseline.speed_target(sens.t_s, sens.ultrasonic_range_m)
                last_steer = steering
                world.advance(steering, target)
                truth = world.truth()
                if cmd is None:
                    metrics.add(truth)
                else:
                    metrics.add(truth, cmd.mode, cmd.strategy, cmd.speed_limit_mps, cmd.fear)
                recorder.frame(
                    frame_index, sens.t_s, cmd, image=sens.frame_bgr, analysis=analysis, caption=f"v {truth.speed_mps:.2f} m/s",
                    speed_mps=truth.speed_mps, fields={
                        "controller": controller, "speed_target_mps": target, "applied_steering_deg": steering,
                        "speed_mps": truth.speed_mps, "s_m": truth.s_m, "lateral_m": truth.lateral_m, "x_m": truth.x_m, "y_m": truth.y_m,
                        "gap_m": truth.gap_m, "ttc_s": truth.ttc_s, "collided": truth.collided, "in_lane": truth.in_lane,
                        "ultrasonic_raw_m": sens.ultrasonic_range_m,
                    })
                frame_index += 1
                if on_frame is not None:
                    on_frame(frame_index, total)
                if truth.collided or truth.finished:
                    break
    except KeyboardInterrupt:
        interrupted = True
    interrupted = interrupted or bool(stop)
    run = metrics.result()
    results = tuple(check_expectations(scenario.expectations, run, metrics.rows))
    return RunResult(scenario.name, controller, seed, run, results, frame_index, interrupted, stop.name if stop else None,
                     tuple(metrics.rows), recorder.trace, recorder.video_path, guard.rules if baseline is None else None)


def _unsupervised_steering(
    estimator: FaultyEstimator, frame: np.ndarray, last: float, limit: float
) -> tuple[float, FrameAnalysis | None]:
    """What a car without a supervisor does with its estimator's answer: use it; on a fault, keep the last angle.

    Also returns the frame's analysis (for the video), None if the analysis itself failed.
    """
    analysis = None
    try:
        analysis = estimator.pipeline.process(frame)
        angle = float(estimator.steer_from(analysis))
    except Exception:  # an unsupervised car has no better idea than holding the wheel
        return last, analysis
    return (max(-limit, min(limit, angle)) if math.isfinite(angle) else last), analysis
