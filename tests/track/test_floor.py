"""The learnt floor (track/floor.py): what a wall, the edge of the course, a box or darkness hides of the floor the
recordings showed — on pictures of many floors, tapes and sizes, and on the shared recordings."""

from __future__ import annotations

import math
from dataclasses import replace
from pathlib import Path

import cv2
import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from fearguard.errors import FileError
from fearguard.track.floor import FLOOR_PX, SMOOTH_RATIO, as_occlusion, floor_view, learn_floor
from fearguard.track.learn import LearnOptions, learn_track
from fearguard.track.profile import load_track, profile_from_arrays, save_track
from fearguard.track.reading import floor_hidden, read_as_learnt

ROBOCAR = "modelcar/robocar-ucsd-window/images"

colour = st.tuples(st.integers(0, 255), st.integers(0, 255), st.integers(0, 255))
grainable = st.tuples(st.integers(30, 225), st.integers(30, 225), st.integers(30, 225))  # grain is not clipped at 0 or 255


def _course(rng: np.random.Generator, floor: tuple[int, int, int], tape: tuple[int, int, int], size: tuple[int, int],
            wall: tuple[int, int, int], horizon: float) -> np.ndarray:
    """A camera's view of a taped course: a wall above the horizon, a floor with sensor noise and light falling off
    with distance, two tape lines meeting toward the horizon that sway as the car turns."""
    w, h = size
    img = np.empty((h, w, 3), np.float64)
    img[:] = wall
    top = int(horizon * h)
    shade = np.linspace(0.85, 1.0, h - top)[:, None, None]
    img[top:] = np.asarray(floor, np.float64) * shade
    sway = rng.uniform(-0.15, 0.15) * w
    for side in (-1, 1):
        for v in range(top, h):
            k = (v - top) / max(h - top, 1)
            u = int(w / 2 + sway * (1 - k) + side * (0.05 + 0.4 * k) * w)
            half = max(1, int(0.02 * w * (0.3 + k)))
            img[v, max(0, u - half): max(0, min(w, u + half))] = tape
    img += rng.normal(0.0, 3.0, img.shape)
    return img.clip(0, 255).astype(np.uint8)


def _far_enough(a: tuple[int, int, int], b: tuple[int, int, int]) -> bool:
    return float(np.linalg.norm(np.subtract(a, b))) >= 80.0


@settings(max_examples=25, deadline=None)
@given(colour, colour, colour, st.sampled_from([(160, 120), (320, 240), (640, 360)]), st.floats(0.3, 0.5),
       st.integers(0, 2**16))
def test_a_wall_ahead_hides_the_floor_and_the_course_does_not(floor, tape, wall, size, horizon, seed):
    rng = np.random.default_rng(seed)
    if not (_far_enough(floor, wall) and _far_enough(floor, tape) and _far_enough(tape, wall)):
        return  # a wall the colour of the floor or of its tape (tape lies on the floor ahead of the nose) is not seen
    model = learn_floor([floor_view(_course(rng, floor, tape, size, wall, horizon)) for _ in range(30)])
    assert model is not None
    again = [model.hidden(_course(rng, floor, tape, size, wall, horizon)) for _ in range(5)]
    assert max(again) <= 0.2, again  # more of the same course: its floor is where it was
    h = size[1]
    facing = _course(rng, floor, tape, size, wall, horizon)
    facing[: int(0.9 * h)] = wall  # a wall close ahead: floor only just in front of the nose
    assert model.hidden(facing) >= 0.5
    dark = (_course(rng, floor, tape, size, wall, horizon) * 0.3).astype(np.uint8)
    dimmed = tuple(int(c * 0.3) for c in floor)  # darkened, the floor may look like its own tape: then it is still floor
    if _far_enough(dimmed, floor) and _far_enough(dimmed, tape):
        assert model.hidden(dark) >= 0.5


@settings(max_examples=300, deadline=None)
@given(st.floats(0.0, 1.0), st.floats(0.0, 1.0), st.one_of(st.floats(0.0, 1.0), st.just(math.nan)), st.floats(0.0, 0.5))
def test_more_floor_hidden_is_never_less_occlusion_and_the_typical_frame_is_calm(a, b, usual, calm):
    lo, hi = as_occlusion(min(a, b), usual, calm), as_occlusion(max(a, b), usual, calm)
    assert 0.0 <= lo <= hi <= 1.0
    assert as_occlusion(0.0, usual, calm) == 0.0 and as_occlusion(1.0, usual, calm) == pytest.approx(1.0)
    if math.isfinite(usual) and 1e-3 <= usual <= 1.0 - 1e-3:
        assert as_occlusion(usual, usual, calm) == pytest.approx(calm)
    assert math.isnan(as_occlusion(math.nan, usual, calm))


