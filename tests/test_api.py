"""The public surface docs/architecture.md promises: names outside tests call exactly."""

from __future__ import annotations

import dataclasses
import inspect
from pathlib import Path

import numpy as np
import pytest

import fearguard as fg


def test_public_names_are_exported_explicitly() -> None:
    expected = {"TrackProfile", "load_track",
                "CUE_NAMES", "CameraModel", "Cause", "Command", "Cues", "FearGuard", "FearLevel", "FearResult",
                "FearguardError", "FrameAnalysis", "FrameSteering", "GroundLaneSpec", "HoughLaneSteering", "Lead", "LeadBox",
                "Mode", "Observation",
                "PolicyConfig", "RuleBase", "RuleError", "Strategy", "VehicleLimits", "analyze_frame", "load_camera",
                "load_rules", "save_camera"}
    assert set(fg.__all__) == expected
    assert all(hasattr(fg, name) for name in fg.__all__)


def test_the_bending_lane_model_is_a_keyword_only_addition() -> None:
    """Added after the contract: the ground-plane lane model is asked for by keyword, the positional signatures stay."""
    for call in (fg.HoughLaneSteering, fg.vision.frame.FramePipeline):
        ground = inspect.signature(call).parameters["ground"]
        assert ground.kind is inspect.Parameter.KEYWORD_ONLY and ground.default is None
    spec = fg.GroundLaneSpec(lane_width_m=0.236)
    assert (spec.near_m, spec.far_m, spec.aim_m, spec.max_bearing_deg) == (0.07, 0.5, 0.25, 75.0)


def test_values_moved_to_observation_keep_their_old_import_paths() -> None:
    import fearguard.observation
    import fearguard.policy
    import fearguard.supervisor
    import fearguard.vision.lead

    assert fg.Lead is fearguard.observation.Lead is fearguard.policy.Lead
    assert fg.LeadBox is fearguard.observation.LeadBox is fearguard.vision.lead.LeadBox
    assert fg.Observation is fearguard.observation.Observation is fearguard.supervisor.Observation
    assert [f.name for f in dataclasses.fields(fg.Observation)][:9] == [  # later fields are additions
        "t_s", "speed_mps", "frame", "cues", "ultrasonic_range_m", "odometer_m", "qr_payload", "lead", "ultrasonic_echo_s"]


def test_design_contract_signatures() -> None:
    assert fg.CUE_NAMES == ("lane_confidence", "brightness", "occlusion", "obstacle_range_m", "qr_staleness_s", "familiarity")
    assert fg.Cues(0.9, 120.0, 0.0, 3.0, 0.5).familiarity == 1.0  # five fields: a car without a track profile
    assert [f.name for f in dataclasses.fields(fg.Cues)] == list(fg.CUE_NAMES)
    assert [level.value for level in fg.FearLevel] == [0, 1, 2, 3, 4] and fg.FearLevel.VERY_HIGH.name == "VERY_HIGH"
    assert {m.name for m in fg.Mode} == {"NORMAL", "CAUTION", "EMERGENCY"}
    assert {s.name for s in fg.Strategy} == {"PASS_THROUGH", "FOLLOW_LEAD", "STOP", "CRAWL"}
    assert list(inspect.signature(fg.FearGuard).parameters)[:4] == ["steer", "rules", "vehicle", "camera"]
    obs = fg.Observation(t_s=0.0, speed_mps=1.0, frame=None, cues=None, ultrasonic_range_m=None,
                         odometer_m=None, qr_payload=None, lead=None)
    cmd = fg.FearGuard(lambda frame: 0.0).step(obs)
    for name in ("steering_deg", "speed_limit_mps", "mode", "strategy", "fear", "fear_level", "cues", "reasons", "perceived"):
        assert hasattr(cmd, name)
    perceived = next(f for f in dataclasses.fields(fg.Command) if f.name == "perceived")
    assert not perceived.compare and not perceived.repr and perceived.default is None
    assert fg.Lead(1.0).range_m is None
    for name in ("max_speed_mps", "max_decel_mps2", "reaction_time_s", "stop_margin_m", "max_steering_deg"):
        assert name in {f.name for f in dataclasses.fields(fg.VehicleLimits)}
    res = fg.load_rules().evaluate(fg.Cues(lane_confidence=.9, brightness=120., occlusion=0., obstacle_range_m=3., qr_staleness_s=.5))
    assert isinstance(res.fear, float) and isinstance(res.level, fg.FearLevel) and isinstance(res.activations, dict)


def test_analyze_frame_contract() -> None:
    frame = np.full((240, 320, 3), 90, np.uint8)
    a = fg.analyze_frame(frame, camera=None)
    for name in ("lane_confidence", "brightness", "occlusion", "lead", "qr_payloads", "steering_deg"):
        assert hasattr(a, name)
    assert isinstance(a.qr_payloads, tuple) and (a.lead is None or isinstance(a.lead, fg.Lead))
    assert a.steering_deg is None  # a blank grey frame shows no lane
    steer = fg.HoughLaneSteering()
    assert isinstance(steer(frame), float)
    assert isinstance(steer, fg.FrameSteering) and isinstance(steer.steer_from(steer.pipeline.process(frame)), float)


def test_camera_projection_and_its_inverse_agree(tmp_path: Path) -> None:
    cam = fg.CameraModel.default(320, 240, hfov_deg=62.2, mount_height_m=0.15, pitch_deg=13.0)
    for ahead_m, left_m in ((0.5, 0.0), (1.0, 0.2), (3.0, -0.3)):
        u, v, front = cam.project_ground(np.array([ahead_m]), np.array([left_m]))
        assert front[0]
        assert cam.ground_range_m(float(v[0])) == pytest.approx(ahead_m, rel=1e-9)
        assert np.sign(cam.bearing_deg(float(u[0]))) == np.sign(left_m)
    _, far_v, _ = cam.project_ground(np.array([1e7]), np.array([0.0]))
    assert float(far_v[0]) == pytest.approx(cam.horizon_v_px(), abs=1e-3)
    path = tmp_path / "camera.toml"
    fg.save_camera(cam, path)
    assert fg.load_camera(path) == cam


def test_additions_of_issue_32_are_pinned() -> None:
    """A caller that holds the estimator's angle passes it; a detector's box has its own field; ``steer`` may be None."""
    names = [f.name for f in dataclasses.fields(fg.Observation)]
    assert names[names.index("range_rate_mps") + 1 :] == ["steering_deg", "lead_box", "route_steering_deg"]  # + issue 38's route
    box = fg.LeadBox(10.0, 20.0, 30.0, 40.0)
    obs = fg.Observation(t_s=0.0, lead=box)  # the contract's lead= took a box: it keeps working, as lead_box
    assert obs.lead is None and obs.lead_box == box
    guard = fg.FearGuard(None)
    assert guard.step(fg.Observation(t_s=0.0, steering_deg=3.0, cues=fg.Cues(1.0, 130.0, 0.0, float("inf"), 0.0))).steering_deg == 3.0
    fault = guard.step(fg.Observation(t_s=0.1, cues=fg.Cues(1.0, 130.0, 0.0, float("inf"), 0.0)))
    assert fault.reasons[0] == "fault: no steering: give Observation.steering_deg or a steering function"
    bad = fg.FearGuard(None).step(fg.Observation(t_s=0.0, steering_deg=float("nan")))
    assert bad.reasons[0] == "fault: the given steering_deg is nan, not a finite number"
