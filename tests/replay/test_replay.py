"""Replay of recorded drives: real videos end to end, truncated and killed runs, a Donkey tub, an image folder,
and a sensor log with an approaching obstacle."""

from __future__ import annotations

import json
import subprocess
import sys
import time
from pathlib import Path

import cv2
import numpy as np
import pytest

from fearguard.cli import main
from fearguard.outputs.report import read_jsonl
from fearguard.replay.run import ReplayOptions, replay


@pytest.fixture(scope="module")
def video(shared_data: Path) -> Path:
    return shared_data / "road" / "video" / "solidWhiteRight.mp4"


def test_easy_drive_replays_without_false_alarms(video: Path, tmp_path: Path, capsys):
    assert main(["replay", str(video), "--out", str(tmp_path)]) == 0
    records = read_jsonl(tmp_path / "log.jsonl")
    assert len(records) == 221
    summary = json.loads((tmp_path / "summary.json").read_text())
    calm = summary["fear_level_share"]["VERY_LOW"] + summary["fear_level_share"]["LOW"]
    assert calm >= 0.9 and summary["emergency_episodes"] == []
    assert (tmp_path / "timeline.png").stat().st_size > 1000
    assert "emergency episodes: 0" in capsys.readouterr().out


def test_a_truncated_video_replays_up_to_the_cut_and_says_so(video: Path, tmp_path: Path):
    cut = tmp_path / "cut.mp4"
    data = video.read_bytes()
    cut.write_bytes(data[: int(0.4 * len(data))])
    result = replay(cut, tmp_path / "out", ReplayOptions(plots=False))
    records = read_jsonl(tmp_path / "out" / "log.jsonl")
    assert 0 < len(records) < 221 and records[-1]["frame"] == len(records) - 1
    assert result.summary["stopped_early"] and "221" in result.summary["stopped_early"]


