"""Track profiles (issue 34): learnt from real recordings, read back exactly, a calibrated familiarity that falls for
what is unlike the recordings, the light read against the learnt band — and every wrong file a FileError naming its key."""

from __future__ import annotations

import io
import itertools
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
from fearguard.track.features import frame_features
from fearguard.track.learn import LearnOptions, learn_track
from fearguard.track.profile import (
    FAMILIAR_AT_REFERENCE,
    UNFAMILIAR_RATIO,
    familiarity_from,
    load_track,
    profile_from_arrays,
    save_track,
)

ROBOCAR = "modelcar/robocar-ucsd-window/images"  # glass walls, a bright window: 160×120 images, 20 fps
DEEPPICAR = "modelcar/deeppicar-tape/video01.avi"  # a PiCar on tape, 320×240 video
TUB = "modelcar/donkey-carpet-dark"  # a Donkey tub on dark carpet


@pytest.fixture(scope="module")
def robocar_track(shared_data: Path) -> fg.TrackProfile:
    return learn_track([shared_data / ROBOCAR], LearnOptions(stop="1300f", every=2)).profile


def _frames(path: Path, start: int, stop: int, every: int) -> list[np.ndarray]:
    from fearguard.replay.recordings import open_recording

    return [f.image_bgr for f in open_recording(path).iter_frames(start, stop, every)]


def test_a_profile_survives_its_file(robocar_track, tmp_path):
    back = load_track(save_track(robocar_track, tmp_path / "t.npz"))
    for key in ("mean", "weights", "basis", "bank", "calibration_distances"):
        assert np.array_equal(getattr(back, key), getattr(robocar_track, key)), key
    assert back.brightness_band == robocar_track.brightness_band and back.frames_learnt == robocar_track.frames_learnt
    frame = _frames(Path(robocar_track.source), 1400, 1401, 1)[0]
    assert back.familiarity(frame) == robocar_track.familiarity(frame)


