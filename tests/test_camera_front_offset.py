"""Ranges to what stands ahead are given from the car's front (``CameraModel.front_offset_m``), as a range sensor at the
bumper gives them and as the policy's stopping distances read them. MetaDrive's camera sits 1.46 m behind its car's
front bumper: its camera ranges read the gap plus that (a stopped car 5.0 m ahead at 8.4-9.2 m)."""

from __future__ import annotations

import math
from dataclasses import replace
from pathlib import Path

import pytest
from hypothesis import given
from hypothesis import strategies as st

from fearguard.camera import CameraModel, load_camera, save_camera
from fearguard.observation import LeadBox
from fearguard.vision.lead import lead_from_box
from fearguard.worlds.metadrive.preset import CAMERA_BEHIND_FRONT_M, CAR_LENGTH_M, metadrive_camera


def _camera(offset: float) -> CameraModel:
    return replace(CameraModel.default(320, 240, 60.0, mount_height_m=1.4, pitch_deg=4.0), front_offset_m=offset)


@given(offset=st.floats(0.0, 5.0), v=st.floats(0.0, 240.0))
def test_a_range_ahead_is_the_ground_range_less_the_offset_never_negative(offset: float, v: float) -> None:
    cam = _camera(offset)
    ground = cam.ground_range_m(v)
    ahead = cam.range_ahead_m(v)
    if ground is None:
        assert ahead is None
    else:
        assert ahead is not None and ahead == pytest.approx(max(0.0, ground - offset))


@given(offset=st.floats(0.0, 3.0), y=st.integers(130, 230), h=st.integers(5, 60))
def test_a_lead_is_nearer_by_the_offset_and_keeps_its_bearing(offset: float, y: int, h: int) -> None:
    box = LeadBox(140.0, float(y - h), 40.0, float(h))
    near, far = lead_from_box(box, _camera(offset)), lead_from_box(box, _camera(0.0))
    assert near.bearing_deg == far.bearing_deg
    assert far.range_m is not None and near.range_m == pytest.approx(max(0.0, far.range_m - offset))


@pytest.mark.parametrize("bad", [-0.1, math.nan, math.inf])
def test_a_negative_or_non_finite_offset_is_refused(bad: float) -> None:
    with pytest.raises(ValueError, match="front_offset_m"):
        replace(CameraModel.default(320, 240), front_offset_m=bad)


def test_camera_toml_keeps_the_offset(tmp_path: Path) -> None:
    cam = _camera(1.9)
    save_camera(cam, tmp_path / "camera.toml")
    assert load_camera(tmp_path / "camera.toml").front_offset_m == 1.9
    (tmp_path / "old.toml").write_text("[camera]\nwidth_px = 320\nheight_px = 240\nfx_px = 277.0\nfy_px = 277.0\n"
                                       "cx_px = 160.0\ncy_px = 120.0\n")
    assert load_camera(tmp_path / "old.toml").front_offset_m == 0.0  # a file from before: ranges from the lens, as then


def test_metadrive_camera_is_behind_the_bumper_by_half_the_car_less_its_mount() -> None:
    assert CAMERA_BEHIND_FRONT_M == pytest.approx(CAR_LENGTH_M / 2.0 - 0.8)
    assert metadrive_camera().front_offset_m == CAMERA_BEHIND_FRONT_M
    assert metadrive_camera().scaled_to(640, 480).front_offset_m == CAMERA_BEHIND_FRONT_M


@pytest.mark.parametrize(("name", "offset_m"), [("stationary_obstacle", 0.08), ("ccrm_road", 2.1)])
def test_the_simulators_camera_knows_how_far_behind_the_bumper_it_sits(name: str, offset_m: float) -> None:
    """fearguard's own simulator: length − rear overhang − the camera's place ahead of the rear axle."""
    from fearguard.sim.scenario import load_scenario
    from fearguard.sim.world import World

    sc = load_scenario(Path(__file__).resolve().parents[1] / "scenarios" / f"{name}.toml")
    v = sc.vehicle
    world = World(sc)
    assert world.camera.front_offset_m == pytest.approx(v.length_m - v.rear_overhang_m - sc.camera.forward_m)
    assert world.camera.front_offset_m == pytest.approx(offset_m, abs=0.01)
