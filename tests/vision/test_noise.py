"""The picture's noise: Immerkær's estimate reads the sensor noise, and a noisy picture supports the lane less.

What tells night (dark and noisy) from deep shade by day (dim, clean): the road region's S/N.
"""

from __future__ import annotations

import math
from pathlib import Path

import cv2
import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

import fearguard as fg
from fearguard.vision.confidence import NOISE_WEIGHT, SNR_ACCEPTABLE, lane_confidence
from fearguard.vision.exposure import Exposure, noise_grey, road_exposure
from fearguard.vision.lanes import LaneLine, road_region

FULL = np.full((120, 160), 255, np.uint8)


@pytest.mark.parametrize("sigma", [2.0, 5.0, 8.0, 15.0])
def test_the_estimate_reads_the_added_gaussian_noise_within_ten_percent(sigma: float) -> None:
    rng = np.random.default_rng(1)
    grey = np.clip(100.0 + rng.normal(0.0, sigma, FULL.shape), 0, 255).astype(np.uint8)
    assert noise_grey(grey, FULL) == pytest.approx(sigma, rel=0.1)


def test_a_clean_brightness_gradient_is_not_noise() -> None:
    ramp = np.tile(np.linspace(40, 200, 160), (120, 1)).astype(np.uint8)  # the kernel is blind to linear gradients
    assert noise_grey(ramp, FULL) < 0.3


def test_signal_to_noise_is_mean_over_sigma_inf_without_noise_and_nan_when_unknown() -> None:
    assert Exposure(50.0, 0.0, 0.0, 5.0).signal_to_noise == pytest.approx(10.0)
    assert Exposure(50.0, 0.0, 0.0, 0.0).signal_to_noise == math.inf
    assert math.isnan(Exposure(50.0, 0.0, 0.0).signal_to_noise)
    assert math.isnan(road_exposure(np.zeros((2, 2), np.uint8), np.full((2, 2), 255, np.uint8)).noise_grey)


LINE_L, LINE_R = LaneLine(-1.0, 200.0, 1.0, 4), LaneLine(1.0, 120.0, 1.0, 4)
REGION = road_region(320, 240)


@settings(max_examples=200, deadline=None)
@given(st.floats(0.0, 100.0), st.floats(0.0, 100.0))
def test_a_noisier_picture_never_raises_the_confidence(snr_a: float, snr_b: float) -> None:
    lo, hi = sorted((snr_a, snr_b))
    c_lo = lane_confidence(LINE_L, LINE_R, REGION, signal_to_noise=lo).confidence
    c_hi = lane_confidence(LINE_L, LINE_R, REGION, signal_to_noise=hi).confidence
    assert c_lo <= c_hi + 1e-12


@settings(max_examples=100, deadline=None)
@given(st.one_of(st.floats(0.0, 1e6), st.just(math.inf)))
def test_noise_costs_nothing_from_acceptable_on_and_at_most_half_below(snr: float) -> None:
    clean = lane_confidence(LINE_L, LINE_R, REGION).confidence
    c = lane_confidence(LINE_L, LINE_R, REGION, signal_to_noise=snr).confidence
    if snr >= SNR_ACCEPTABLE:
        assert c == clean
    assert c >= (1.0 - NOISE_WEIGHT) * clean - 1e-12


def test_unknown_noise_counts_as_pure_noise() -> None:
    clean = lane_confidence(LINE_L, LINE_R, REGION).confidence
    assert lane_confidence(LINE_L, LINE_R, REGION, signal_to_noise=math.nan).confidence == pytest.approx((1 - NOISE_WEIGHT) * clean)


def test_deep_shade_keeps_the_lane_but_the_same_dimness_with_night_noise_loses_some(shared_data: Path) -> None:
    """Every shared still dimmed to a road grey of about 45 (deep shade): visibility untouched by noise; the same
    with the simulator's night noise (σ 8 grey levels at the 320-px working size, where the lanes are read: noise added
    to a bigger frame is averaged away by the downscale): S/N below acceptable and a lower confidence on most stills."""
    rng = np.random.default_rng(3)
    lower = 0
    paths = sorted((shared_data / "road" / "images").glob("*.jpg"))
    for path in paths:
        img = cv2.imread(str(path))
        img = cv2.resize(img, (320, round(img.shape[0] * 320 / img.shape[1])), interpolation=cv2.INTER_AREA).astype(np.float32)
        gain = 45.0 / fg.analyze_frame(img.astype(np.uint8)).brightness  # road grey about 45: deep shade
        shade = np.clip(img * gain, 0, 255).astype(np.uint8)
        luminance_noise = rng.normal(0.0, 8.0, (*img.shape[:2], 1))  # grey-level noise, as the simulator's night
        night = np.clip(img * gain + luminance_noise, 0, 255).astype(np.uint8)
        a_shade, a_night = fg.analyze_frame(shade), fg.analyze_frame(night)
        assert a_shade.exposure.signal_to_noise >= SNR_ACCEPTABLE, path.name
        assert a_night.exposure.signal_to_noise < SNR_ACCEPTABLE, path.name
        assert a_night.evidence.visibility < a_shade.evidence.visibility, path.name
        lower += a_night.lane_confidence < a_shade.lane_confidence
    assert lower >= 0.8 * len(paths)


@settings(max_examples=60, deadline=None)
@given(st.integers(3, 40), st.integers(3, 40), st.integers(0, 2**32 - 1))
def test_the_filter_is_immerkaers_kernel_exactly(h: int, w: int, seed: int) -> None:
    grey = np.random.default_rng(seed).integers(0, 256, (h, w), dtype=np.uint8)
    kernel = np.array([[1, -2, 1], [-2, 4, -2], [1, -2, 1]], np.float32)  # N of the module docstring
    response = np.abs(cv2.filter2D(grey, cv2.CV_32F, kernel, borderType=cv2.BORDER_REPLICATE).astype(np.float64))
    expected = math.sqrt(math.pi / 2.0) * response.mean() / 6.0
    assert noise_grey(grey, np.full((h, w), 255, np.uint8)) == pytest.approx(expected, rel=1e-12, abs=1e-12)
