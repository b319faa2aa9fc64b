"""Timing watchdog and repeated frames: a stall is a fault; a loop faster than its camera is not "frozen"."""

from __future__ import annotations

import math

import cv2
import numpy as np
import pytest
from hypothesis import given
from hypothesis import strategies as st

import fearguard as fg

CALM = fg.Cues(0.9, 120.0, 0.0, math.inf, 0.5)
CAR = fg.VehicleLimits.preset("model_car")


def video_frames(shared_data, count: int | None = None) -> list[np.ndarray]:
    cap = cv2.VideoCapture(str(shared_data / "road" / "video" / "solidWhiteRight.mp4"))
    frames = []
    while count is None or len(frames) < count:
        ok, frame = cap.read()
        if not ok:
            break
        frames.append(frame)
    cap.release()
    assert frames, "solidWhiteRight.mp4 gave no frames"
    return frames


def test_a_2_s_stall_after_a_steady_drive_is_a_fault() -> None:
    guard = fg.FearGuard(lambda f: 0.0, vehicle=CAR)
    for k in range(40):
        assert guard.step(fg.Observation(t_s=0.05 * k, speed_mps=1.0, cues=CALM)).mode is fg.Mode.NORMAL
    for gap in (2.0, 5.0):
        guard.reset()
        for k in range(40):
            guard.step(fg.Observation(t_s=0.05 * k, speed_mps=1.0, cues=CALM))
        cmd = guard.step(fg.Observation(t_s=0.05 * 39 + gap, speed_mps=1.0, cues=CALM))
        assert cmd.mode is fg.Mode.EMERGENCY and cmd.strategy is fg.Strategy.STOP and cmd.speed_limit_mps == 0.0
        assert cmd.reasons[0] == f"fault: input stalled {gap:.1f} s (watchdog 1.0 s)"


def test_a_slow_loop_gets_a_watchdog_of_ten_periods() -> None:
    guard = fg.FearGuard(lambda f: 0.0, vehicle=CAR)
    for k in range(10):  # a 2 Hz loop: 10 periods = 5 s
        guard.step(fg.Observation(t_s=0.5 * k, speed_mps=1.0, cues=CALM))
    assert guard.step(fg.Observation(t_s=4.5 + 4.0, speed_mps=1.0, cues=CALM)).mode is not fg.Mode.EMERGENCY
    assert "input stalled 5.5 s" in guard.step(fg.Observation(t_s=8.5 + 5.5, speed_mps=1.0, cues=CALM)).reasons[0]


@given(st.lists(st.floats(0.01, 3.0), min_size=1, max_size=40))
def test_property_watchdog_faults_exactly_the_late_frames(gaps) -> None:
    guard = fg.FearGuard(lambda f: 0.0, vehicle=CAR)
    cfg = guard.rules.policy
    t, accepted = 0.0, []
    guard.step(fg.Observation(t_s=t, speed_mps=0.5, cues=CALM))
    for gap in gaps:
        t += gap
        cmd = guard.step(fg.Observation(t_s=t, speed_mps=0.5, cues=CALM))
        allowed = max(cfg.watchdog_age_s, cfg.watchdog_frames * float(np.median(accepted[-9:]))) if accepted else cfg.watchdog_age_s
        stalled = gap > allowed
        assert stalled == cmd.reasons[0].startswith("fault: input stalled")
        if stalled:
            assert cmd.strategy is fg.Strategy.STOP and cmd.speed_limit_mps == 0.0
        else:
            accepted.append(gap)


def test_a_20_hz_loop_on_a_5_fps_camera_is_not_frozen_and_adds_no_fear(shared_data) -> None:
    frames = video_frames(shared_data, 30)
    guard = fg.FearGuard(fg.HoughLaneSteering())
    first_fear = {}
    for k in range(4 * len(frames)):
        frame = frames[k // 4].copy()  # a new array every time, the same content up to 4 times in a row
        cmd = guard.step(fg.Observation(t_s=0.05 * k, speed_mps=1.0, frame=frame))
        assert not any("frozen" in r for r in cmd.reasons)
        first_fear.setdefault(k // 4, cmd.fear)
        if k % 4:
            assert cmd.fear == first_fear[k // 4]  # a repeated frame: the same analysis, no extra fear


def test_a_camera_identical_for_more_than_half_a_second_is_frozen(shared_data) -> None:
    frame = video_frames(shared_data, 1)[0]
    guard = fg.FearGuard(fg.HoughLaneSteering())
    cmds = [guard.step(fg.Observation(t_s=0.05 * k, speed_mps=1.0, frame=frame.copy())) for k in range(30)]
    frozen = [0.05 * k for k, c in enumerate(cmds) if any("camera: frozen" in r for r in c.reasons)]
    assert frozen and frozen[0] == pytest.approx(0.55) and math.isnan(cmds[-1].cues.lane_confidence)


def test_one_buffer_refilled_with_new_pixels_is_analysed_afresh(shared_data) -> None:
    frames = video_frames(shared_data, 20)
    guard = fg.FearGuard(fg.HoughLaneSteering())
    buffer = np.empty_like(frames[0])
    analyses = []
    for k, pixels in enumerate(frames):
        np.copyto(buffer, pixels)
        cmd = guard.step(fg.Observation(t_s=0.05 * k, speed_mps=1.0, frame=buffer))
        assert not any("no new frame" in r or "frozen" in r for r in cmd.reasons)
        analyses.append(cmd.perceived.analysis)
    assert len({id(a) for a in analyses}) == len(frames)


def test_camera_only_default_drives_the_real_video(shared_data) -> None:
    """FearGuard(steer) with the defaults, fed only the frames of an easy real drive: NORMAL on >= 90 % of them."""
    frames = video_frames(shared_data)
    guard = fg.FearGuard(fg.HoughLaneSteering())
    modes = [guard.step(fg.Observation(t_s=k / 25.0, speed_mps=1.0, frame=f)).mode for k, f in enumerate(frames)]
    normal = sum(m is fg.Mode.NORMAL for m in modes) / len(modes)
    assert normal >= 0.9, f"NORMAL on {100 * normal:.0f} % of {len(modes)} frames"
