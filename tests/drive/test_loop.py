"""The one driver loop on a real world (the built-in simulator): how a run ends, and the unguarded controller's fallback."""

from __future__ import annotations

import math
from collections.abc import Iterator, Sequence
from pathlib import Path

import numpy as np

from fearguard.drive.controllers import Unguarded, unsupervised_steering
from fearguard.drive.loop import run
from fearguard.drive.plan import RunSpec
from fearguard.drive.suite import finished_rows, run_plan
from fearguard.drive.world import Decision, Sensed
from fearguard.outputs.recorder import Recorder
from fearguard.outputs.report import read_jsonl
from fearguard.sim.loop import FaultyEstimator, SimWorld
from fearguard.sim.scenario import BUNDLED, load_scenario
from fearguard.sim.scenario_values import SteeringFault

SCENARIO = load_scenario(BUNDLED / "clear_straight.toml")


class CtrlCAfter:
    """The driver presses Ctrl-C while the controller thinks about frame ``n`` (a KeyboardInterrupt, as Python raises it)."""

    name = "unguarded"

    def __init__(self, n: int, inner: Unguarded) -> None:
        self.n, self.inner, self.calls = n, inner, 0

    def decide(self, sensed: Sensed) -> Decision:
        self.calls += 1
        if self.calls > self.n:
            raise KeyboardInterrupt
        return self.inner.decide(sensed)


def _unguarded(world: SimWorld) -> Unguarded:
    estimator = FaultyEstimator((), camera=world.world.camera, fps=SCENARIO.camera.fps)
    return Unguarded("unguarded", estimator, lambda _s: SCENARIO.cruise_speed_mps, SCENARIO.vehicle.max_steering_deg)


def test_ctrl_c_ends_the_run_with_every_frame_recorded_and_the_world_closed(tmp_path: Path) -> None:
    world = SimWorld(SCENARIO, seed=1, controller="unguarded")
    closed: list[bool] = []
    world.close = lambda: closed.append(True)  # type: ignore[method-assign]  # observe the loop closing the real world
    ran = run(world, CtrlCAfter(5, _unguarded(world)), Recorder(tmp_path, fps=SCENARIO.camera.fps), total=99)
    assert ran.interrupted and ran.stopped_by is None and ran.frames == 5 and closed == [True]
    rows = read_jsonl(tmp_path / "log.jsonl")
    assert [r["frame"] for r in rows] == [0, 1, 2, 3, 4] and len(ran.controller_ms) == 5


def test_an_estimator_that_raises_leaves_an_unsupervised_car_holding_its_last_angle() -> None:
    world = SimWorld(SCENARIO, seed=1, controller="unguarded")
    estimator = FaultyEstimator((SteeringFault(kind="raise", t_s=0.0, until_s=10.0, value=0.0),), camera=world.world.camera)
    frame = world.sense().observation.frame
    assert isinstance(frame, np.ndarray)
    angle, analysis = unsupervised_steering(estimator, frame, 7.5, 30.0, t_s=1.0)
    assert angle == 7.5 and analysis is not None and analysis.t_s == 1.0
    angle, _ = unsupervised_steering(FaultyEstimator((), camera=world.world.camera), frame, 7.5, 30.0)
    assert math.isfinite(angle) and angle != 7.5


def test_ctrl_c_during_a_suite_keeps_the_rows_that_finished(tmp_path: Path) -> None:
    specs = [RunSpec("sim", f"run {k}", "unguarded", k, {"file": str(BUNDLED / "clear_straight.toml")}) for k in range(3)]

    def first_then_ctrl_c(todo: Sequence[RunSpec], stop: object = None) -> Iterator[tuple[int, dict]]:
        yield 0, {"spec": todo[0].to_json(), "collisions": 0}
        raise KeyboardInterrupt

    log = tmp_path / "runs.jsonl"
    result = run_plan(specs, runs_log=log, executor=first_then_ctrl_c)
    assert result.interrupted and result.stopped_by is None and len(result.rows) == 1 and len(finished_rows(log)) == 1
    again = run_plan(specs[:1], runs_log=log, resume=True, executor=first_then_ctrl_c)  # nothing left to run
    assert not again.interrupted and again.resumed == 1 and again.rows == result.rows
    assert finished_rows(None) == [] and finished_rows(tmp_path / "none.jsonl") == []
