"""A track profile learns whether the track's markings are light paint or dark tape, keeps it in its file, and the
supervisor's and replay's lane model then looks for them (``markings``)."""

from __future__ import annotations

import json
import math
from pathlib import Path

import cv2
import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

import fearguard as fg
from fearguard.cli import main
from fearguard.errors import FileError
from fearguard.track.learn import (
    CENTRE_SHARE,
    DARK_MARGIN,
    ONE_LINE_MIN_SHARE,
    ONE_LINE_RATIO,
    LaneRead,
    LearnOptions,
    learn_track,
    learnt_guidance,
    learnt_markings,
)
from fearguard.track.profile import load_track, save_track
from tests.vision.test_dark_markings import DARK_TAPES, FLOORS, track_frame

FRAMES = 60


def _recording(folder: Path, tape: tuple[int, int, int], floors: tuple[tuple[int, int, int], ...]) -> Path:
    """An image folder of a car weaving gently along a taped lane (the lane's centre sways across the picture)."""
    folder.mkdir(parents=True)
    for i in range(FRAMES):
        centre = 160.0 + 20.0 * math.sin(i / 7.0)
        cv2.imwrite(str(folder / f"{i:04d}.png"), track_frame(floors[i % len(floors)], tape, 5, centre, i))
    return folder


@pytest.fixture(scope="module")
def dark_track(tmp_path_factory) -> tuple[fg.TrackProfile, Path]:
    rec = _recording(tmp_path_factory.mktemp("dark") / "frames", DARK_TAPES[0], FLOORS[:1])
    return learn_track([rec], LearnOptions(fps=20.0)).profile, rec


def test_a_track_taped_in_black_is_learnt_dark_and_one_painted_white_light(dark_track, tmp_path):
    profile, _ = dark_track
    assert profile.markings == "dark" and profile.lane_confidence_median >= 0.5
    light = _recording(tmp_path / "light", (235, 235, 235), ((45, 45, 50),))
    assert learn_track([light], LearnOptions(fps=20.0)).profile.markings == "light"


def test_the_markings_survive_the_file_and_an_older_file_reads_light(dark_track, tmp_path):
    profile, _ = dark_track
    path = save_track(profile, tmp_path / "t.npz")
    assert load_track(path).markings == "dark"
    with np.load(path) as z:
        data = {k: z[k] for k in z.files}
    older = tmp_path / "older.npz"
    np.savez(older, **{k: v for k, v in data.items() if k != "markings"})
    assert load_track(older).markings == "light"
    bad = tmp_path / "bad.npz"
    np.savez(bad, **{**data, "markings": np.array("grey")})
    with pytest.raises(FileError, match="markings"):
        load_track(bad)


@settings(max_examples=60, deadline=None, derandomize=True)
@given(light=st.lists(st.floats(0, 1) | st.just(math.nan), max_size=20), dark=st.lists(st.floats(0, 1) | st.just(math.nan), max_size=20))
def test_dark_markings_are_learnt_only_where_they_are_seen_clearly_better(light, dark):
    def med(xs):
        v = [x for x in xs if math.isfinite(x)]
        return float(np.median(v)) if v else 0.0

    assert learnt_markings(light, dark) == ("dark" if med(dark) >= med(light) + DARK_MARGIN else "light")


def test_the_supervisor_with_a_dark_track_looks_for_dark_tape(dark_track):
    profile, _ = dark_track
    assert fg.FearGuard(lambda frame: 0.0, track=profile).perception.pipeline.markings == "dark"
    assert fg.FearGuard(lambda frame: 0.0).perception.pipeline.markings == "light"
    shared = fg.HoughLaneSteering()  # a steering that shares its pipeline decides for itself
    assert fg.FearGuard(shared, track=profile).perception.pipeline.markings == "light"


def test_replay_finds_the_dark_lane_with_the_profile_or_the_option_and_not_without(dark_track, tmp_path, capsys):
    profile, rec = dark_track
    track = save_track(profile, tmp_path / "t.npz")

    def median_confidence(*extra: str) -> float:
        out = tmp_path / f"o{len(list(tmp_path.iterdir()))}"
        assert main(["replay", str(rec), "--fps", "20", "--out", str(out), "--no-plots", *extra]) == 0
        rows = [json.loads(line) for line in (out / "log.jsonl").read_text().splitlines()]
        return float(np.median([r["lane_confidence"] for r in rows]))

    assert median_confidence("--markings", "dark") >= 0.5
    assert median_confidence("--track", str(track)) >= 0.5
    assert median_confidence() <= 0.2
    assert main(["replay", str(rec), "--markings", "dark", "--steer", "fearguard.demo:straight",
                 "--out", str(tmp_path / "x")]) == 2
    assert "--markings" in capsys.readouterr().err
    with pytest.raises(SystemExit) as bad:
        main(["replay", str(rec), "--markings", "grey", "--out", str(tmp_path / "y")])
    assert bad.value.code == 2 and "--markings" in capsys.readouterr().err


