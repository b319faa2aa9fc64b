"""The boundary tracks: a detection far from its track is a miss; only a persistent one moves the track."""

from __future__ import annotations

import copy

import numpy as np
from hypothesis import assume, given, settings
from hypothesis import strategies as st

from fearguard.vision.confidence import EVIDENCE_SPREAD
from fearguard.vision.lane_tracker import (
    LOST_AFTER_S,
    OWN_DIRECTION_SPAN,
    REINIT_AFTER,
    REINIT_SUPPORT_SHARE,
    SUPPORT_HOLD_S,
    BoundaryTrack,
    LaneTracker,
    seen_span,
)
from fearguard.vision.lanes import LaneLine, RoadRegion, SeenRows

WIDTH_PX = 320


def steady_track() -> BoundaryTrack:
    track = BoundaryTrack(WIDTH_PX)
    for k in range(10):
        track.predict(0.05)
        assert track.update(0.05 * k, np.array([150.0, -40.0]))
    return track


def test_outliers_scattered_over_the_image_never_move_the_track() -> None:
    track = steady_track()
    for k, z in enumerate([(190.0, 360.0), (240.0, 300.0), (65.0, 378.0), (200.0, 420.0), (90.0, 250.0)]):
        track.predict(0.05)
        assert not track.update(0.5 + 0.05 * k, np.array(z))  # a shadow edge, a far dash, ...: noise
    assert abs(float(track.kf.x[0]) - 150.0) < 5.0


def test_an_outlier_that_persists_reinitialises_the_track_there() -> None:
    track = steady_track()
    accepted = []
    for k in range(REINIT_AFTER):
        track.predict(0.05)
        accepted.append(track.update(0.5 + 0.05 * k, np.array([60.0 + k, 300.0 - k])))  # the lane really moved
    assert accepted == [False] * (REINIT_AFTER - 1) + [True]
    assert abs(float(track.kf.x[0]) - (60.0 + REINIT_AFTER - 1)) < 1e-6


# --- a detection is measured where it was seen (seen_span) ---------------------------------------------------------

REGION = RoadRegion(WIDTH_PX, 240, 68, 239, ((0, 239), (0, 68), (WIDTH_PX, 68), (WIDTH_PX, 239)))  # a model car's road rows


def _through(u_top: float, u_bottom: float, rows: SeenRows | None = None, region: RoadRegion = REGION) -> LaneLine:
    slope = (u_bottom - u_top) / (region.bottom_v_px - region.top_v_px)
    return LaneLine(slope, u_top - slope * region.top_v_px, 0.5, 1, rows)


def _tracked(u_top: float, u_bottom: float) -> BoundaryTrack:
    track = BoundaryTrack(WIDTH_PX)
    line = _through(u_top, u_bottom)
    for k in range(10):
        track.predict(0.05)
        z, h, _ = seen_span(line, REGION)
        assert track.update(0.05 * k, z, h)
    return track


@given(u_top=st.floats(100, 220), u_bottom=st.floats(-60, 380), rows=st.none() | st.builds(
    SeenRows, st.integers(2, 80), st.floats(REGION.top_v_px, REGION.bottom_v_px), st.floats(86, 300)))
def test_a_line_seen_over_the_region_is_measured_at_its_ends(u_top: float, u_bottom: float, rows: SeenRows | None) -> None:
    """Whole-region evidence (no rows known, or a spread reaching past both ends): the measurement is the line's ends."""
    z, h, span = seen_span(_through(u_top, u_bottom, rows), REGION)
    assert h is None and span == 1.0
    np.testing.assert_allclose(z, [u_top, u_bottom], atol=1e-9)


@given(top=st.integers(0, 300), height=st.integers(0, 3), mean=st.floats(-1e3, 1e3), std=st.floats(0.0, 1e3),
       slope=st.floats(-50.0, 50.0), intercept=st.floats(-1e3, 1e3))
def test_any_detection_gives_a_measurement_a_track_can_take(top: int, height: int, mean: float, std: float, slope: float,
                                                            intercept: float) -> None:
    """Whatever the region (even one or two rows high) and the rows a line was seen on, the measurement is finite, its
    matrix invertible, and a new track begins on it and judges the next one without an error."""
    region = RoadRegion(WIDTH_PX, top + height + 1, top, top + height, ((0, top + height), (0, top), (WIDTH_PX, top)))
    line = LaneLine(slope, intercept, 0.5, 1, SeenRows(5, mean, std))
    z, h, span = seen_span(line, region)
    assert np.all(np.isfinite(z)) and 0.0 <= span <= 1.0 + 1e-9
    assert h is None or abs(np.linalg.det(h)) > 1e-9
    track = BoundaryTrack(WIDTH_PX)
    assert track.update(0.0, z, h, span)
    track.predict(0.05)
    track.update(0.05, z, h, span)
    assert np.all(np.isfinite(track.kf.x))


