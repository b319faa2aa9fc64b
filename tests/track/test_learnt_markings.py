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
from fearguard.track.learn import DARK_MARGIN, LearnOptions, learn_track, learnt_markings
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