def _grained(rng: np.random.Generator, floor: tuple[int, int, int], size: tuple[int, int], grain: float, horizon: float,
             along: bool) -> np.ndarray:
    """A floor with grain of this strength (grey levels): speckle (carpet, concrete) or streaks along one direction (wood),
    under a plain wall above the horizon."""
    w, h = size
    if along:  # wood: streaks across the picture, a few pixels apart, of random strength
        streaks = rng.normal(0.0, grain, (h, 1)) * np.ones((1, w))
        texture = cv2.GaussianBlur(streaks + rng.normal(0.0, grain / 3, (h, w)), (1, 3), 0)
    else:
        texture = rng.normal(0.0, grain, (h, w))
    img = np.clip(np.array(floor, np.float64)[None, None, :] + texture[:, :, None], 0, 255)
    img[: int(horizon * h)] = (90, 90, 90)
    return img.astype(np.uint8)


@settings(max_examples=25, deadline=None)
@given(grainable, st.sampled_from([(160, 120), (320, 240), (640, 360)]), st.floats(6.0, 25.0), st.floats(0.25, 0.45),
       st.booleans(), st.integers(0, 2**16))
def test_a_flat_box_of_the_floors_own_colour_hides_the_floor_and_more_of_the_floor_does_not(floor, size, grain, horizon,
                                                                                             along, seed):
    """Issue 34's box over half the lane, the colour of the floor: an orange box on an orange wooden floor, a black one
    on dark concrete. Its colour matches; its missing grain does not."""
    rng = np.random.default_rng(seed)
    model = learn_floor([floor_view(_grained(rng, floor, size, grain, horizon, along)) for _ in range(20)])
    assert model is not None and model.texture_low is not None
    again = [model.hidden(_grained(rng, floor, size, grain, horizon, along)) for _ in range(5)]
    assert max(again) <= 0.2, again
    boxed = _grained(rng, floor, size, grain, horizon, along)
    w, h = size
    boxed[h // 2:, w // 4: 3 * w // 4] = floor
    box_share = 0.25 / (1.0 - horizon)  # of the floor in view: the box is a quarter of the picture
    assert model.hidden(boxed) >= max(0.7 * box_share, max(again) + 0.15)


def test_a_floor_that_was_smooth_asks_nothing_of_the_texture():
    rng = np.random.default_rng(3)
    plain = [_grained(rng, (60, 140, 200), (160, 120), 0.0, 0.4, False) for _ in range(10)]
    model = learn_floor([floor_view(f) for f in plain])
    assert model is not None and model.texture_low is not None and float(model.texture_low.max()) == 0.0
    assert model.hidden(plain[0]) <= 0.05
    assert learn_floor([floor_view(f) for f in plain], texture_percentile=None).texture_low is None
    assert 0.0 < SMOOTH_RATIO < 1.0


def test_too_little_to_learn_a_floor_from_is_no_model():
    assert learn_floor([]) is None and learn_floor([floor_view(np.zeros((120, 160, 3), np.uint8))]) is None


@pytest.fixture(scope="module")
def robocar(shared_data: Path):
    return learn_track([shared_data / ROBOCAR], LearnOptions(stop="1300f", every=2)).profile


def _frames(path: Path, start: int, stop: int, every: int) -> list[np.ndarray]:
    from fearguard.replay.recordings import open_recording

    return [f.image_bgr for f in open_recording(path).iter_frames(start, stop, every)]


def test_on_a_real_track_a_box_over_the_lane_hides_the_floor_later_laps_do_not(robocar, shared_data):
    floor = robocar.floor
    assert floor is not None and 0.0 <= floor.hidden_usual <= 0.5
    later = _frames(shared_data / ROBOCAR, 1350, 2550, 40)
    plain = np.array([floor.hidden(f) for f in later])
    assert np.median(plain) <= 2 * floor.hidden_usual + 0.05
    # not white: this glossy mat shows the window's white light as floor, and a white box on it is floor to the model
    for i, box in enumerate(((40, 160, 220), (30, 30, 200), (200, 90, 30), (20, 20, 20))):
        boxed = []
        for f in later[i::5]:
            f = f.copy()
            h, w = f.shape[:2]
            f[h // 2:, w // 4: 3 * w // 4] = box
            boxed.append(floor.hidden(f))
        assert np.median(boxed) > np.median(plain) + 0.1, (box, boxed)


def test_on_a_real_wooden_floor_a_box_of_its_own_colour_is_seen_by_its_missing_grain(shared_data):
    """deeppicar-tape: blue tape on an orange wooden floor. An orange box over half the lane matches the floor's colour
    (by colour alone it hides less than the plain frames do); the wood's grain is what it lacks."""
    video = shared_data / "modelcar/deeppicar-tape/video01.avi"
    floor = learn_floor([floor_view(f) for f in _frames(video, 0, 111, 1)])
    assert floor is not None and floor.texture_low is not None
    later = _frames(video, 111, 222, 5)
    plain = float(np.median([floor.hidden(f) for f in later]))
    boxed = []
    for f in later:
        f = f.copy()
        h, w = f.shape[:2]
        f[h // 2:, w // 4: 3 * w // 4] = (40, 160, 220)
        boxed.append(f)
    assert np.median([floor.hidden(f) for f in boxed]) >= plain + 0.3
    colour_alone = replace(floor, texture_low=None)
    assert np.median([colour_alone.hidden(f) for f in boxed]) <= plain + 0.05  # what the grain adds


def test_the_floor_raises_the_occlusion_never_lowers_it_and_unknown_stays_worst(robocar, shared_data):
    frame = _frames(shared_data / ROBOCAR, 1400, 1401, 1)[0]
    wall = frame.copy()
    wall[: int(0.85 * wall.shape[0])] = (40, 160, 220)
    facts: list[str] = []
    for occ in (0.0, 0.3, 1.0):
        assert floor_hidden(robocar, frame, occ, 0.1, facts) >= occ
        assert floor_hidden(robocar, wall, occ, 0.1, facts) >= max(occ, 0.5)
    assert any("floor" in f for f in facts)
    assert math.isnan(floor_hidden(robocar, frame, math.nan, 0.1, []))
    assert math.isnan(floor_hidden(robocar, None, 0.0, 0.1, []))
    blind = replace(robocar, lane_confidence_median=0.0)
    a = read_as_learnt(blind, wall, 0.0, 120.0, 1.0, (80.0, 180.0), 0.1)
    assert a.occlusion >= 0.5 and any("floor" in f for f in a.facts)
    assert read_as_learnt(replace(blind, floor=None), wall, 0.0, 120.0, 1.0, (80.0, 180.0), 0.1).occlusion == 0.0


def test_the_floor_survives_its_file_and_old_profiles_load_without_one(robocar, tmp_path):
    back = load_track(save_track(robocar, tmp_path / "t.npz"))
    assert back.floor is not None and robocar.floor is not None
    assert np.array_equal(back.floor.usual, robocar.floor.usual) and back.floor.radius_lab == robocar.floor.radius_lab
    assert back.floor.hidden_usual == robocar.floor.hidden_usual
    assert back.floor.texture_low is not None and robocar.floor.texture_low is not None
    assert np.array_equal(back.floor.texture_low, robocar.floor.texture_low)
    with np.load(tmp_path / "t.npz") as z:
        data = {k: z[k] for k in z.files if not k.startswith("floor_")}
        before_texture = {k: z[k] for k in z.files if k != "floor_texture_low"}
    assert profile_from_arrays(data, "old.npz").floor is None
    older = profile_from_arrays(before_texture, "older.npz").floor  # learnt before the texture test: colour alone
    assert older is not None and older.texture_low is None


@pytest.mark.parametrize(("key", "value"), [
    ("floor_usual", np.zeros((3, 3))), ("floor_usual", np.full((FLOOR_PX[1], FLOOR_PX[0]), 2.0)),
    ("floor_radius_lab", np.array(0.0)), ("floor_hidden_usual", np.array(1.5)), ("floor_colours_lab", np.zeros((0, 3))),
    ("floor_colours_lab", np.full((2, 3), np.nan)), ("floor_radius_lab", None),
    ("floor_texture_low", np.zeros((3, 3))), ("floor_texture_low", np.full((FLOOR_PX[1], FLOOR_PX[0]), -1.0)),
    ("floor_texture_low", np.full((FLOOR_PX[1], FLOOR_PX[0]), np.inf)),
])
def test_a_wrong_floor_names_its_key(robocar, tmp_path, key, value):
    with np.load(save_track(robocar, tmp_path / "ok.npz")) as z:
        data = {k: z[k] for k in z.files}
    if value is None:
        del data[key]
    else:
        data[key] = value
    with pytest.raises(FileError, match=key):
        profile_from_arrays(data, "bad.npz")


@settings(max_examples=120, deadline=None)
@given(st.dictionaries(st.sampled_from(["floor_colours_lab", "floor_radius_lab", "floor_usual", "floor_hidden_usual",
                                        "floor_texture_low"]),
                       st.one_of(st.none(), st.integers(-3, 300).map(np.array), st.text(max_size=5).map(np.array),
                                 st.lists(st.floats(allow_nan=True, allow_infinity=True), max_size=6).map(np.array),
                                 st.floats(-2.0, 300.0).map(lambda v: np.full((FLOOR_PX[1], FLOOR_PX[0]), v)),
                                 st.floats(-2.0, 300.0).map(lambda v: np.full((3, 3), v))), max_size=5))
def test_hostile_floor_arrays_in_a_good_profile_are_a_file_error_or_a_floor_never_a_crash(robocar, tmp_path_factory, changes):
    with np.load(save_track(robocar, tmp_path_factory.mktemp("floor") / "ok.npz")) as z:
        data = {k: z[k] for k in z.files}
    for key, value in changes.items():
        if value is None:
            data.pop(key, None)
        else:
            data[key] = value
    try:
        profile = profile_from_arrays(data, "hostile.npz")
    except FileError as err:
        assert "hostile.npz" in str(err)
        return
    if profile.floor is not None:  # accepted: then it reads any picture into a share 0..1
        share = profile.floor.hidden(np.zeros((120, 160, 3), np.uint8))
        assert 0.0 <= share <= 1.0