@settings(max_examples=200)
@given(u_top=st.floats(120, 200), u_bottom=st.floats(-40, 360), tilt=st.floats(0.2, 0.6) | st.floats(-0.6, -0.2),
       mean=st.floats(110, 200), std=st.floats(11.0, 16.0))
def test_a_line_through_the_dashes_in_view_is_judged_where_they_are(u_top: float, u_bottom: float, tilt: float, mean: float,
                                                                    std: float) -> None:
    """A curved dashed boundary seen as a few dashes: the straight line through them meets the track where they are and
    swings far from it at the region's ends. It is evidence (accepted) and moves the track only where it was seen; the
    same line judged at its extrapolated ends was a miss. A line off the track where it was seen is a miss."""
    track = _tracked(u_top, u_bottom)
    tracked = _through(u_top, u_bottom)
    rows = SeenRows(6, mean, std)
    slope = tracked.slope + tilt  # the dashes' own direction: through the track at the mean row, far off at the ends
    dash = LaneLine(slope, tracked.u_at(mean) - slope * mean, 0.3, 1, rows)
    ends = np.array([dash.u_at(REGION.top_v_px), dash.u_at(REGION.bottom_v_px)])
    z, h, span = seen_span(dash, REGION)
    assume(span >= OWN_DIRECTION_SPAN)  # a line with a direction of its own ...
    assume(abs(tilt) * EVIDENCE_SPREAD * std <= 0.04 * WIDTH_PX)  # ... on the track over the span of its ridges ...
    old = copy.deepcopy(track)
    old.predict(0.05)
    assume(not old.update(0.5, ends))  # ... and far off where extrapolated: judged at its ends, an outlier
    track.predict(0.05)
    assert track.update(0.5, z, h, span)
    after = _through(float(track.kf.x[0]), float(track.kf.x[1]))
    assert abs(after.u_at(mean) - tracked.u_at(mean)) < 0.02 * WIDTH_PX  # where seen, it agreed: the track stays there
    off = LaneLine(slope, dash.intercept_px + 0.25 * WIDTH_PX, 0.3, 1, rows)
    z, h, span = seen_span(off, REGION)
    assert not track.update(0.55, z, h, span)  # a quarter of the width off where it was seen: a miss


@given(u_top=st.floats(120, 200), u_bottom=st.floats(-40, 360), offset=st.floats(-0.1, 0.1), mean=st.floats(70, 235),
       std=st.floats(0.0, 2.0), slope=st.floats(-4.0, 4.0))
def test_a_speck_is_evidence_where_the_track_is_but_neither_moves_it_nor_keeps_it(
        u_top: float, u_bottom: float, offset: float, mean: float, std: float, slope: float) -> None:
    """A line through one short dash or a speck (seen over a few rows) has no direction of its own: lying on the track
    within a dash period of the last line that had one, it is evidence (accepted); it never changes the track's
    geometry, and a track fed only by specks is dropped after LOST_AFTER_S (a speck of worn concrete kept the last
    line's track alive and it drifted onto the verge)."""
    track = _tracked(u_top, u_bottom)
    before = track.kf.x[:2].copy()
    tracked = _through(u_top, u_bottom)
    at = tracked.u_at(mean) + offset * WIDTH_PX * 0.1
    speck = LaneLine(slope, at - slope * mean, 0.05, 1, SeenRows(3, mean, std))
    z, h, span = seen_span(speck, REGION)
    assert span < OWN_DIRECTION_SPAN
    t = 0.45  # the last frame with a line of its own direction
    for k in range(round(LOST_AFTER_S / 0.05) - 1):
        t += 0.05
        track.predict(0.05)
        accepted = track.update(t, z, h, span)
        assert accepted or k >= round(SUPPORT_HOLD_S / 0.05)  # within a dash period of the last line: evidence
    np.testing.assert_allclose(track.kf.x[:2], before, atol=1e-6)  # steady track, no velocity: the geometry is kept
    track.predict(0.05)
    assert track.update(t + 0.1, z, h, span)  # nothing with a direction for LOST_AFTER_S: a new track begins on it
    assert not track.paired


