"""A replay says when the camera's lane model hardly saw the road, and what would help (replay/eyes.py): real model-car
recordings without a camera file or a track, the same with a learnt track, and a clean highway that needs no advice."""

from __future__ import annotations

import json
import math
from pathlib import Path

import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

import fearguard as fg
from fearguard.camera import save_camera
from fearguard.cli import main
from fearguard.fear import Cause, FearLevel
from fearguard.policy.config import Mode, Strategy
from fearguard.replay.eyes import ROAD_EMERGENCY_SHARE_MIN, SEEN_SHARE_MIN, EyesCheck
from fearguard.supervisor import Command
from fearguard.track.learn import LearnOptions, learn_track
from fearguard.track.profile import save_track

TUB = "modelcar/donkey-carpet-dark"  # black tape on dark carpet, a Donkey tub at 160x120
DEEPPICAR = "modelcar/deeppicar-tape/video01.avi"  # blue tape on a wooden floor, a PiCar's 320x240 video
HIGHWAY = "road/video/project_video.mp4"  # a clean dash-cam highway


def _replay(args: list[str], out: Path, capsys) -> tuple[dict, str]:
    assert main(["replay", *args, "--no-plots", "--out", str(out)]) == 0
    printed = capsys.readouterr().out
    return json.loads((out / "summary.json").read_text())["eyes_check"], printed


@pytest.mark.parametrize("source, span", [(TUB, ["--to", "300f"]), (DEEPPICAR, ["--to", "200f"])])
def test_a_model_car_replayed_without_camera_or_track_is_told_what_would_help(shared_data, tmp_path, capsys, source, span):
    check, printed = _replay([str(shared_data / source), "--vehicle", "donkey", *span], tmp_path / "rp", capsys)
    assert check["lane_seen_share"] < SEEN_SHARE_MIN and check["road_emergency_share"] >= ROAD_EMERGENCY_SHARE_MIN
    note = next(line for line in printed.splitlines() if line.startswith("note: the lane was seen"))
    assert note == f"note: {check['advice']}"
    assert "fearguard learn" in note and "--track" in note and "--camera" in note and "dash-cam" in note
    assert f"{100 * check['lane_seen_share']:.0f} % of frames" in note
    assert "--markings dark" in note  # the lane model looked for light paint: dark tape is worth a try


def test_advice_after_looking_for_dark_tape_does_not_ask_for_it_again(shared_data, tmp_path, capsys):
    check, _ = _replay([str(shared_data / TUB), "--vehicle", "donkey", "--to", "200f", "--markings", "dark"], tmp_path / "rp", capsys)
    assert check["advice"] is not None and "fearguard learn" in check["advice"] and "--markings" not in check["advice"]


def test_with_a_camera_file_the_advice_is_to_learn_the_track(shared_data, tmp_path, capsys):
    camera = tmp_path / "camera.toml"
    save_camera(fg.CameraModel.default(320, 240, pitch_deg=20.0), camera)  # looking 20 deg down, its height not measured
    check, _ = _replay([str(shared_data / DEEPPICAR), "--vehicle", "donkey", "--to", "200f", "--camera", str(camera)],
                             tmp_path / "rp", capsys)
    assert check["advice"] is not None and "fearguard learn" in check["advice"] and "--camera" not in check["advice"]


def test_with_a_learnt_track_there_is_no_advice_and_the_car_drives(shared_data, tmp_path, capsys):
    track = save_track(learn_track([shared_data / TUB], LearnOptions(stop="1200f", every=2)).profile, tmp_path / "track.npz")
    check, printed = _replay([str(shared_data / TUB), "--vehicle", "donkey", "--from", "1300f", "--to", "1600f", "--track",
                              str(track)], tmp_path / "rp", capsys)
    assert check["advice"] is None and "note: the lane was seen" not in printed
    assert check["frames"] == 300 and 0.0 <= check["lane_seen_share"] <= 1.0


def test_a_clean_highway_needs_no_advice(shared_data, tmp_path, capsys):
    check, _ = _replay([str(shared_data / HIGHWAY), "--to", "5s"], tmp_path / "rp", capsys)
    assert check["advice"] is None and check["lane_seen_share"] > 0.9 and check["lane_confidence_median"] > 0.5
    assert check["road_emergency_share"] == 0.0


def _command(confidence: float, mode: Mode, cause: Cause | None) -> Command:
    cues = fg.Cues(lane_confidence=confidence, brightness=120.0, occlusion=0.0, obstacle_range_m=math.inf, qr_staleness_s=0.0)
    return Command(0.0, 0.0, mode, Strategy.STOP if mode is Mode.EMERGENCY else Strategy.PASS_THROUGH, 0.5, FearLevel.MEDIUM,
                   cues, (), cause=cause)


frames = st.lists(st.tuples(st.one_of(st.floats(0.0, 1.0), st.just(math.nan)), st.sampled_from(list(Mode)),
                            st.sampled_from([*Cause, None])), max_size=60)


@settings(max_examples=200, deadline=None)
@given(frames=frames, camera=st.booleans(), track=st.booleans())
def test_the_verdict_counts_what_it_was_given(frames, camera, track):
    check = EyesCheck(0.25, camera=camera, track=track)
    check.add(None)  # a frame without a command counts for nothing
    for confidence, mode, cause in frames:
        check.add(_command(confidence, mode, cause))
    v = check.finish()
    read = [c for c, _, _ in frames if not math.isnan(c)]
    assert v.frames == len(read)
    if not read:
        assert v.lane_seen_share is None and v.advice is None
        return
    assert v.lane_seen_share == sum(c >= 0.25 for c in read) / len(read)
    ordered = sorted(read)
    assert ordered[(len(read) - 1) // 2] - 0.011 <= v.lane_confidence_median <= ordered[len(read) // 2] + 0.011  # to the hundredth
    road = sum(m is Mode.EMERGENCY and c is Cause.ROAD for _, m, c in frames) / len(frames)
    assert v.road_emergency_share == pytest.approx(road)
    wanted = v.lane_seen_share < SEEN_SHARE_MIN and road >= ROAD_EMERGENCY_SHARE_MIN and not track
    assert (v.advice is not None) == wanted
    if wanted:
        assert ("--camera" in v.advice) == (not camera) and "fearguard learn" in v.advice
