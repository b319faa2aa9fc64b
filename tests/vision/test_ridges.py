"""The ridge scan (vision/ridges.py): which run of marking pixels a candidate boundary finds, and its inner edge."""

from __future__ import annotations

import numpy as np
from hypothesis import given, settings
from hypothesis import strategies as st
from hypothesis.extra.numpy import arrays

from fearguard.vision import ridges

H, W = 40, 320
ROWS = np.arange(H)


def _maps(stripes: list[tuple[int, int]], road: int = 60, paint: int = 200) -> ridges.RidgeMaps:
    """A plain road with vertical paint stripes [start, end) on every row; the marking mask is the paint."""
    light = np.full((H, W), road, np.uint8)
    for a, b in stripes:
        light[:, a:b] = paint
    sat = np.full((H, W), 10, np.uint8)
    return ridges.ridge_maps((light, sat), (light == paint).astype(np.uint8) * 255, 0, H - 1)


def _scan(maps: ridges.RidgeMaps, centre: float, right_boundary: bool) -> ridges.RidgeScan:
    return ridges.scan_ridges(maps, ROWS, np.full((1, H), centre), np.full(H, 100.0), np.array([right_boundary]))


def test_a_stripe_near_the_candidate_is_found_and_its_inner_edge_reported() -> None:
    maps = _maps([(100, 104)])
    for centre in (102.0, 96.0, 108.0):  # on it, or within the search distance either side
        right = _scan(maps, centre, right_boundary=True)
        assert right.ok.all() and right.support[0] == 1.0
        assert (right.inner_u == 100).all()  # a right boundary's inner edge is the stripe's left edge
        left = _scan(maps, centre, right_boundary=False)
        assert (left.inner_u == 103).all()  # ... a left boundary's, its right edge
    far = _scan(maps, 130.0, right_boundary=True)
    assert not far.ok.any() and far.support[0] == 0.0


def test_between_two_stripes_at_the_same_distance_the_left_one_is_taken() -> None:
    maps = _maps([(90, 94), (109, 113)])  # paint ends at 93 and starts at 109: 8 px either side of 101
    assert (_scan(maps, 101.0, right_boundary=True).inner_u == 90).all()
    assert (_scan(maps, 102.0, right_boundary=True).inner_u == 109).all()  # nearer the right one


def test_paint_too_wide_for_the_lane_is_no_marking() -> None:
    assert not _scan(_maps([(100, 140)]), 120.0, right_boundary=True).ok.any()  # 40 px of a 100 px lane


def _long_runs_reference(ok: np.ndarray, min_rows: int) -> np.ndarray:
    out = np.zeros_like(ok)
    for i, row in enumerate(ok):
        j = 0
        while j < len(row):
            if not row[j]:
                j += 1
                continue
            end = j
            while end < len(row) and row[end]:
                end += 1
            if end - j >= min_rows:
                out[i, j:end] = True
            j = end
    return out


@settings(max_examples=200, deadline=None)
@given(arrays(bool, st.tuples(st.integers(1, 4), st.integers(0, 30))), st.integers(1, 5))
def test_only_runs_of_enough_consecutive_rows_are_kept(ok: np.ndarray, min_rows: int) -> None:
    assert np.array_equal(ridges._in_long_runs(ok, min_rows), _long_runs_reference(ok, min_rows))


@settings(max_examples=60, deadline=None)
@given(st.integers(8, 60), st.integers(20, 90), st.integers(0, 2**32 - 1), st.floats(0.0, 1.0))
def test_the_row_limited_top_hat_equals_the_full_one_on_its_rows(h: int, w: int, seed: int, share: float) -> None:
    """The top-hat is row by row: computed on a subset of rows (the yellow test's), those rows are the full image's."""
    from fearguard.vision.lanes import _ridges, road_region

    rng = np.random.default_rng(seed)
    channel = rng.integers(0, 256, (h, w), dtype=np.uint8)
    rows = np.flatnonzero(rng.random(h) < share)
    for region in (None, road_region(w, h)):
        full, part = _ridges(channel, region), _ridges(channel, region, rows)
        assert np.array_equal(part[rows], full[rows])
        assert not np.delete(part, rows, axis=0).any()


@settings(max_examples=100, deadline=None)
@given(arrays(bool, st.tuples(st.integers(1, 12), st.integers(1, 40))), st.integers(0, 2**32 - 1))
def test_the_run_through_a_marking_pixel_is_its_whole_run_of_the_row(feat: np.ndarray, seed: int) -> None:
    """``runs`` (a binary search in the row-offset gap counts built from the integral image) gives the first and last
    column of the consecutive marking pixels through each marking pixel, as a walk along the row does."""
    h, w = feat.shape
    maps = ridges.ridge_maps((np.zeros((h, w), np.uint8),), feat.astype(np.uint8) * 255, 0, h - 1)
    r, u = np.nonzero(feat)
    if len(r) == 0:
        return
    pick = np.random.default_rng(seed).permutation(len(r))
    r, u = r[pick], u[pick]
    start, end = maps.runs(r, u)
    for ri, ui, a, b in zip(r, u, start, end, strict=True):
        lo, hi = ui, ui
        while lo > 0 and feat[ri, lo - 1]:
            lo -= 1
        while hi < w - 1 and feat[ri, hi + 1]:
            hi += 1
        assert (a, b) == (lo, hi)
