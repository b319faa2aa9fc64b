"""``LaneEvidence.guide``: one boundary found in the frame steers a creep even when the picture as a whole is not trusted.

The confidence counts what the picture cannot show (clipped or hidden road, noise); the guide asks only whether a line was
found where the track expected it. Checked here on the factors (every mix); on rendered glare frames in tests/sim/test_glare_creep.py.
"""

from __future__ import annotations

import math

from hypothesis import given
from hypothesis import strategies as st

from fearguard.vision.confidence import lane_confidence
from fearguard.vision.lanes import LaneLine, road_region

REGION = road_region(320, 240)
unit = st.floats(0.0, 1.0)


def line(u_bottom: float, slope: float, support: float) -> LaneLine:
    return LaneLine(slope, u_bottom - slope * REGION.bottom_v_px, support, 3)


@given(unit, unit, unit, unit, unit, st.floats(0.0, 1.0), st.floats(0.0, 50.0), st.booleans(), st.booleans())
def test_the_guide_is_never_below_the_confidence_and_ignores_visibility(
    s_l: float, s_r: float, a_l: float, a_r: float, occ: float, clipped: float, snr: float, has_l: bool, has_r: bool,
) -> None:
    left = line(60.0, -0.9, s_l) if has_l else None
    right = line(260.0, 0.9, s_r) if has_r else None
    seen = lane_confidence(left, right, REGION, a_l, a_r, occ, clipped, snr)
    clean = lane_confidence(left, right, REGION, a_l, a_r)
    assert 0.0 <= seen.guide <= 1.0
    assert seen.guide >= seen.confidence - 1e-12
    assert seen.guide == clean.guide  # washed out, hidden or noisy: the line found still guides as much
    if not has_l and not has_r:
        assert seen.guide == 0.0


def test_one_clear_line_in_a_blown_out_picture_guides_though_the_confidence_is_near_zero() -> None:
    left = line(60.0, -0.9, 0.45)
    e = lane_confidence(left, None, REGION, 1.0, 1.0, occlusion=0.5, clipped_share=0.45)
    assert e.confidence < 0.05 and math.isclose(e.guide, 0.45)


def test_a_line_where_the_track_did_not_expect_it_guides_nothing() -> None:
    e = lane_confidence(line(60.0, -0.9, 0.9), None, REGION, agreement_left=0.0)
    assert e.guide == 0.0
