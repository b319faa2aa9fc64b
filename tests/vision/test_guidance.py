"""A track guided by one line (a centre line, one edge) is seen when its best line is; two lines count both."""

from __future__ import annotations

import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from fearguard.lane import GUIDANCE
from fearguard.vision.confidence import lane_confidence
from fearguard.vision.frame import FramePipeline
from fearguard.vision.lanes import LaneLine, RoadRegion

REGION = RoadRegion(320, 240, 150, 225, ((0, 225), (120, 150), (200, 150), (319, 225)))
unit = st.floats(0.0, 1.0)


def _line(u_bottom: float, support: float) -> LaneLine:
    return LaneLine(slope=(u_bottom - 160.0) / 100.0, intercept_px=u_bottom - 225 * (u_bottom - 160.0) / 100.0, support=support,
                    segments=3)


@settings(max_examples=200, deadline=None, derandomize=True)
@given(sl=unit, sr=unit, ag=unit, occ=st.floats(0.0, 1.0), left=st.booleans(), right=st.booleans())
def test_one_line_counts_its_best_line_and_never_less_than_two(sl, sr, ag, occ, left, right):
    lines = (_line(40.0, sl) if left else None, _line(280.0, sr) if right else None)
    two = lane_confidence(*lines, REGION, ag, ag, occ)
    for guidance in GUIDANCE[1:]:
        one = lane_confidence(*lines, REGION, ag, ag, occ, guidance=guidance)
        best = max(sl if left else 0.0, sr if right else 0.0)
        assert one.confidence == pytest.approx(min(1.0, best * one.agreement * one.visibility))
        assert one.confidence >= two.confidence - 1e-12 and one.guidance == guidance and one.geometry == 1.0
        assert one.as_guidance("two_lines") <= one.confidence + 1e-12
    assert two.guidance == "two_lines" and two.as_guidance("two_lines") == pytest.approx(two.confidence)


def test_the_guidance_is_one_of_the_known_kinds():
    with pytest.raises(ValueError, match="guidance"):
        FramePipeline(guidance="three_lines")
    assert FramePipeline(guidance="one_edge").guidance == "one_edge"
