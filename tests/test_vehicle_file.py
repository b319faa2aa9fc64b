"""vehicle.toml files: read by the one strict reader; every mistake names the file, the line and the key."""

from __future__ import annotations

from pathlib import Path

import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

import fearguard as fg
from fearguard.vehicle import PRESETS, VehicleFileError, load_vehicle


def write(tmp_path: Path, text: str) -> Path:
    path = tmp_path / "car.toml"
    path.write_text(text)
    return path


def test_a_file_starts_from_its_preset_and_overrides_keys(tmp_path) -> None:
    car = load_vehicle(write(tmp_path, 'preset = "road_car"\nmax_speed_mps = 25\nhas_qr_localisation = true\n'))
    assert car.max_speed_mps == 25.0 and car.has_qr_localisation
    assert car.ultrasonic_max_range_m == PRESETS["road_car"].ultrasonic_max_range_m


@pytest.mark.parametrize(("text", "says"), [
    ('preset = "road_car"\n# a comment\nstop_margin = 2.0\n',
     "line 3, key stop_margin: unknown key 'stop_margin' (did you mean 'stop_margin_m'?)"),
    ('max_speed_mps = "fast"\n', "line 1, key max_speed_mps: must be a finite number"),
    ('preset = "roadcar"\n', "line 1, key preset: must be one of"),
    ("has_ultrasonic = 1\n", "line 1, key has_ultrasonic: must be true or false"),
    ("max_decel_mps2 = 0.0\n", "VehicleLimits.max_decel_mps2 must be > 0"),
    ("max_speed_mps = = 2\n", "TOML syntax"),
    ("a = " + "[" * 200 + "]" * 200 + "\n", "nested deeper"),
])
def test_a_mistake_names_the_file_the_line_and_the_key(tmp_path, text, says) -> None:
    path = write(tmp_path, text)
    with pytest.raises(VehicleFileError) as err:
        load_vehicle(path)
    assert str(path) in str(err.value) and says in str(err.value)


@settings(max_examples=300, derandomize=True, deadline=None)
@given(st.text(max_size=200))
def test_any_text_is_a_vehicle_or_a_vehicle_file_error(tmp_path_factory, text) -> None:
    path = tmp_path_factory.mktemp("fuzz") / "car.toml"
    path.write_bytes(text.encode("utf-8", errors="replace"))
    try:
        assert isinstance(load_vehicle(path), fg.VehicleLimits)
    except VehicleFileError as exc:
        assert str(path) in str(exc)
