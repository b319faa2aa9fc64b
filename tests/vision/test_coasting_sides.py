"""Which boundaries steer when one side is missed this frame (vision/frame.py ``coasting_sides``).

A side missed this frame coasts on its track (the aim point stays steady through a dash gap) only if that track was once
a side of the lane seen well (``paired``): a track begun on a stray ridge — glare's speckle at support 0.05, grass at the
verge — would hold the aim point half way to it. Detections are never dropped, whatever their tracks.
"""

from __future__ import annotations

from hypothesis import given
from hypothesis import strategies as st

from fearguard.vision.frame import coasting_sides
from fearguard.vision.lane_tracker import LaneTracker, TrackedLanes
from fearguard.vision.lanes import LaneLine, road_region

REGION = road_region(320, 240)
PERIOD_S = 0.05


def line(u_bottom: float, slope: float, support: float) -> LaneLine:
    return LaneLine(slope, u_bottom - slope * REGION.bottom_v_px, support, 3)


LEFT, RIGHT = line(60.0, -0.9, 0.9), line(260.0, 0.9, 0.9)
TRACK_L, TRACK_R = line(62.0, -0.9, 0.0), line(258.0, 0.9, 0.0)

maybe_line = st.sampled_from([None, LEFT])
maybe_right = st.sampled_from([None, RIGHT])
maybe_track_l = st.sampled_from([None, TRACK_L])
maybe_track_r = st.sampled_from([None, TRACK_R])


def tracked(left: LaneLine | None, right: LaneLine | None, paired: tuple[bool, bool]) -> TrackedLanes:
    return TrackedLanes(left, right, False, False, left, right, 0.0, 0.0, paired)


@given(maybe_line, maybe_right, maybe_track_l, maybe_track_r, st.booleans(), st.booleans())
def test_a_detection_always_steers_and_only_a_paired_track_coasts_beside_a_side_seen(
    det_l: LaneLine | None, det_r: LaneLine | None, track_l: LaneLine | None, track_r: LaneLine | None, paired_l: bool,
    paired_r: bool,
) -> None:
    out_l, out_r = coasting_sides(det_l, det_r, tracked(track_l, track_r, (paired_l, paired_r)))
    if det_l is not None:
        assert out_l is det_l
    if det_r is not None:
        assert out_r is det_r
    if det_l is None:  # coasting: the other side found this frame, a track there, and it was a side of the lane
        assert out_l is (track_l if det_r is not None and track_l is not None and paired_l else None)
    if det_r is None:
        assert out_r is (track_r if det_l is not None and track_r is not None and paired_r else None)


def test_a_lane_seen_well_coasts_through_a_gap_and_a_track_begun_on_a_stray_ridge_does_not() -> None:
    tracker = LaneTracker()
    for i in range(3):  # a lane seen well: both tracks become sides of it
        tracker.update(i * PERIOD_S, REGION, LEFT, RIGHT)
    gap = tracker.update(3 * PERIOD_S, REGION, LEFT, None)  # a dash gap on the right
    assert gap.paired == (True, True)
    assert coasting_sides(LEFT, None, gap)[1] is gap.right

    fresh = LaneTracker()
    for i in range(3):  # only the left line, and once a faint ridge far to the right (a new track there)
        fresh.update(i * PERIOD_S, REGION, LEFT, line(300.0, 0.4, 0.05) if i == 1 else None)
    stray = fresh.update(3 * PERIOD_S, REGION, LEFT, None)
    assert stray.right is not None and stray.paired == (False, False)
    assert coasting_sides(LEFT, None, stray) == (LEFT, None)  # the left line and the remembered width steer
