"""A dashed line's evidence over time (vision/lane_tracker.py, vision/confidence.py).

- An accepted detection's support is the best its track had over the last SUPPORT_HOLD_S: the dash between two others
  is no weaker evidence of the line than they were. A miss or a rejected outlier holds nothing, a new track holds
  nothing from before it, and in a noisy picture (night) nothing is held: there, a weaker line may be one the noise hid.
- A track is ``paired`` once it was accepted together with the other side as a lane seen well; a line alone guides a
  creep only if its track was (a verge's edge or a seam in worn concrete never was).
- A detection is compared with its track where its ridges lie: a line through one far dash is not judged by where it
  is extrapolated to.
"""

from __future__ import annotations

import math

import numpy as np
from hypothesis import given
from hypothesis import strategies as st

from fearguard.vision.confidence import SNR_ACCEPTABLE, agreement, lane_confidence
from fearguard.vision.lane_tracker import PAIRED_MIN_EVIDENCE, SUPPORT_HOLD_S, BoundaryTrack, LaneTracker
from fearguard.vision.lanes import LaneLine, SeenRows, road_region

REGION = road_region(320, 240)
PERIOD_S = 0.05


def line(u_bottom: float, slope: float, support: float, rows: SeenRows | None = None) -> LaneLine:
    return LaneLine(slope, u_bottom - slope * REGION.bottom_v_px, support, 3, rows)


def left(support: float) -> LaneLine:
    return line(60.0, -0.9, support)


def right(support: float) -> LaneLine:
    return line(260.0, 0.9, support)


@given(st.lists(st.floats(0.0, 1.0), min_size=1, max_size=60))
def test_the_held_support_is_the_best_of_the_window(supports: list[float]) -> None:
    track = BoundaryTrack(REGION.width_px)
    window = round(SUPPORT_HOLD_S / PERIOD_S)
    for i, s in enumerate(supports):
        held = track.held_support(i * PERIOD_S, s)
        recent = supports[max(0, i - window) : i + 1]
        assert held >= s
        assert math.isclose(held, max(recent))


def test_a_dashed_line_reads_steady_and_a_line_that_ends_fades_within_the_hold() -> None:
    tracker = LaneTracker()
    dashes = [0.8, 0.5, 0.2, 0.05, 0.6, 0.9, 0.4, 0.1, 0.7]  # a dash passing, the next coming
    held = [tracker.update(i * PERIOD_S, REGION, left(s), right(s)).left_support for i, s in enumerate(dashes)]
    assert min(held[1:]) >= 0.8 * 0.9 and held[3] >= 0.8  # the gap between two dashes holds the dash before it
    t = len(dashes) * PERIOD_S
    after = [tracker.update(t + i * PERIOD_S, REGION, None, None) for i in range(3)]
    assert all(a.left_support == 0.0 for a in after)  # nothing seen: nothing held


def test_a_new_track_holds_nothing_from_the_one_before() -> None:
    tracker = LaneTracker()
    for i in range(5):
        tracker.update(i * PERIOD_S, REGION, left(0.9), right(0.9))
    far = line(200.0, -0.2, 0.1)  # a different line, persisting until it re-initialises the track
    supports = [tracker.update((5 + i) * PERIOD_S, REGION, far, right(0.9)).left_support for i in range(4)]
    assert supports[-1] == 0.1 or supports[-1] == 0.0


def test_a_pair_seen_well_pairs_both_tracks_and_a_weak_pair_does_not() -> None:
    weak = LaneTracker()
    for i in range(5):
        out = weak.update(i * PERIOD_S, REGION, left(0.3), right(0.05))
    assert out.paired == (False, False)
    assert 0.5 * (0.3 + 0.05) < PAIRED_MIN_EVIDENCE
    lane = LaneTracker()
    lane.update(0.0, REGION, left(0.9), right(0.8))
    out = lane.update(PERIOD_S, REGION, left(0.9), None)
    assert out.paired == (True, True)


def test_a_lone_line_never_paired_guides_nothing_and_a_paired_one_does() -> None:
    alone = lane_confidence(left(0.6), None, REGION, paired=(False, False))
    paired = lane_confidence(left(0.6), None, REGION, paired=(True, False))
    assert alone.guide == 0.0
    assert math.isclose(paired.guide, 0.6)


@given(st.floats(0.0, 1.0), st.floats(0.0, 1.0), st.floats(0.0, 1.0), st.floats(0.0, 1.0), st.floats(0.0, 60.0))
def test_a_hold_only_ever_raises_a_present_line_and_never_the_guide(s_l: float, s_r: float, h_l: float, h_r: float, snr: float) -> None:
    base = lane_confidence(left(s_l), None, REGION, signal_to_noise=snr)
    held = lane_confidence(left(s_l), None, REGION, signal_to_noise=snr, held=(h_l, h_r))
    assert held.confidence >= base.confidence - 1e-12
    assert held.support_right == 0.0  # the right side was not seen: its track's memory adds nothing
    assert held.guide == base.guide  # the guide is what this frame shows
    if snr <= 0.5 * SNR_ACCEPTABLE:
        assert held.confidence == base.confidence  # a noisy picture: a weaker line may be one the noise hid


def test_a_far_dash_is_compared_with_its_track_where_it_lies() -> None:
    track = line(60.0, -0.9, 0.0)
    rows = SeenRows(12, REGION.top_v_px + 10.0, 3.5)  # one short dash near the top of the region
    v = rows.mean_v_px
    tilted = LaneLine(track.slope + 1.0, track.u_at(v) - (track.slope + 1.0) * v, 0.2, 2, rows)  # the same at the dash, fanning out below
    assert agreement(tilted, track, REGION, 150.0) > 0.8  # within the dash's span (mean ± 2 std) it is a few pixels off
    no_rows = LaneLine(tilted.slope, tilted.intercept_px, 0.2, 2, None)
    assert agreement(no_rows, track, REGION, 150.0) < 0.5


def test_seen_rows_of_a_set_of_rows() -> None:
    assert SeenRows.of(np.array([5])) is None
    r = SeenRows.of(np.array([10, 11, 12, 13]))
    assert r is not None and r.count == 4 and math.isclose(r.mean_v_px, 11.5) and math.isclose(r.std_v_px, np.std([10, 11, 12, 13]))
