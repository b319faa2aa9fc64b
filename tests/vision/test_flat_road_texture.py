"""A smooth patch is an object only on a road with texture to be smooth against (occlusion.RoadAppearance.textured).

Roughness is a ratio (mean neighbour difference over the grey level), so the same flat road reads rougher as the light
dims. MetaDrive's rendered road by night (grey ~49, a mean neighbour difference of 0.2 grey levels: quantisation) read as
textured, and every patch a little smoother than that noise became an object in the lane (43 of 300 frames of a night
drive, the car stopping for nothing). The texture must also stand above half a grey level.
"""

from __future__ import annotations

import numpy as np
from hypothesis import given
from hypothesis import strategies as st

from fearguard.vision.obstacle import foreign_mask
from fearguard.vision.occlusion import ROUGH_MIN, ROUGH_MIN_LEVELS, RoadAppearance, SurfaceMaps


@given(grey=st.floats(1.0, 255.0), levels=st.floats(0.0, 20.0), saturation=st.floats(0.0, 255.0))
def test_textured_needs_both_the_ratio_and_texture_in_grey_levels(grey: float, levels: float, saturation: float) -> None:
    road = RoadAppearance(grey, saturation, levels / grey)
    assert road.textured == (levels / grey >= ROUGH_MIN and levels >= ROUGH_MIN_LEVELS)


@given(levels=st.floats(0.0, ROUGH_MIN_LEVELS, exclude_max=True), grey=st.floats(1.0, 255.0))
def test_a_flat_road_is_not_textured_however_dark(levels: float, grey: float) -> None:
    assert not RoadAppearance(grey, 20.0, levels / grey).textured


def _maps(grey: float, roughness: np.ndarray) -> SurfaceMaps:
    h, w = roughness.shape
    return SurfaceMaps(0, np.full((h, w), grey, np.float32), np.full((h, w), 23.0, np.float32), roughness.astype(np.float32),
                       np.zeros((h, w), np.uint8), np.zeros((h + 1, w + 1)))


def _with_smooth_patch(road: RoadAppearance) -> np.ndarray:
    rough = np.full((40, 60), road.roughness)
    rough[20:30, 20:40] = 0.2 * road.roughness  # smoother than the road: an object, if the road has texture
    return rough


def test_on_a_dark_flat_road_a_smoother_patch_is_no_object() -> None:
    road = RoadAppearance(49.0, 23.0, 0.2 / 49.0)  # MetaDrive by night: 0.2 grey levels, ratio 0.004 (= ROUGH_MIN)
    assert road.roughness >= ROUGH_MIN
    assert not foreign_mask(_maps(49.0, _with_smooth_patch(road)), road).any()


def test_on_a_textured_road_a_smoother_patch_is_still_an_object() -> None:
    for grey, levels in ((49.0, 2.0), (130.0, 2.5), (75.0, 0.6)):  # dark carpet, a daylight road, a night road's tarmac
        road = RoadAppearance(grey, 23.0, levels / grey)
        mask = foreign_mask(_maps(grey, _with_smooth_patch(road)), road)
        assert mask[20:30, 20:40].all() and not mask[:20].any()
