"""White paint in glare is paint: over a road lifted so bright by glare's veil that no ratio fits under the clip, a
line that reaches the clip (exposure.SATURATED_MIN) counts; below the clip the ratio still guards.

The bundled ``glare_zone_clear`` (and issue 35's held-back glare zone) lifts the asphalt to ~225-235 and clips the
paint at 255: a ratio of 1.09-1.13, under both the marking pixels' 1.15 (lanes.RIDGE_RATIO) and the ridge scan's
1.12 (ridges.CONTRAST_RATIO), although the line is plain to the eye. On seeds 24, 28 and 37 the car stood for good
1.1-1.7 m into the glare, the range clear. Synthetic roads of several brightnesses, positions and seeds here.
"""

from __future__ import annotations

import numpy as np
from hypothesis import given, settings
from hypothesis import strategies as st
from tests.vision.test_yellow_in_the_dark import _left_found, road

from fearguard.vision import ridges
from fearguard.vision.exposure import SATURATED_MIN
from fearguard.vision.lanes import RIDGE_MIN

H, W = 40, 320
ROWS = np.arange(H)


def _stripe_scan(road_grey: int, paint_grey: int, noise: int, seed: int) -> ridges.RidgeScan:
    """The ridge scan of a 4 px stripe of ``paint_grey`` on a road of ``road_grey`` (± noise), for a right boundary."""
    rng = np.random.default_rng(seed)
    light = np.clip(np.full((H, W), road_grey, np.int16) + rng.integers(-noise, noise + 1, (H, W)), 0, 255)
    light[:, 100:104] = paint_grey
    light = light.astype(np.uint8)
    feat = np.zeros((H, W), np.uint8)
    feat[:, 100:104] = 255
    maps = ridges.ridge_maps((light, np.full((H, W), 10, np.uint8)), feat, 0, H - 1)
    return ridges.scan_ridges(maps, ROWS, np.full((1, H), 102.0), np.full(H, 100.0), np.array([True]))


@settings(max_examples=30, deadline=None)
@given(road_grey=st.integers(int(255 / ridges.CONTRAST_RATIO) + 1, SATURATED_MIN - 12), seed=st.integers(0, 2**16))
def test_a_clipped_stripe_on_a_road_too_bright_for_the_ratio_is_a_ridge(road_grey: int, seed: int) -> None:
    """No paint this close to the clip can pass the ratio (255 < 1.12 × the road): clipped, it is a ridge."""
    scan = _stripe_scan(road_grey, 255, 2, seed)
    assert scan.ok.all() and scan.support[0] == 1.0


@settings(max_examples=30, deadline=None)
@given(road_grey=st.integers(150, 235), lift=st.floats(0.02, 0.1), seed=st.integers(0, 2**16))
def test_below_the_clip_the_ratio_still_guards(road_grey: int, lift: float, seed: int) -> None:
    """A stripe a few per cent lighter than the road that does not reach the clip (a worn seam, a sheen) is no ridge."""
    paint = min(SATURATED_MIN - 1, int(road_grey * (1.0 + lift)))
    assert not _stripe_scan(road_grey, paint, 0, seed).ok.any()


@settings(max_examples=12, deadline=None)
@given(asphalt=st.integers(int(255 / ridges.CONTRAST_RATIO) + 1, SATURATED_MIN - RIDGE_MIN - 4),
       seed=st.integers(0, 2**16), shift=st.integers(-15, 15))
def test_a_white_line_in_glare_is_the_left_boundary(asphalt: int, seed: int, shift: int) -> None:
    """Asphalt lifted to 228-232 by glare (no white fits the ratios above it), the lines clipped white: the solid left line
    is found on (almost) every row."""
    grey = (asphalt, asphalt - 2, asphalt - 1)
    white = (255, 255, 255)
    found, _ = _left_found([road(grey, white, white, seed + i, shift) for i in range(4)])
    assert found, asphalt


@settings(max_examples=10, deadline=None)
@given(asphalt=st.integers(200, SATURATED_MIN - RIDGE_MIN - 4), seed=st.integers(0, 2**16))
def test_a_pale_line_that_does_not_reach_the_clip_on_bright_asphalt_is_not_paint(asphalt: int, seed: int) -> None:
    """The same picture with the line 8 % lighter than the asphalt and short of the clip: no boundary (a sheen)."""
    line = min(SATURATED_MIN - 2, int(asphalt * 1.08))
    grey = (asphalt, asphalt - 2, asphalt - 1)
    found, _ = _left_found([road(grey, (line,) * 3, (255, 255, 255), seed + i) for i in range(4)])
    assert not found


@settings(max_examples=20, deadline=None)
@given(flank_sat=st.integers(int(255 / ridges.CONTRAST_RATIO) + 1, 245), light=st.integers(60, 200))
def test_a_saturation_at_its_ceiling_is_no_clipped_paint(flank_sat: int, light: int) -> None:
    """Glare lifts lightness, not saturation: a stripe of saturation 255 beside saturation too high for the ratio, as
    light as its flanks (an orange mat's edge in sunset light), is no ridge."""
    lightness = np.full((H, W), light, np.uint8)
    sat = np.full((H, W), flank_sat, np.uint8)
    sat[:, 100:104] = 255
    feat = np.zeros((H, W), np.uint8)
    feat[:, 100:104] = 255
    maps = ridges.ridge_maps((lightness, sat), feat, 0, H - 1)
    scan = ridges.scan_ridges(maps, ROWS, np.full((1, H), 102.0), np.full(H, 100.0), np.array([True]))
    assert not scan.ok.any()
