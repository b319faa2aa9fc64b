"""Camera presets for the common cars: the datasheet field of view, a consistent size, usable by the pipeline."""

from __future__ import annotations

import math

import numpy as np
import pytest

import fearguard as fg
from fearguard.camera import CAMERA_PRESETS, camera_preset


def hfov_deg(cam: fg.CameraModel) -> float:
    return 2 * math.degrees(math.atan(cam.width_px / 2 / cam.fx_px))


@pytest.mark.parametrize("name", ["picam-v2-160x120", "picam-v2-320x240"])
def test_pi_camera_v2_presets_have_its_datasheet_field_of_view(name):
    cam = camera_preset(name)
    assert hfov_deg(cam) == pytest.approx(62.2, abs=0.2)  # Raspberry Pi Camera Module v2: 62.2° × 48.8°
    assert 2 * math.degrees(math.atan(cam.height_px / 2 / cam.fy_px)) == pytest.approx(48.8, abs=0.2)
    assert f"{cam.width_px}x{cam.height_px}" in name


def test_the_two_pi_camera_sizes_are_one_camera_scaled():
    assert camera_preset("picam-v2-320x240").scaled_to(160, 120) == camera_preset("picam-v2-160x120")


def test_the_wide_donkey_camera_is_wider_and_distorted():
    wide, pi = camera_preset("donkey-wide-160x120"), camera_preset("picam-v2-160x120")
    assert hfov_deg(wide) > hfov_deg(pi) + 20
    assert wide.distortion and wide.distortion[0] < 0  # barrel distortion


@pytest.mark.parametrize("name", sorted(CAMERA_PRESETS))
def test_every_preset_mounts_on_the_car_and_drives_the_pipeline(name):
    cam = camera_preset(name)
    assert cam.mount_height_m is not None and cam.pitch_deg > 0
    assert cam.ground_range_m(cam.height_px - 1) is not None
    frame = np.full((cam.height_px, cam.width_px, 3), 90, np.uint8)
    analysis = fg.analyze_frame(frame, camera=cam)
    assert 0.0 <= analysis.lane_confidence <= 1.0


def test_an_unknown_preset_lists_the_known_ones():
    with pytest.raises(ValueError, match="picam-v2-160x120"):
        camera_preset("picam-v7")
