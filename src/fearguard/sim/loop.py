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
from collections.abc import Callable, Mapping
from dataclasses import asdict, dataclass, field, replace
from pathlib import Path
from typing import Any

from fearguard.camera import CameraModel
from fearguard.drive.controllers import Guarded, Unguarded
from fearguard.drive.interrupt import StopSignal
from fearguard.drive.loop import run
from fearguard.drive.world import Controller, Decision, Outcome, Sensed
from fearguard.errors import EstimatorFault
from fearguard.fuzzy.loader import load_rules, policy_with
from fearguard.fuzzy.rulebase import RuleBase
from fearguard.observation import Observation
from fearguard.outputs.recorder import Recorder, Trace
from fearguard.sim.baselines import BASELINES, Baseline
from fearguard.sim.metrics import ExpectationResult, Metrics, Row, RunMetrics, check_expectations
from fearguard.sim.scenario_values import Scenario, SteeringFault
from fearguard.sim.world import World
from fearguard.supervisor import FearGuard
from fearguard.vehicle import VehicleLimits
from fearguard.vision.frame import FrameAnalysis
from fearguard.vision.lane_steering import HoughLaneSteering

CONTROLLERS = ("guarded", *BASELINES)


class FaultyEstimator(HoughLaneSteering):
    """The lane steering with the scenario's estimator faults applied at their times (the frame's, ``analysis.t_s``)."""

    def __init__(self, faults: tuple[SteeringFault, ...], camera: CameraModel | None = None, fps: float = 20.0) -> None:
        super().__init__(camera, fps)
        self.faults = faults

    def steer_from(self, analysis: FrameAnalysis) -> float:
        angle = super().steer_from(analysis)
        t_s = analysis.t_s
        for f in self.faults:
            if f.active(t_s):
                if f.kind == "raise":
                    raise EstimatorFault(f"simulated estimator fault at t={t_s:.2f} s")
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


class SimWorld:
    """The built-in simulator as a ``World``: rendered frames and simulated sensors in, steering and speed out; the
    truth of every step goes to the run's metrics."""

    def __init__(self, scenario: Scenario, seed: int, controller: str) -> None:
        self.world = World(scenario, seed=seed)
        self.fps = scenario.camera.fps
        self.controller = controller
        self.metrics = Metrics()
        self._frames = 0

    def sense(self) -> Sensed:
        sens = self.world.sense()
        obs = Observation(t_s=sens.t_s, speed_mps=sens.speed_mps, frame=sens.frame_bgr, ultrasonic_range_m=sens.ultrasonic_range_m,
                          odometer_m=sens.odometer_m)
        return Sensed(self._frames, sens.t_s, obs, sens.frame_bgr)

    def act(self, sensed: Sensed, decision: Decision) -> Outcome:
        self.world.advance(decision.steering_deg, decision.speed_mps)
        truth = self.world.truth()
        cmd = decision.command
        if cmd is None:
            self.metrics.add(truth)
        else:
            self.metrics.add(truth, cmd.mode, cmd.strategy, cmd.speed_limit_mps, cmd.fear)
        self._frames += 1
        fields = {
            "controller": self.controller, "speed_target_mps": decision.speed_mps, "applied_steering_deg": decision.steering_deg,
            "speed_mps": truth.speed_mps, "s_m": truth.s_m, "lateral_m": truth.lateral_m, "x_m": truth.x_m, "y_m": truth.y_m,
            "gap_m": truth.gap_m, "ttc_s": truth.ttc_s, "collided": truth.collided, "in_lane": truth.in_lane,
            "ultrasonic_raw_m": sensed.observation.ultrasonic_range_m,
        }
        return Outcome(fields, f"v {truth.speed_mps:.2f} m/s", truth.speed_mps, truth.collided or truth.finished)

    def close(self) -> None:
        """Nothing to release (the simulator is plain Python)."""


def scenario_controller(name: str, scenario: Scenario, guard: FearGuard, estimator: FaultyEstimator, limits: VehicleLimits) -> Controller:
    """fearguard (``guarded``), or a baseline speed rule around the same estimator (``sim/baselines.py``)."""
    profile = scenario.vehicle
    if name == "guarded":
        return Guarded(guard, profile.cruise_speed_mps)
    baseline = Baseline(name, profile.cruise_speed_mps, limits.ultrasonic_min_range_m, limits.ultrasonic_max_range_m)
    return Unguarded(name, estimator, lambda s: baseline.speed_target(s.t_s, s.observation.ultrasonic_range_m),
                     profile.max_steering_deg)


def run_scenario(
    scenario: Scenario, seed: int | None = None, controller: str = "guarded", out_dir: Path | None = None, *, video: bool = False,
    on_frame: Callable[[int, int], None] | None = None, stop: StopSignal | None = None, video_kind: str | None = None,
    mcap: bool = False, policy: Mapping[str, Any] | None = None, vehicle: Mapping[str, Any] | None = None,
    track: str | None = None,
) -> RunResult:
    """Run one scenario closed loop; with ``out_dir``, record log.jsonl (flushed per frame) and, if asked, the video.

    ``policy`` / ``vehicle`` change numbers of the rule file's [policy] table and of the supervisor's VehicleLimits (a
    sweep's ``--set``), validated as the files are (a RuleError / ValueError otherwise); the car's physics stay the scenario's.

    ``stop`` (from ``interrupt.stop_on_signals``) ends the run after the current frame; so does a
    KeyboardInterrupt. Either way the result says ``interrupted`` and keeps every frame recorded.

    ``track``: a track profile (``fearguard learn``, e.g. on an earlier run's video) the guarded supervisor reads with.
    """
    if controller not in CONTROLLERS:
        raise ValueError(f"unknown controller {controller!r}; choose one of {', '.join(CONTROLLERS)}")
    seed = scenario.seed if seed is None else seed
    world = SimWorld(scenario, seed, controller)
    camera = world.world.camera
    estimator = FaultyEstimator(scenario.faults.steering, camera=camera, fps=scenario.camera.fps)
    limits = scenario.vehicle.limits
    if scenario.sensors is not None:  # the range sensor the scenario's car carries (HC-SR04 on a model car, radar-like on a road car)
        limits = replace(limits, ultrasonic_min_range_m=scenario.sensors.min_range_m, ultrasonic_max_range_m=scenario.sensors.max_range_m)
    limits = replace(limits, **vehicle) if vehicle else limits
    rules = load_rules(scenario.rules_path)
    if policy:
        rules = replace(rules, policy=policy_with(rules.policy, policy, f"{scenario.path}: the changed [policy] of {rules.path}"))
    guard = FearGuard(estimator, rules=rules, vehicle=limits, camera=camera, track=track)
    total = math.ceil(scenario.duration_s / world.world.dt_s)
    recorder = Recorder(out_dir, fps=scenario.camera.fps, video=video, video_kind=video_kind, mcap=mcap)
    ran = run(world, scenario_controller(controller, scenario, guard, estimator, limits), recorder, stop=stop, on_frame=on_frame,
              total=total)
    metrics = world.metrics
    result = metrics.result()
    results = tuple(check_expectations(scenario.expectations, result, metrics.rows))
    return RunResult(scenario.name, controller, seed, result, results, ran.frames, ran.interrupted, ran.stopped_by,
                     tuple(metrics.rows), recorder.trace, recorder.video_path, guard.rules if controller == "guarded" else None)
