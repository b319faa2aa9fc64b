"""The working-size reduction (``frame.reduce_to``): area averaging by halvings, within a grey level of INTER_AREA."""

from __future__ import annotations

from pathlib import Path

import cv2
import numpy as np
from hypothesis import given, settings
from hypothesis import strategies as st
from hypothesis.extra import numpy as hnp

from fearguard.vision.frame import reduce_to


@settings(max_examples=60, deadline=None)
@given(st.data(), st.sampled_from([1, 2, 4, 8, 3, 6, 12]), st.integers(1, 12), st.integers(1, 12), st.sampled_from([1, 3]))
def test_reduction_is_the_block_mean_within_one_grey_level(data, factor: int, w: int, h: int, channels: int) -> None:
    """Any whole factor (halvings, then the odd rest): the size asked, and each pixel within 1 of the exact block mean."""
    shape = (h * factor, w * factor) + ((channels,) if channels > 1 else ())
    image = data.draw(hnp.arrays(np.uint8, shape))
    out = reduce_to(image, w, h)
    assert out.shape[:2] == (h, w) and out.dtype == np.uint8
    blocks = image.reshape(h, factor, w, factor, -1).astype(float).mean(axis=(1, 3)).reshape(out.shape)
    assert np.abs(out - blocks).max() <= 1.0


@settings(max_examples=30, deadline=None)
@given(hnp.arrays(np.uint8, hnp.array_shapes(min_dims=3, max_dims=3, min_side=1, max_side=40).map(lambda s: (s[0], s[1], 3))),
       st.integers(1, 40), st.integers(1, 40))
def test_any_size_gets_the_size_asked(image: np.ndarray, w: int, h: int) -> None:
    out = reduce_to(image, w, h)
    assert out.shape == (h, w, 3)
    if image.shape[1] % (2 * w) or image.shape[0] % (2 * h):  # no halving possible: exactly OpenCV's INTER_AREA
        assert np.array_equal(out, cv2.resize(image, (w, h), interpolation=cv2.INTER_AREA))


def test_a_frame_at_its_working_size_is_returned_as_is() -> None:
    image = np.zeros((240, 320, 3), np.uint8)
    assert reduce_to(image, 320, 240) is image


def test_a_720p_dash_cam_frame_stays_within_a_grey_level_of_inter_area(shared_data: Path) -> None:
    """The replay's case (1280×720 → 320×180, two halvings): a quarter of a level brighter on average, never more than 1."""
    cap = cv2.VideoCapture(str(shared_data / "road" / "video" / "project_video.mp4"))
    ok, frame = cap.read()
    cap.release()
    assert ok and frame.shape == (720, 1280, 3)
    d = reduce_to(frame, 320, 180).astype(int) - cv2.resize(frame, (320, 180), interpolation=cv2.INTER_AREA)
    assert np.abs(d).max() <= 1
    assert 0.0 <= d.mean() <= 0.5


@settings(max_examples=60, deadline=None)
@given(st.data(), st.sampled_from([(1280, 720), (1920, 1080), (640, 480), (800, 600), (320, 240), (160, 120), (1000, 562)]),
       st.integers(0, 240), st.integers(0, 240), st.sampled_from([1, 3]))
def test_the_road_rows_alone_are_the_rows_of_the_whole_reduction(data, size: tuple[int, int], lo: int, hi: int,
                                                                  channels: int) -> None:
    """``reduce_rows``: the rows asked exactly as ``reduce_to`` gives them (a whole factor or not), every other row 0."""
    from fearguard.vision.frame import reduce_rows
    from fearguard.vision.lanes import work_size

    fw, fh = size
    ww, wh = work_size(fw, fh)
    image = data.draw(hnp.arrays(np.uint8, (fh, fw) + ((channels,) if channels > 1 else ()), elements=st.integers(0, 255)))
    rows = slice(min(lo, hi), max(lo, hi))
    out = reduce_rows(image, ww, wh, rows)
    whole = reduce_to(image, ww, wh)
    assert out.shape == whole.shape and out.dtype == np.uint8
    inside = np.zeros(wh, bool)
    inside[rows] = True
    assert np.array_equal(out[inside], whole[inside])
    assert not out[~inside].any()


def test_the_road_rows_of_noise_and_of_a_dash_cam_frame_match_the_whole_reduction(shared_data: Path) -> None:
    """Every pixel different (seeded noise) and the replay's own frame: no row of the band is off by a pixel."""
    from fearguard.vision.frame import reduce_rows

    cap = cv2.VideoCapture(str(shared_data / "road" / "video" / "project_video.mp4"))
    ok, frame = cap.read()
    cap.release()
    assert ok
    rng = np.random.default_rng(0)
    for image, (ww, wh), rows in [(frame, (320, 180), slice(111, 168)),
                                  (rng.integers(0, 256, (1080, 1920, 3), np.uint8), (320, 180), slice(99, 171)),
                                  (rng.integers(0, 256, (600, 800, 3), np.uint8), (320, 240), slice(140, 223))]:
        out = reduce_rows(image, ww, wh, rows)
        assert np.array_equal(out[rows], reduce_to(image, ww, wh)[rows])
        assert not out[: rows.start].any() and not out[rows.stop :].any()
