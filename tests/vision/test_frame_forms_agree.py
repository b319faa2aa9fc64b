"""The stateless and the stateful frame analysis are one computation (filterpy's procedural-vs-class test).

``analyze_frame`` and a ``FramePipeline`` built with pass-through trackers must give the same
measurements on every frame of a rendered drive; with its real trackers the pipeline may differ only
through what it remembers.
"""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest

import fearguard as fg
from fearguard.sim.scenario import load_scenario
from fearguard.sim.suite import BUNDLED
from fearguard.sim.world import World
from fearguard.vision.frame import QR_EVERY_N_FRAMES, FrameAnalysis, FramePipeline
from fearguard.vision.trackers import Trackers

FRAMES = 60  # 3 s at 20 Hz


def _rendered(name: str) -> tuple[fg.CameraModel, list[tuple[float, np.ndarray]]]:
    """(t_s, frame) of a drive through a bundled scenario, steered by the stateless baseline at cruise speed."""
    scenario = load_scenario(BUNDLED / f"{name}.toml")
    world = World(scenario, seed=1)
    frames = []
    for _ in range(FRAMES):
        sensed = world.sense()
        frames.append((sensed.t_s, sensed.frame_bgr.copy()))
        angle = fg.analyze_frame(sensed.frame_bgr, world.camera).steering_deg
        world.advance(angle if angle is not None else 0.0, scenario.cruise_speed_mps)
    return world.camera, frames


def _value(a: FrameAnalysis, scanned: bool) -> str:
    """Everything measured (exact: repr keeps every float bit, and NaN equals NaN), timings and the time stamp aside."""
    return repr(dataclasses.replace(a, timings_ms={}, qr_payloads=a.qr_payloads if scanned else (), t_s=0.0))  # when: the caller's


@pytest.mark.parametrize("name", ["occluding_traffic_follow_lead", "qr_markers_missing", "camera_blackout"])
def test_the_pipeline_with_pass_through_trackers_agrees_with_analyze_frame_on_every_frame(name: str) -> None:
    camera, frames = _rendered(name)
    pipeline = FramePipeline(camera, trackers=Trackers.pass_through)
    stateless = []
    for k, (t_s, frame) in enumerate(frames):
        expected = fg.analyze_frame(frame, camera)
        got = pipeline.process(frame, t_s, scan_qr=True)
        assert _value(got, k % QR_EVERY_N_FRAMES == 0) == _value(expected, k % QR_EVERY_N_FRAMES == 0), f"frame {k}"
        stateless.append(expected)
    assert any(a.steering_deg is not None for a in stateless)  # the drive shows a lane: the comparison is not vacuous
    if name == "occluding_traffic_follow_lead":
        assert any(a.lead is not None for a in stateless)
    if name == "qr_markers_missing":
        assert any(a.qr_payloads for a in stateless)


def test_with_its_trackers_the_pipeline_remembers_until_reset() -> None:
    camera, frames = _rendered("occluding_traffic_follow_lead")
    tracking, passing = FramePipeline(camera), FramePipeline(camera, trackers=Trackers.pass_through)
    first = [_value(tracking.process(f, t), False) for t, f in frames]
    assert first != [_value(passing.process(f, t), False) for t, f in frames]  # tracks, lane memory, confidence median
    tracking.reset()
    assert [_value(tracking.process(f, t), False) for t, f in frames] == first  # a reset forgets everything