def test_later_frames_of_the_same_track_are_familiar_other_tracks_and_changes_are_not(robocar_track, shared_data):
    later = [robocar_track.familiarity(f)[0] for f in _frames(shared_data / ROBOCAR, 1350, 2550, 40)]
    assert np.median(later) >= 0.8  # the same room, a few laps on
    for other in (TUB, DEEPPICAR):  # another room, another camera
        there = [robocar_track.familiarity(f)[0] for f in _frames(shared_data / other, 0, 200, 20)]
        assert np.mean(np.array(there) < 0.5) >= 0.8, (other, there)
    boxed = []
    for i, f in enumerate(_frames(shared_data / ROBOCAR, 1350, 2550, 80)):  # a box over half the lane, colours vary
        f = f.copy()
        h, w = f.shape[:2]
        f[h // 2:, w // 4: 3 * w // 4] = ((i * 67) % 256, (i * 131) % 256, (i * 29) % 256)
        boxed.append(robocar_track.familiarity(f)[0])
    assert np.mean(np.array(boxed) < 0.5) >= 0.8, boxed


@settings(max_examples=200, deadline=None)
@given(st.floats(0.0, 1e6), st.floats(0.0, 1e6))
def test_familiarity_never_rises_with_distance_and_stays_in_0_1(robocar_track, a, b):
    fa, fb = robocar_track.familiarity_of(min(a, b)), robocar_track.familiarity_of(max(a, b))
    assert 0.0 <= fb <= fa <= 1.0


def test_familiarity_is_1_for_the_typical_frame_graded_to_the_reference_and_0_from_the_unfamiliar_ratio(robocar_track):
    typ, ref = robocar_track.typical_distance, robocar_track.reference_distance
    assert 0.0 < typ < ref
    assert robocar_track.familiarity_of(0.5 * typ) == robocar_track.familiarity_of(typ) == 1.0
    assert 1.0 > robocar_track.familiarity_of(0.5 * (typ + ref)) > FAMILIAR_AT_REFERENCE
    assert robocar_track.familiarity_of(ref) == pytest.approx(FAMILIAR_AT_REFERENCE)
    assert robocar_track.familiarity_of(UNFAMILIAR_RATIO * ref) == 0.0
    assert math.isnan(robocar_track.familiarity_of(math.nan))


distances = st.floats(0.0, 1e6, allow_nan=False)


@settings(max_examples=300, deadline=None)
@given(distances, distances, st.floats(0.0, 1e3), st.floats(0.0, 1e3))
def test_familiarity_from_any_calibration_never_rises_with_distance(a, b, typical, reference):
    """Whatever the recordings' own distances (a typical distance at, above or below the reference, zeros), a farther
    frame is never more familiar, the cue stays in 0..1, a frame as near as the typical one is fully familiar, and an
    unknown distance stays unknown (the worst)."""
    near, far = min(a, b), max(a, b)
    f_near, f_far = familiarity_from(near, reference, typical), familiarity_from(far, reference, typical)
    assert 0.0 <= f_far <= f_near <= 1.0
    assert familiarity_from(min(typical, reference) * 0.999, reference, typical) == 1.0
    assert math.isnan(familiarity_from(math.nan, reference, typical))


@pytest.mark.parametrize("rules", ["default.toml", "duckiebot.toml", "road_car.toml"])
def test_calm_frames_less_typical_than_the_median_read_more_fear_but_stay_normal(robocar_track, rules):
    """Between the typical recorded frame and d_ref the fear orders the frames (what a replay's fear curve and an
    AUROC of fear need), and every one of them stays below caution."""
    from fearguard.fuzzy.loader import bundled_rules_path, load_rules

    rb = load_rules(bundled_rules_path(rules))
    typ, ref = robocar_track.typical_distance, robocar_track.reference_distance
    fears = [rb.engine.evaluate([1.0, 128.0, 0.0, math.inf, 0.0, robocar_track.familiarity_of(d)]).fear
             for d in np.linspace(typ, ref, 6)]
    assert all(a < b for a, b in itertools.pairwise(fears)), fears
    assert fears[-1] < rb.policy.caution_fear


@settings(max_examples=200, deadline=None)
@given(st.floats(0.0, 255.0), st.floats(0.0, 255.0), st.floats(0.0, 255.0), st.floats(0.0, 255.0))
def test_light_read_against_the_learnt_band_keeps_darker_darker_and_the_ends_fixed(robocar_track, a, b, lo, hi):
    from dataclasses import replace

    lo, hi = sorted((lo, hi))
    track = replace(robocar_track, brightness_band=(lo, hi))
    band = (80.0, 180.0)
    ra, rb = track.brightness_as_learnt(min(a, b), band), track.brightness_as_learnt(max(a, b), band)
    assert 0.0 <= ra <= rb <= 255.0
    assert track.brightness_as_learnt(0.0, band) == 0.0 and track.brightness_as_learnt(255.0, band) == 255.0
    if 1.0 <= lo and lo + 1.0 <= hi <= 254.0:
        assert track.brightness_as_learnt(lo, band) == pytest.approx(80.0)
        assert track.brightness_as_learnt(hi, band) == pytest.approx(180.0)


def test_a_dim_room_is_normal_for_the_car_that_learnt_it_and_a_blackout_is_not(robocar_track):
    from dataclasses import replace

    dim = replace(robocar_track, brightness_band=(30.0, 60.0))
    assert 80.0 <= dim.brightness_as_learnt(45.0, (80.0, 180.0)) <= 180.0
    assert dim.brightness_as_learnt(4.0, (80.0, 180.0)) < 20.0  # the rule file's dark


@settings(max_examples=12, deadline=None)
@given(st.floats(0.2, 0.4), st.integers(0, 9))
def test_lights_switched_off_are_unfamiliar_in_a_room_whose_own_frames_are_dark_below_a_bright_window(
    robocar_track, shared_data, factor, offset
):
    """The robocar's room has frames facing a sunset window (the floor dark, the window blown out): a mean brightness
    band holds darkened frames too. The light's shape does not: every grey level lower alike is no frame it learnt."""
    frames = _frames(shared_data / ROBOCAR, 1350 + offset, 2600, 25)
    lit = [robocar_track.familiarity(f)[0] for f in frames]
    dark = [robocar_track.familiarity((f.astype(np.float32) * factor).astype(np.uint8))[0] for f in frames]
    assert np.median(lit) >= 0.8
    assert np.mean(np.array(dark) < 0.8) >= 0.9 and np.median(dark) < 0.5, sorted(dark)


def test_a_dim_arena_learnt_stays_familiar_and_the_same_arena_darker_still_is_not(shared_data):
    """A dark carpet arena (mean grey ~55) is normal for the car that learnt it; the same frames at 0.3 are not."""
    track = learn_track([shared_data / TUB], LearnOptions(stop="1200f", every=2)).profile
    frames = _frames(shared_data / TUB, 1300, 2500, 40)
    lit = [track.familiarity(f)[0] for f in frames]
    dark = [track.familiarity((f.astype(np.float32) * 0.3).astype(np.uint8))[0] for f in frames]
    assert np.median(lit) >= 0.8
    assert np.mean(np.array(dark) < 0.5) >= 0.9, sorted(dark)


def test_the_tub_s_standing_frames_are_not_learnt(shared_data):
    learnt = learn_track([shared_data / TUB], LearnOptions(stop="400f"))
    assert learnt.frames_standing > 0 and learnt.profile.frames_learnt == learnt.frames_read - learnt.frames_standing


def test_the_supervisor_reads_the_track_and_without_one_the_cue_does_not_apply(robocar_track, shared_data):
    frame = _frames(shared_data / TUB, 300, 301, 1)[0]
    with_track = fg.FearGuard(lambda f: 0.0, track=robocar_track)
    cmd = with_track.step(fg.Observation(t_s=0.0, speed_mps=0.5, frame=frame))
    assert cmd.cues.familiarity < 0.5 and any("unlike the learnt track" in r for r in cmd.reasons)
    missing = with_track.step(fg.Observation(t_s=0.05, speed_mps=0.5, frame=None))
    assert math.isnan(missing.cues.familiarity)
    plain = fg.FearGuard(lambda f: 0.0).step(fg.Observation(t_s=0.0, speed_mps=0.5, frame=frame))
    assert plain.cues.familiarity == 1.0


def test_a_given_familiarity_counts_and_unknown_is_worst():
    rules = fg.load_rules()
    calm = dict(lane_confidence=1.0, brightness=120.0, occlusion=0.0, obstacle_range_m=math.inf, qr_staleness_s=0.0)
    assert rules.evaluate(fg.Cues(**calm)).fear == rules.evaluate(fg.Cues(**calm, familiarity=1.0)).fear
    low = rules.evaluate(fg.Cues(**calm, familiarity=0.0)).fear
    assert low >= rules.policy.caution_fear and rules.evaluate(fg.Cues(**calm, familiarity=math.nan)).fear == low
    five = np.array([[1.0, 120.0, 0.0, math.inf, 0.0]])
    assert rules.evaluate_batch(five)[0] == rules.evaluate_batch(np.hstack([five, [[1.0]]]))[0]
    assert rules.evaluate_batch(np.hstack([five, [[0.0]]]))[0] == pytest.approx(low)
    with pytest.raises(ValueError, match=r"\(N, 5\) or \(N, 6\)"):
        rules.evaluate_batch(np.zeros((2, 4)))


def _arrays(track: fg.TrackProfile, tmp_path: Path) -> dict[str, np.ndarray]:
    with np.load(save_track(track, tmp_path / "ok.npz")) as z:
        return {k: z[k] for k in z.files}


@pytest.mark.parametrize(("key", "value", "says"), [
    ("format", np.array("something-else"), "format"), ("version", np.array(99), "version"),
    ("version", np.array(1), "version"), ("bank", None, "bank"),
    ("mean", np.zeros(3), "mean"), ("calibration_distances", np.array([np.nan]), "calibration_distances"),
    ("brightness_band", np.array([200.0, 100.0]), "brightness_band"), ("basis", np.array(["a", "b"]), "basis"),
    ("light_levels", None, "light_levels"), ("light_levels", np.zeros((3, 3)), "light_levels"),
    ("light_levels", np.full((3, 4), 2.0), "light_levels"), ("light_calibration", np.array([-1.0]), "light_calibration"),
    ("light_calibration", np.zeros(0), "light_calibration"),
])
def test_a_wrong_profile_names_its_key(robocar_track, tmp_path, key, value, says):
    data = _arrays(robocar_track, tmp_path)
    if value is None:
        del data[key]
    else:
        data[key] = value
    path = tmp_path / "bad.npz"
    np.savez(path, **data)
    with pytest.raises(FileError, match=says) as err:
        load_track(path)
    assert str(path) in str(err.value)


def test_a_profile_learnt_before_the_light_reads_the_layout_alone(robocar_track, shared_data, tmp_path):
    data = {k: v for k, v in _arrays(robocar_track, tmp_path).items() if not k.startswith("light_")}
    old = profile_from_arrays(data, "old.npz")
    assert old.light is None
    back = load_track(save_track(robocar_track, tmp_path / "t.npz"))
    assert np.array_equal(back.light.levels, robocar_track.light.levels)
    assert np.array_equal(back.light.calibration, robocar_track.light.calibration)
    frame = _frames(shared_data / ROBOCAR, 1400, 1401, 1)[0]
    dark = (frame.astype(np.float32) * 0.3).astype(np.uint8)
    assert old.familiarity(dark)[0] == old.familiarity_of(old.distance(frame_features(dark)))
    fam, why = robocar_track.familiarity(dark)
    assert fam <= old.familiarity(dark)[0] and "the light is unlike the learnt light: darker" in why


@settings(max_examples=60, deadline=None)
@given(st.sampled_from(["light_levels", "light_calibration"]),
       st.one_of(st.integers(-3, 300).map(np.array), st.text(max_size=5).map(np.array),
                 st.lists(st.floats(allow_nan=True, allow_infinity=True), max_size=8).map(np.array),
                 st.lists(st.lists(st.floats(-1.0, 2.0), min_size=4, max_size=4), max_size=3).map(np.array)))
def test_hostile_light_arrays_are_a_profile_or_a_file_error(robocar_track, tmp_path_factory, key, value):
    data = _arrays(robocar_track, tmp_path_factory.mktemp("light"))
    data[key] = value
    try:
        track = profile_from_arrays(data, "hostile.npz")
    except FileError as err:
        assert key in str(err)
        return
    fam, _ = track.familiarity(np.full((120, 160, 3), 90, np.uint8))
    assert 0.0 <= fam <= 1.0


@settings(max_examples=60, deadline=None)
@given(st.binary(max_size=400))
def test_any_bytes_are_a_profile_or_a_file_error(tmp_path_factory, blob):
    path = tmp_path_factory.mktemp("fuzz") / "t.npz"
    path.write_bytes(blob)
    with pytest.raises(FileError):
        load_track(path)


@settings(max_examples=40, deadline=None)
@given(st.dictionaries(st.sampled_from(["format", "version", "mean", "weights", "basis", "bank", "calibration_distances",
                                        "brightness_band", "frames_learnt", "source"]),
                       st.one_of(st.integers(-3, 300).map(np.array), st.text(max_size=5).map(np.array),
                                 st.lists(st.floats(allow_nan=True), max_size=4).map(np.array)), max_size=10))
def test_hostile_arrays_are_a_file_error_never_a_crash(data):
    with pytest.raises(FileError):
        profile_from_arrays(data, "hostile.npz")


def test_frame_features_refuse_what_is_not_a_picture_and_take_any_picture():
    assert frame_features(None) is None and frame_features(np.zeros((0, 5, 3), np.uint8)) is None
    assert frame_features(np.array([["a"]], dtype=object)) is None and frame_features(np.zeros((4, 4, 7))) is None
    for img in (np.zeros((120, 160), np.uint8), np.full((480, 640, 4), 200, np.uint8), np.random.default_rng(3).random((9, 13, 3))):
        f = frame_features(img)
        assert f is not None and np.all(np.isfinite(f))


@pytest.mark.parametrize("horizontal", [True, False])
def test_motion_blur_lowers_the_detail_block_on_every_shared_source(shared_data, horizontal):
    """The detail block (the fine gradient, and its ratio to the shrunk picture's) falls as a motion blur grows, on a
    glossy mat (robocar), dark carpet (a Donkey tub) and a wooden floor (a 320×240 PiCar video), along or across."""
    frames = [cv2.imread(str(shared_data / ROBOCAR / "1400_cam_image_array_.jpg")),
              cv2.imread(str(shared_data / TUB / "images" / "1400_cam_image_array_.jpg")),
              _frames(shared_data / DEEPPICAR, 50, 51, 1)[0]]
    for img in frames:
        details = []
        for n in (1, 3, 7, 15):
            kernel = np.zeros((n, n), np.float32)
            if horizontal:
                kernel[n // 2, :] = 1.0 / n
            else:
                kernel[:, n // 2] = 1.0 / n
            f = frame_features(cv2.filter2D(img, -1, kernel))
            details.append((f[-2], f[-1]))
        assert all(a[0] > b[0] and a[1] > b[1] for a, b in itertools.pairwise(details)), details


def test_learn_and_replay_from_the_command_line(shared_data, tmp_path, capsys):
    out = tmp_path / "track.npz"
    assert main(["learn", str(shared_data / DEEPPICAR), "--to", "100f", "--out", str(out)]) == 0
    printed = capsys.readouterr().out
    assert "learnt 100 frames" in printed and "brightness band" in printed and "grey at the 10/50/90/99th percentiles" in printed
    assert out.is_file() and out.with_suffix(".png").is_file()
    assert cv2.imread(str(out.with_suffix(".png"))) is not None
    rp = tmp_path / "rp"
    assert main(["replay", str(shared_data / DEEPPICAR), "--from", "100f", "--to", "130f", "--track", str(out), "--out", str(rp),
                 "--no-plots"]) == 0
    import json

    rows = [json.loads(line) for line in (rp / "log.jsonl").read_text().splitlines()]
    assert len(rows) == 30 and all(0.0 <= r["familiarity"] <= 1.0 for r in rows)


def test_learn_says_what_is_wrong_with_exit_2(shared_data, tmp_path, capsys):
    assert main(["learn", str(shared_data / DEEPPICAR), "--to", "5f", "--out", str(tmp_path / "t.npz")]) == 2
    assert "at least 20" in capsys.readouterr().err
    bad = tmp_path / "bad.npz"
    bad.write_bytes(io.BytesIO(b"not a profile").getvalue())
    assert main(["replay", str(shared_data / DEEPPICAR), "--to", "3f", "--track", str(bad), "--out", str(tmp_path / "o")]) == 2
    assert "bad.npz" in capsys.readouterr().err


def test_a_scenario_run_with_another_track_s_profile_slows_and_says_why(shared_data, tmp_path, capsys):
    """The simulator's taped track is nothing like a PiCar's room: with that room's profile the guarded car is slower."""
    track = tmp_path / "room.npz"
    assert main(["learn", str(shared_data / DEEPPICAR), "--out", str(track)]) == 0
    runs = {}
    for name, extra in (("plain", []), ("room", ["--track", str(track)])):
        out = tmp_path / name
        main(["run", "clear_straight", "--out", str(out), *extra])
        import json

        rows = [json.loads(line) for line in (out / "log.jsonl").read_text().splitlines()]
        runs[name] = rows
    capsys.readouterr()
    fam = [r["familiarity"] for r in runs["room"] if r.get("familiarity") is not None]
    assert np.median(fam) < 0.5 and all(r.get("familiarity") in (1.0, None) for r in runs["plain"])
    speed = {k: np.mean([r["speed_limit_mps"] for r in v if r.get("speed_limit_mps") is not None]) for k, v in runs.items()}
    assert speed["room"] < speed["plain"]
    assert any("unlike the learnt track" in reason for r in runs["room"] for reason in r.get("reasons", []))


@pytest.mark.parametrize("lane_median", [None, 0.3])  # as learnt (never seen), and a lane seen partly
def test_verify_holds_for_a_supervisor_that_reads_a_track(robocar_track, tmp_path, capsys, lane_median):
    from dataclasses import replace

    track = robocar_track if lane_median is None else replace(robocar_track, lane_confidence_median=lane_median)
    path = save_track(track, tmp_path / "t.npz")
    code = main(["verify", "--track", str(path), "--examples", "5", "--only", "unknown_is_worst,monotone,reachable,repeated_frames",
                 "--out", str(tmp_path / "cx")])
    printed = capsys.readouterr().out
    assert code == 0, printed
    assert f"track {path}" in printed and "4 held, 0 failed" in printed


@pytest.mark.parametrize("lane_median", [None, 0.3])  # as learnt (never seen), and a lane seen partly
@settings(max_examples=80, deadline=None)
@given(st.tuples(st.integers(0, 40), st.integers(0, 40), st.sampled_from([None, 1, 2, 3, 4, 5])),
       st.sampled_from([np.uint8, np.uint16, np.float32, np.float64, np.int64, np.bool_]),
       st.sampled_from([0.0, 1.0, 255.0, 1e300, -5.0, math.nan, math.inf]))
def test_any_frame_with_a_track_is_an_answer_never_an_internal_error(robocar_track, lane_median, shape, dtype, fill):
    from dataclasses import replace

    h, w, c = shape
    dims = (h, w) if c is None else (h, w, c)
    with np.errstate(all="ignore"):
        frame = np.full(dims, fill).astype(dtype)
    track = robocar_track if lane_median is None else replace(robocar_track, lane_confidence_median=lane_median)
    guard = fg.FearGuard(lambda f: 0.0, track=track)
    for k in range(3):
        cmd = guard.step(fg.Observation(t_s=0.05 * k, speed_mps=0.5, frame=frame))
        assert not any("internal error" in r for r in cmd.reasons), cmd.reasons
        fam = cmd.cues.familiarity
        assert math.isnan(fam) or 0.0 <= fam <= 1.0


@settings(max_examples=200, deadline=None)
@given(st.floats(0.0, 1.0), st.floats(0.0, 1.0), st.floats(0.0, 1.0), st.floats(0.0, 0.5))
def test_occlusion_read_against_normal_driving_keeps_more_hidden_more_hidden(robocar_track, a, b, usual, calm):
    from dataclasses import replace

    track = replace(robocar_track, occlusion_usual=usual)
    lo, hi = track.occlusion_as_learnt(min(a, b), calm), track.occlusion_as_learnt(max(a, b), calm)
    assert 0.0 <= lo <= hi <= 1.0 and track.occlusion_as_learnt(1.0, calm) == pytest.approx(1.0)
    if usual <= calm:
        assert (lo, hi) == (min(a, b), max(a, b))  # calm recordings: the cue as measured
    else:
        assert track.occlusion_as_learnt(min(usual, 0.99), calm) <= calm + 1e-6  # normal driving reads calm; 1 stays 1


def test_where_the_lane_model_never_saw_the_track_familiarity_is_its_guidance(robocar_track, shared_data):
    from dataclasses import replace

    from fearguard.track.reading import read_as_learnt

    frame = _frames(shared_data / ROBOCAR, 1400, 1401, 1)[0]
    blind = replace(robocar_track, lane_confidence_median=0.0, occlusion_usual=1.0, floor=None)  # the floor: test_floor.py
    seen = replace(robocar_track, lane_confidence_median=0.8, occlusion_usual=0.6, floor=None)
    a = read_as_learnt(blind, frame, 0.0, 120.0, 1.0, (80.0, 180.0), 0.1)
    assert a.lane_confidence == a.familiarity and a.occlusion == 0.0 and any("did not see" in f for f in a.facts)
    b = read_as_learnt(seen, frame, 0.4, 120.0, 0.6, (80.0, 180.0), 0.1)
    assert b.lane_confidence == pytest.approx(0.5) and b.occlusion == pytest.approx(0.1)
    nan = read_as_learnt(blind, None, 0.0, 120.0, 1.0, (80.0, 180.0), 0.1)
    assert math.isnan(nan.familiarity) and math.isnan(nan.lane_confidence) and math.isnan(nan.occlusion)


@settings(max_examples=300, deadline=None)
@given(st.floats(1e-3, 0.499), st.floats(-0.1, 1.1), st.floats(-0.1, 1.1), st.floats(0.0, 1.0))
def test_a_partly_seen_lane_never_rises_as_the_lane_is_lost_and_never_reads_below_half(seen, a, b, fam):
    from fearguard.track.reading import PARTLY_SEEN, partly_seen_lane

    lo, hi = partly_seen_lane(seen, min(a, b), fam, []), partly_seen_lane(seen, max(a, b), fam, [])
    assert lo <= hi <= fam  # monotone in the lane's confidence, never above the familiarity
    assert lo >= min(fam, PARTLY_SEEN)  # a lost lane alone is evidence, not proof: at worst "medium"
    assert partly_seen_lane(seen, seen, fam, []) == fam  # at the recordings' median: only the familiarity speaks
    assert math.isnan(partly_seen_lane(seen, math.nan, fam, []))  # unknown lane: the worst
    assert math.isnan(partly_seen_lane(seen, 0.0, math.nan, []))  # unknown familiarity stays the worst
    assert partly_seen_lane(0.0, 0.0, fam, []) == fam  # a lane model that never saw the track tells nothing


def test_where_the_lane_model_saw_the_track_partly_losing_the_lane_lowers_the_cue_and_says_so(robocar_track, shared_data):
    from dataclasses import replace

    from fearguard.track.reading import PARTLY_SEEN, read_as_learnt

    frame = _frames(shared_data / ROBOCAR, 1400, 1401, 1)[0]
    partly = replace(robocar_track, lane_confidence_median=0.3, floor=None)
    lost = read_as_learnt(partly, frame, 0.0, 120.0, 1.0, (80.0, 180.0), 0.1)
    assert lost.lane_confidence == pytest.approx(min(lost.familiarity, PARTLY_SEEN)) and lost.occlusion == 0.0
    assert any("only partly" in f for f in lost.facts)
    assert any("reads no lower than" in f for f in lost.facts) == (lost.familiarity > PARTLY_SEEN)
    held = read_as_learnt(partly, frame, 0.3, 120.0, 1.0, (80.0, 180.0), 0.1)
    assert held.lane_confidence == held.familiarity and not any("reads no lower" in f for f in held.facts)
