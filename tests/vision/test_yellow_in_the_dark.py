"""A yellow line in the dark is paint: as strongly coloured as yellow paint at the lightness floor (lanes.YELLOW_LIGHT_MIN)
it counts, however dark; a dark pixel whose hue is only noise does not.

MetaDrive by night renders its yellow centre line at lightness ~55 (saturation 255, chroma 110) on asphalt at ~46: below
the old floor of 70 the line was not paint, the lane model took the oncoming carriageway's dashes for the left boundary
and steered the car over the centre line (20 s of 30 unguarded). Synthetic roads of several darknesses and yellows here.
"""

from __future__ import annotations

import cv2
import numpy as np
from hypothesis import given, settings
from hypothesis import strategies as st

from fearguard.vision.frame import FramePipeline
from fearguard.vision.lanes import marking_features, region_mask, road_region, work_size

W, H = 320, 240


def _quad(img: np.ndarray, bottom: tuple[float, float], top: tuple[float, float], half_px: tuple[float, float], colour) -> None:
    (u0, v0), (u1, v1) = bottom, top
    pts = np.array([[u0 - half_px[0], v0], [u0 + half_px[0], v0], [u1 + half_px[1], v1], [u1 - half_px[1], v1]], np.int32)
    cv2.fillConvexPoly(img, pts, colour)


def road(asphalt: tuple[int, int, int], left: tuple[int, int, int], white: tuple[int, int, int], seed: int,
         shift_px: int = 0) -> np.ndarray:
    """A dash-cam picture of a straight lane: a solid line on the left in ``left``, white dashes on the right."""
    rng = np.random.default_rng(seed)
    img = np.zeros((H, W, 3), np.uint8)
    img[:] = (120, 90, 60)
    img[120:] = asphalt
    _quad(img, (70 + shift_px, 239), (155, 125), (6, 1), left)
    for k in range(6):
        t0, t1 = k / 6, k / 6 + 0.08
        a = (280 + shift_px + (168 - 280 - shift_px) * t0, 239 - 114 * t0)
        b = (280 + shift_px + (168 - 280 - shift_px) * t1, 239 - 114 * t1)
        _quad(img, a, b, (6 * (1 - t0), 6 * (1 - t1)), white)
    noise = rng.integers(-2, 3, img.shape)
    return np.clip(img.astype(np.int16) + noise, 0, 255).astype(np.uint8)


def _left_found(frames: list[np.ndarray]) -> tuple[bool, float]:
    p = FramePipeline(None, 20.0)
    a = None
    for i, f in enumerate(frames):
        a = p.process(f, i / 20.0)
    assert a is not None
    return a.left is not None and a.left.support >= 0.8, a.lane_confidence


def _yellow(lightness: float, hue_deg: float) -> tuple[int, int, int]:
    """A fully saturated yellow-to-amber BGR of this HLS lightness (hue in degrees, 40-60 is yellow paint's)."""
    hls = np.array([[[hue_deg / 2.0, lightness, 255]]], np.uint8)
    return tuple(int(x) for x in cv2.cvtColor(hls, cv2.COLOR_HLS2BGR)[0, 0])


@settings(max_examples=25, deadline=None)
@given(asphalt=st.integers(25, 60), lift=st.integers(3, 14), hue=st.floats(40.0, 60.0), seed=st.integers(0, 2**16),
       shift=st.integers(-15, 15))
def test_a_dark_yellow_line_is_the_left_boundary(asphalt: int, lift: int, hue: float, seed: int, shift: int) -> None:
    """A yellow line barely lighter than dark asphalt (3-14 grey levels: no bright ridge) is found by its colour."""
    yellow = _yellow(asphalt + lift, hue)
    grey = (asphalt, asphalt - 4, asphalt - 2)
    white = (asphalt + 60,) * 3
    found, conf = _left_found([road(grey, yellow, white, seed + i, shift) for i in range(4)])
    assert found and conf >= 0.8, (yellow, conf)


@settings(max_examples=15, deadline=None)
@given(asphalt=st.integers(25, 60), lift=st.integers(3, 10), seed=st.integers(0, 2**16))
def test_a_dark_grey_line_of_the_same_lightness_is_not_paint(asphalt: int, lift: int, seed: int) -> None:
    """The same line without colour (a tar seam, a crack): no bright ridge, no chroma: not a boundary."""
    line = (asphalt + lift, asphalt + lift - 2, asphalt + lift + 1)  # a faint hue, chroma 3
    grey = (asphalt, asphalt - 4, asphalt - 2)
    found, _ = _left_found([road(grey, line, (asphalt + 60,) * 3, seed + i) for i in range(4)])
    assert not found


@settings(max_examples=15, deadline=None)
@given(asphalt=st.integers(8, 60), seed=st.integers(0, 2**16))
def test_dark_noise_with_a_yellow_hue_is_not_paint(asphalt: int, seed: int) -> None:
    """Dark pixels whose hue is noise (HLS saturation high, chroma a few levels) give no marking pixels."""
    rng = np.random.default_rng(seed)
    img = np.full((H, W, 3), asphalt, np.int16)
    img[..., 0] -= rng.integers(0, 6, (H, W))  # less blue: yellowish hue, chroma ≤ 5
    img = np.clip(img, 0, 255).astype(np.uint8)
    hls = cv2.cvtColor(cv2.resize(img, work_size(W, H)), cv2.COLOR_BGR2HLS)
    region = road_region(*work_size(W, H))
    assert not marking_features(hls, region_mask(region), region).any()