def test_a_killed_replay_leaves_valid_json_lines(video: Path, tmp_path: Path):
    out = tmp_path / "killed"
    proc = subprocess.Popen([sys.executable, "-m", "fearguard.cli", "replay", str(video), "--out", str(out)],
                            stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
    log = out / "log.jsonl"
    deadline = time.monotonic() + 60
    while time.monotonic() < deadline and (not log.exists() or log.read_text().count("\n") < 20):
        time.sleep(0.05)
    proc.kill()
    proc.wait()
    lines = log.read_text().splitlines()
    assert len(lines) >= 20
    complete = lines if log.read_text().endswith("\n") else lines[:-1]
    frames = [json.loads(line)["frame"] for line in complete]  # every complete line parses
    assert frames == list(range(len(frames)))


def _still(shared_data: Path) -> np.ndarray:
    return cv2.resize(cv2.imread(str(shared_data / "road" / "images" / "solidWhiteRight.jpg")), (320, 180))


def test_an_image_folder_replays_in_name_order(shared_data: Path, tmp_path: Path):
    folder = tmp_path / "imgs"
    folder.mkdir()
    for k in (1, 2, 10):
        cv2.imwrite(str(folder / f"img{k}.jpg"), _still(shared_data))
    result = replay(folder, tmp_path / "out", ReplayOptions(fps=10.0, plots=False))
    records = read_jsonl(tmp_path / "out" / "log.jsonl")
    assert [r["t_s"] for r in records] == pytest.approx([0.0, 0.1, 0.2])
    assert result.summary["kind"] == "images"


def _write_tub(tub: Path, image: np.ndarray, stamps_ms: list[float], deleted: list[int] = ()) -> Path:
    """A Donkey tub (manifest, catalog, images) of ``image`` at these clock stamps; record i: angle 0.1 i, throttle 0.3."""
    (tub / "images").mkdir(parents=True)
    inputs, types = ["cam/image_array", "user/angle", "user/throttle", "user/mode"], ["image_array", "float", "float", "str"]
    lines = []
    for i, stamp in enumerate(stamps_ms):
        cv2.imwrite(str(tub / "images" / f"{i}_cam_image_array_.jpg"), image)
        lines.append(json.dumps({"_index": i, "_session_id": "s", "_timestamp_ms": stamp,
                                 "cam/image_array": f"{i}_cam_image_array_.jpg", "user/angle": 0.1 * i, "user/throttle": 0.3,
                                 "user/mode": "user"}))
    (tub / "catalog_0.catalog").write_text("\n".join(lines) + "\n")
    (tub / "catalog_0.catalog_manifest").write_text(json.dumps({"path": "catalog_0.catalog", "created_at": 0, "line_lengths": [],
                                                                "start_index": 0}) + "\n")
    manifest = [json.dumps(inputs), json.dumps(types), json.dumps({}), json.dumps({"created_at": 0}),
                json.dumps({"paths": ["catalog_0.catalog"], "current_index": len(stamps_ms), "max_len": 1000,
                            "deleted_indexes": list(deleted)})]
    (tub / "manifest.json").write_text("\n".join(manifest) + "\n")
    return tub


def test_a_donkey_tub_replays_with_its_recorded_angles(shared_data: Path, tmp_path: Path):
    tub = _write_tub(tmp_path / "tub", _still(shared_data), [1000 + 50 * i for i in range(6)], deleted=[2])
    result = replay(tub, tmp_path / "out", ReplayOptions(plots=False))
    records = read_jsonl(tmp_path / "out" / "log.jsonl")
    assert [r["frame"] for r in records] == [0, 1, 3, 4, 5]
    assert records[1]["user_angle_donkey"] == pytest.approx(0.1) and records[1]["t_s"] == pytest.approx(0.05)
    assert records[1]["user_throttle_donkey"] == 0.3 and records[1]["user_mode_donkey"] == "user"
    units = result.summary["log_field_units"]  # the tub's channels only (no pilot/* in this one), units and sign said
    assert set(units) == {"user_angle_donkey", "user_throttle_donkey", "user_mode_donkey"}
    assert "-1 = full left, + = right" in units["user_angle_donkey"]
    assert result.summary["recording_pauses"] == []  # a deleted record is 0.1 s: no pause


def test_a_real_tubs_throttle_pause_is_a_fresh_start_not_a_stalled_camera(shared_data: Path, tmp_path: Path, capsys):
    """donkey-carpet-dark stops recording for 1.15 s before record 1487 (the throttle fell from 0.5 to 0.16 and comes
    back at 0.04: Donkey records only while the car drives). Replayed, that is no stall fault: the supervisor starts
    afresh there, the log and the summary say so; the same frames read as a 10 Hz image folder have no pause at all."""
    tub = shared_data / "modelcar" / "donkey-carpet-dark"
    out = tmp_path / "out"
    assert main(["replay", str(tub), "--vehicle", "donkey", "--from", "1478f", "--to", "1496f", "--out", str(out), "--no-plots"]) == 0
    assert "1 recording pause(s)" in capsys.readouterr().out
    records = read_jsonl(out / "log.jsonl")
    resumed = [r for r in records if "resumed_after_s" in r]
    assert [r["frame"] for r in resumed] == [1487] and resumed[0]["resumed_after_s"] == pytest.approx(1.154, abs=1e-3)
    assert not any("stalled" in reason for r in records for reason in r["reasons"])
    summary = json.loads((out / "summary.json").read_text())
    assert summary["recording_pauses"] == [{"frame": 1487, "paused_s": pytest.approx(1.154, abs=1e-3)}]


@pytest.mark.parametrize(("gap_s", "pause"), [(0.3, False), (0.95, False), (1.2, True), (45.0, True), (600.0, True)])
def test_a_tub_gap_longer_than_the_watchdog_is_a_pause_and_resets_the_supervisor(shared_data: Path, tmp_path: Path,
                                                                                  gap_s: float, pause: bool):
    """20 Hz records with one gap after record 9: beyond the watchdog's 1 s (max(10 periods, 1 s)) it is a pause, the
    supervisor starting afresh (its speed limit ramps up from standing again); within it, the drive simply goes on."""
    stamps = [50.0 * i + (1000.0 * gap_s if i >= 10 else 0.0) for i in range(20)]
    tub = _write_tub(tmp_path / "tub", _still(shared_data), stamps)
    result = replay(tub, tmp_path / "out", ReplayOptions(plots=False))
    records = read_jsonl(tmp_path / "out" / "log.jsonl")
    assert not any(reason.startswith("fault") for r in records for reason in r["reasons"])
    assert [p["frame"] for p in result.summary["recording_pauses"]] == ([10] if pause else [])
    assert ("resumed_after_s" in records[10]) is pause
    if pause:
        assert records[10]["speed_limit_mps"] <= records[0]["speed_limit_mps"] + 1e-9  # a fresh ramp, as at the start


def test_a_gap_in_a_recording_that_is_no_tub_stays_a_stall(shared_data: Path, tmp_path: Path):
    """A bag or a video has no throttle-gated recorder: a long gap there is the car's own stall, a fault (the watchdog)."""
    import fearguard as fg
    from fearguard.drive.controllers import Guarded
    from fearguard.replay.run import RecordingWorld
    from fearguard.replay.sources import Frame

    image = _still(shared_data)
    frames = iter([Frame(k, 0.05 * k + (3.0 if k >= 5 else 0.0), image, {}) for k in range(8)])
    world, guarded = RecordingWorld(frames, 20.0, None, 1.0), Guarded(fg.FearGuard(fg.HoughLaneSteering()))
    reasons = []
    while (sensed := world.sense()) is not None:
        assert sensed.resumed_after_s is None
        reasons.append(guarded.decide(sensed).command.reasons[0])
    assert "input stalled" in reasons[5] and world.pauses == []


def test_a_sensor_log_with_an_approaching_obstacle_drives_fear_and_the_limit(shared_data: Path, tmp_path: Path):
    folder = tmp_path / "imgs"
    folder.mkdir()
    for k in range(40):
        cv2.imwrite(str(folder / f"f{k:03d}.jpg"), _still(shared_data))
    log = tmp_path / "sensors.csv"
    rows = ["t_s,ultrasonic_range_m,speed_mps"] + [f"{0.1 * k:.1f},{max(0.2, 3.0 - 0.08 * k):.3f},1.0" for k in range(40)]
    rows.insert(5, "0.45,not-a-number,1.0")  # a malformed line: reported with its line number, skipped
    log.write_text("\n".join(rows) + "\n")
    result = replay(folder, tmp_path / "out", ReplayOptions(fps=10.0, sensor_log=str(log), plots=False))
    records = read_jsonl(tmp_path / "out" / "log.jsonl")
    ranges = [r["obstacle_range_m"] for r in records]
    assert ranges[0] == pytest.approx(3.0, abs=0.1) and ranges[-1] < 0.5
    assert records[-1]["fear"] > records[0]["fear"] and records[-1]["speed_limit_mps"] < 0.5 * records[5]["speed_limit_mps"] + 1e-9
    assert records[-1]["mode"] == "EMERGENCY" and records[-1]["strategy"] == "STOP"
    assert [i["line"] for i in result.summary["sensor_log_issues"]] == [6]
    with pytest.raises(Exception, match="line 6"):
        replay(folder, tmp_path / "strict", ReplayOptions(fps=10.0, sensor_log=str(log), strict=True, plots=False))


def test_missing_or_unreadable_recording_exits_2_with_advice(tmp_path: Path, capsys):
    assert main(["replay", str(tmp_path / "nope.mp4"), "--out", str(tmp_path / "o")]) == 2
    assert "no such file" in capsys.readouterr().err
    fake = tmp_path / "fake.mp4"
    fake.write_text("not a video")
    assert main(["replay", str(fake), "--out", str(tmp_path / "o2")]) == 2
    assert "ffmpeg" in capsys.readouterr().err


def test_project_video_sample_explains_where_fear_rose(shared_data: Path, tmp_path: Path):
    src = shared_data / "road" / "video" / "project_video.mp4"
    result = replay(src, tmp_path, ReplayOptions(start="20s", stop="26s", plots=False))
    assert result.summary["processed_frames"] == 150
    for stretch in result.summary["elevated_fear"]:
        assert stretch["why"] and stretch["cue_at_peak"]