def test_a_coasted_track_is_taken_up_again_only_by_the_whole_line() -> None:
    """Past a dash period without a line of its own direction, the track's gate has widened: a partial line that lies on
    it only where it was seen (worn concrete, a verge's edge) no longer takes it up; a line along the whole track does."""
    partial = LaneLine(0.6, 0.0, 0.2, 1, SeenRows(20, 200.0, 6.0))  # through the track near row 200, 0.14 of the rows
    for gap_s, accepted in ((SUPPORT_HOLD_S - 0.05, True), (SUPPORT_HOLD_S + 0.1, False)):
        track = _tracked(150.0, 60.0)
        line = _through(150.0, 60.0)
        part = LaneLine(partial.slope, line.u_at(200.0) - partial.slope * 200.0, 0.2, 1, partial.rows)
        z, h, span = seen_span(part, REGION)
        assert span >= OWN_DIRECTION_SPAN
        steps = round(gap_s / 0.05)
        for k in range(steps - 1):
            track.predict(0.05)
            assert not track.update(0.45 + 0.05 * (k + 1), None)
        track.predict(0.05)
        assert track.update(0.45 + gap_s, z, h, span) is accepted
        whole = LaneLine(line.slope, line.intercept_px, 0.6, 1, SeenRows(60, 150.0, 50.0))
        z, h, span = seen_span(whole, REGION)
        track.predict(0.05)
        assert track.update(0.5 + gap_s, z, h, span)


@given(far=st.floats(0.15, 0.5), rows=st.floats(70, 235))
def test_specks_that_persist_never_move_a_track(far: float, rows: float) -> None:
    """A speck off the track, frame after frame at the same place, never re-initialises the track there (it cannot say
    where the line runs): the track keeps its line, however many frames in a row the speck persists."""
    track = _tracked(150.0, 60.0)
    before = track.kf.x[:2].copy()
    at = _through(150.0, 60.0).u_at(rows) + far * WIDTH_PX
    speck = LaneLine(3.0, at - 3.0 * rows, 0.05, 1, SeenRows(3, rows, 1.0))
    z, h, span = seen_span(speck, REGION)
    for k in range(3 * REINIT_AFTER):
        track.predict(0.05)
        track.update(0.5 + 0.05 * k, z, h, span)
    np.testing.assert_allclose(track.kf.x[:2], before, atol=1e-6)


def test_a_line_seen_on_one_row_is_measured_on_that_row_and_the_next() -> None:
    """A degenerate spread (every ridge on one row) gives no direction; the measurement is still two distinct rows."""
    z, h, span = seen_span(_through(150.0, 60.0, SeenRows(3, 150.0, 0.0)), REGION)
    assert np.linalg.matrix_rank(h) == 2 and np.all(np.isfinite(z)) and span < OWN_DIRECTION_SPAN


# --- a weaker line does not replace one seen well (REINIT_SUPPORT_SHARE) ------------------------------------------------


def _with_support(u_top: float, u_bottom: float, support: float) -> LaneLine:
    line = _through(u_top, u_bottom)
    return LaneLine(line.slope, line.intercept_px, support, 1)


@settings(max_examples=40, deadline=None)
@given(seen=st.floats(0.3, 1.0), share=st.floats(0.0, 0.98), jump=st.floats(30.0, 90.0), side=st.sampled_from([0, 1]))
def test_a_weaker_line_that_persists_does_not_replace_a_line_seen_well(seen: float, share: float, jump: float, side: int) -> None:
    """The grass edge beside a dashed line in a bend (support 0.15 where the dashes had 0.63), found three frames running
    half a second after the dashes: not the line; the track stays where the dashes were. A line as well supported as
    the track's recent best re-initialises it there (the lane really moved)."""
    weaker = share * REINIT_SUPPORT_SHARE
    for support, moves in ((seen * weaker, False), (seen * REINIT_SUPPORT_SHARE * 1.01, True)):
        tracker = LaneTracker()
        good = _with_support(150.0, -40.0, seen), _with_support(170.0, 360.0, seen)
        for k in range(10):
            tracker.update(0.05 * k, REGION, *good)
        ends = (150.0 + jump, -40.0 + 3 * jump) if side == 0 else (170.0 + jump, 360.0 + 3 * jump)
        moved = _with_support(*ends, support)
        for k in range(REINIT_AFTER):
            tracked = tracker.update(0.5 + 0.05 * k, REGION, moved if side == 0 else None, moved if side == 1 else None)
        line = (tracked.left, tracked.right)[side]
        was = good[side]
        assert line is not None
        assert (abs(line.u_at(REGION.bottom_v_px) - was.u_at(REGION.bottom_v_px)) > 2 * jump) is moves
