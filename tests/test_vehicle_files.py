"""``--vehicle PRESET|FILE``: one resolver (fearguard.vehicle.resolve_vehicle) for the CLI and the testing kit."""

from __future__ import annotations

from pathlib import Path

import pytest

import fearguard as fg
from fearguard.testing.subject import resolve_vehicle as kit_resolve
from fearguard.vehicle import PRESETS, VehicleFileError, resolve_vehicle


def test_a_preset_name_a_value_and_none_resolve_without_a_file() -> None:
    assert resolve_vehicle("road_car") is PRESETS["road_car"] and resolve_vehicle("road_car").max_speed_mps == 30.0
    car = fg.VehicleLimits(max_speed_mps=1.0)
    assert resolve_vehicle(car) is car
    assert resolve_vehicle(None) == fg.VehicleLimits()


@pytest.mark.parametrize("text", [
    'preset = "road_car"\nmax_speed_mps = 25.0\n',  # top-level keys on a preset
    '[vehicle]\npreset = "road_car"\nmax_speed_mps = 25.0\n',  # a scenario's [vehicle] table layout
])
def test_a_vehicle_file_overrides_its_preset(tmp_path: Path, text: str) -> None:
    path = tmp_path / "car.toml"
    path.write_text(text)
    car = resolve_vehicle(str(path))
    assert car.max_speed_mps == 25.0 and car.max_decel_mps2 == PRESETS["road_car"].max_decel_mps2
    assert kit_resolve(path) == (car, str(path))  # the kit asks the same resolver and adds the name it prints


@pytest.mark.parametrize(("text", "says"), [
    ("max_sped_mps = 2.0\n", "key max_sped_mps: unknown key"),
    ("has_ultrasonic = 1\n", "key has_ultrasonic: must be true or false"),
    ("preset = 'tank'\n", "key preset: must be one of"),
    ("max_speed_mps = \n", "TOML"),
])
def test_a_bad_vehicle_file_names_the_file_and_the_key(tmp_path: Path, text: str, says: str) -> None:
    path = tmp_path / "bad.toml"
    path.write_text(text)
    with pytest.raises(VehicleFileError, match=str(path)) as exc:
        resolve_vehicle(str(path))
    assert says in str(exc.value)


def test_neither_a_preset_nor_a_file_lists_the_presets(tmp_path: Path) -> None:
    with pytest.raises(VehicleFileError, match="neither a preset \\(camera_only, donkey"):
        resolve_vehicle(str(tmp_path / "missing.toml"))
    assert kit_resolve("default") == (fg.VehicleLimits(), "default")