def _one_line_recording(folder: Path, where: float, tape=(235, 235, 235), floor=(45, 45, 50)) -> Path:
    """An image folder of a track guided by one line: its bottom end at ``where`` of the width (0.5: a centre line)."""
    folder.mkdir(parents=True)
    rng = np.random.default_rng(7)
    for i in range(FRAMES):
        img = np.clip(np.full((240, 320, 3), floor, np.int16) + rng.normal(0, 4, (240, 320, 3)), 0, 255).astype(np.uint8)
        bottom = 320 * where + 15.0 * math.sin(i / 7.0)
        far = (160.0 + 0.3 * (bottom - 160.0), 0.45 * 240 + 0.3 * (240 - 0.45 * 240))
        cv2.line(img, (round(bottom), 240), (round(far[0]), round(far[1])), tape, 6, cv2.LINE_AA)
        cv2.imwrite(str(folder / f"{i:04d}.png"), img)
    return folder


@pytest.mark.parametrize(("where", "guidance"), [(0.5, "centre_line"), (0.15, "one_edge"), (0.85, "one_edge")])
def test_a_track_guided_by_one_line_is_learnt_so_and_replayed_with_its_own_confidence(tmp_path, where, guidance):
    rec = _one_line_recording(tmp_path / "frames", where)
    profile = learn_track([rec], LearnOptions(fps=20.0)).profile
    assert profile.guidance == guidance and profile.markings == "light" and profile.lane_confidence_median >= 0.5
    track = save_track(profile, tmp_path / "t.npz")
    assert load_track(track).guidance == guidance
    medians = {}
    for name, extra in (("profile", ["--track", str(track)]), ("two", []), ("option", ["--guidance", guidance])):
        out = tmp_path / name
        assert main(["replay", str(rec), "--fps", "20", "--out", str(out), "--no-plots", *extra]) == 0
        rows = [json.loads(line) for line in (out / "log.jsonl").read_text().splitlines()]
        medians[name] = float(np.median([r["lane_confidence"] for r in rows]))
    assert medians["option"] >= 0.6 and medians["two"] <= 0.5  # one boundary of two counts half


def test_a_two_line_track_is_learnt_as_two_lines(dark_track):
    assert dark_track[0].guidance == "two_lines"


def test_a_wrong_guidance_in_a_profile_names_its_key(dark_track, tmp_path):
    with np.load(save_track(dark_track[0], tmp_path / "t.npz")) as z:
        data = {k: z[k] for k in z.files}
    bad = tmp_path / "bad.npz"
    np.savez(bad, **{**data, "guidance": np.array("three_lines")})
    with pytest.raises(FileError, match="guidance"):
        load_track(bad)


def test_the_lane_reason_names_a_one_line_guidance(tmp_path):
    rec = _one_line_recording(tmp_path / "frames", 0.5)
    frame = cv2.imread(str(sorted(rec.iterdir())[0]))
    for guidance, says in (("centre_line", "guidance centre line: its best line"), ("two_lines", None)):
        perception = fg.FearGuard(fg.HoughLaneSteering(guidance=guidance)).perception
        facts = " ".join(perception.perceive(fg.Observation(frame=frame, t_s=0.0)).facts)
        assert "lane: confidence" in facts and ((says in facts) if says else ("guidance" not in facts))


@settings(max_examples=100, deadline=None, derandomize=True)
@given(views=st.lists(st.sampled_from([(), (0.5,), (0.1,), (0.9,), (0.2, 0.8)]), max_size=40))
def test_one_line_is_learnt_only_from_enough_frames_that_show_one_line(views):
    reads = [LaneRead(0.5, 0.0, None, v) for v in views]
    one = [v[0] for v in views if len(v) == 1]
    both = sum(len(v) == 2 for v in views)
    got = learnt_guidance(reads)
    if not one or len(one) < ONE_LINE_MIN_SHARE * len(views) or len(one) < ONE_LINE_RATIO * both:
        assert got == "two_lines"
    else:
        assert got == ("centre_line" if abs(float(np.median(one)) - 0.5) <= CENTRE_SHARE else "one_edge")
