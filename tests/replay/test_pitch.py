"""Pitch sanity (issue 37): a camera.toml with the wrong pitch is noticed from where the lane lines meet; the right one is not."""

from __future__ import annotations

import json
from pathlib import Path

import pytest

import fearguard as fg
from fearguard.camera import save_camera
from fearguard.cli import main
from fearguard.replay.pitch import PITCH_MIN_FRAMES, PitchCheck

VIDEO = "road/video/project_video.mp4"


def _replay_with_pitch(shared_data: Path, tmp_path: Path, pitch_deg: float, capsys) -> tuple[dict, str]:
    camera = tmp_path / f"camera{pitch_deg:+g}.toml"
    save_camera(fg.CameraModel.default(1280, 720, pitch_deg=pitch_deg), camera)  # as `fearguard calibrate --pitch-deg` writes it
    out = tmp_path / f"out{pitch_deg:+g}"
    assert main(["replay", str(shared_data / VIDEO), "--camera", str(camera), "--to", "6s", "--no-plots", "--out", str(out)]) == 0
    err = capsys.readouterr().err
    return json.loads((out / "summary.json").read_text())["pitch_check"], err


def test_a_pitch_of_3_deg_on_the_shared_highway_is_called_out_once_with_the_pitch_the_lines_suggest(shared_data, tmp_path, capsys):
    check, err = _replay_with_pitch(shared_data, tmp_path, 3.0, capsys)
    warnings = [line for line in err.splitlines() if line.startswith("warning: camera pitch")]
    assert len(warnings) == 1, err
    assert check["warned"] and check["assumed_pitch_deg"] == pytest.approx(3.0, abs=0.01)
    assert -5.0 < check["suggested_pitch_deg"] < -1.0 and check["off_by_deg"] < -3.0  # the lines meet well below that horizon
    assert f"{check['suggested_pitch_deg']:+.1f}°" in warnings[0] and "--pitch-deg" in warnings[0]


def test_the_right_pitch_stays_quiet(shared_data, tmp_path, capsys):
    check, err = _replay_with_pitch(shared_data, tmp_path, -1.5, capsys)
    assert "warning: camera pitch" not in err
    assert not check["warned"] and check["frames"] >= PITCH_MIN_FRAMES and abs(check["off_by_deg"]) <= 3.0


def test_without_enough_frames_showing_both_lines_there_is_no_verdict() -> None:
    check = PitchCheck(None)
    for i in range(3):
        check.add(i * 0.05, None, (320, 240))
    verdict = check.finish()
    assert verdict.off_by_deg is None and not verdict.warned and verdict.frames == 0
    assert check.finish() is verdict  # decided once
