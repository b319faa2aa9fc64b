"""Scenario files: defaults per scale, errors that name the file, the line and the key path, the bundled library."""

from __future__ import annotations

import math
import shutil
import textwrap
from pathlib import Path

import pytest

import fearguard as fg
from fearguard.files.reader import TomlSource
from fearguard.sim.qr import payload, place_boards
from fearguard.sim.scenario import Scenario, ScenarioError, load_scenario

LIBRARY = Path(__file__).resolve().parents[2] / "src" / "fearguard" / "scenarios"
REQUIRED = {"clear_straight", "s_curves", "tunnel_exit_glare", "night", "tree_shadows", "occluding_traffic_follow_lead",
            "unmarked_hill", "stationary_obstacle", "slower_lead", "lead_brakes_hard", "ccrs_road", "qr_markers_missing",
            "ultrasonic_dropout", "camera_blackout", "steering_fault"}
ROAD = """
[[road.segments]]
kind = "straight"
length_m = 10.0
"""


def write(tmp_path: Path, text: str, name: str = "scn.toml") -> Path:
    path = tmp_path / name
    path.write_text(textwrap.dedent(text).lstrip())
    return path


def load(tmp_path: Path, text: str) -> Scenario:
    return load_scenario(write(tmp_path, text))


def error_of(tmp_path: Path, text: str) -> ScenarioError:
    path = write(tmp_path, text)
    with pytest.raises(ScenarioError) as info:
        load_scenario(path)
    assert str(path) in str(info.value)
    return info.value


# -- defaults ------------------------------------------------------------------------------------
def test_model_scale_defaults(tmp_path: Path) -> None:
    sc = load(tmp_path, ROAD)
    assert sc.scale == "model" and sc.name == "scn"
    assert (sc.camera.width_px, sc.camera.height_px, sc.camera.fps) == (320, 240, 20.0)
    assert sc.camera.mount_height_m == pytest.approx(0.15)
    assert 12.0 <= sc.camera.pitch_deg <= 15.0
    assert sc.dt_s == pytest.approx(0.05)
    assert sc.rules_path.name == "default.toml" and sc.rules_path.is_file()
    assert 0.03 <= sc.road.marking_width_m <= 0.05
    assert sc.road.length_m == pytest.approx(10.0)
    limits = sc.vehicle.limits
    assert isinstance(limits, fg.VehicleLimits)
    assert limits.has_ultrasonic and not limits.has_qr_localisation  # no boards in this scenario
    assert sc.vehicle.max_brake_mps2 >= sc.vehicle.max_decel_mps2
    assert sc.ego.speed_mps == sc.vehicle.cruise_speed_mps
    assert sc.sensors is not None and (sc.sensors.min_range_m, sc.sensors.max_range_m) == (0.15, 3.96)


def test_road_scale_defaults(tmp_path: Path) -> None:
    sc = load(tmp_path, 'scale = "road"\n' + ROAD)
    assert sc.camera.mount_height_m == pytest.approx(1.3)
    assert sc.road.lane_width_m == pytest.approx(3.5) and sc.road.marking_width_m == pytest.approx(0.15)
    assert sc.rules_path.name == "road_car.toml"
    assert sc.vehicle.length_m > 4.0


def test_qr_boards_make_the_car_localise_by_qr(tmp_path: Path) -> None:
    sc = load(tmp_path, ROAD + "[[qr_boards]]\nstart_m = 1.0\nspacing_m = 2.0\ncount = 3\nmissing = [1]\n")
    assert sc.vehicle.has_qr_localisation
    boards = place_boards(sc.qr_boards[0], sc.road)
    assert [b.index for b in boards] == [0, 2]
    assert boards[1].payload == "FG1;route=A;sector=2;pos_m=5.0"
    assert all(b.lateral_m < -sc.road.lane_width_m / 2 for b in boards)  # right side by default


def test_payload_format() -> None:
    assert payload("B2", 7, 12.345) == "FG1;route=B2;sector=7;pos_m=12.3"


def test_overrides_and_traffic_start_gap(tmp_path: Path) -> None:
    sc = load(tmp_path, """
        duration_s = 8.0
        [camera]
        pitch_deg = 12.0
        [vehicle]
        cruise_speed_mps = 1.0
        [road]
        lanes_left = 1
        [[road.segments]]
        kind = "arc"
        length_m = 3.0
        radius_m = 2.0
        turn = "left"
        right_marking = "dashed"
        [[vehicles]]
        lane = "left"
        start_gap_m = 1.0
        speed_profile = [[0.0, 1.0], [4.0, 0.5]]
        braking = [{ t_s = 5.0, decel_mps2 = 6.0 }]
        """)
    assert sc.camera.pitch_deg == 12.0 and sc.vehicle.cruise_speed_mps == 1.0
    seg = sc.road.segments[0]
    assert seg.curvature_per_m == pytest.approx(0.5) and seg.right.style == "dashed" and seg.left.style == "solid"
    car = sc.vehicles[0]
    front = sc.vehicle.length_m - sc.vehicle.rear_overhang_m
    assert car.start_s_m == pytest.approx(front + 1.0 + car.length_m / 2)
    assert car.braking[0].to_speed_mps == 0.0


# -- errors --------------------------------------------------------------------------------------
def test_unknown_top_level_key_names_line_and_suggests_the_fix(tmp_path: Path) -> None:
    err = error_of(tmp_path, 'name = "x"\ndurration_s = 5.0\n' + ROAD)
    assert err.where == "line 2, key durration_s"
    assert "did you mean 'duration_s'" in err.problem


def test_unknown_nested_key_names_the_full_key_path(tmp_path: Path) -> None:
    err = error_of(tmp_path, ROAD + """
        [[vehicles]]
        start_gap_m = 1.0
        speed_mps = 1.0

        [[vehicles]]
        start_gap_m = 3.0
        speed_mps = 1.0
        braking = [{ t_s = 2.0, decel_mps = 6.0 }]
        """)
    assert "vehicles[1].braking[0].decel_mps" in err.where
    assert "line 12" in err.where  # the line of the second vehicle's braking entry
    assert "decel_mps2" in err.problem


def test_wrong_type_names_key_and_expected_type(tmp_path: Path) -> None:
    err = error_of(tmp_path, '[[road.segments]]\nkind = "straight"\nlength_m = "ten"\n')
    assert err.where == "line 3, key road.segments[0].length_m"
    assert "finite number" in err.problem and "'ten'" in err.problem


def test_negative_deceleration_is_rejected_with_its_path(tmp_path: Path) -> None:
    err = error_of(tmp_path, ROAD + "[[vehicles]]\nstart_gap_m = 1.0\nspeed_mps = 1.0\nbraking = [{ t_s = 1.0, decel_mps2 = -6.0 }]\n")
    assert "vehicles[0].braking[0].decel_mps2" in err.where and "> 0" in err.problem


def test_missing_road(tmp_path: Path) -> None:
    err = error_of(tmp_path, 'name = "no road"\n')
    assert "road" in err.where and "[[road.segments]]" in err.problem


def test_road_without_segments(tmp_path: Path) -> None:
    err = error_of(tmp_path, "[road]\nlane_width_m = 0.5\n")
    assert "road.segments" in err.where


@pytest.mark.parametrize(("segment", "key", "words"), [
    ('kind = "curve"\nlength_m = 3.0', "kind", "'straight', 'arc'"),
    ('kind = "arc"\nlength_m = 3.0\nturn = "left"', "radius_m", "missing"),
    ('kind = "arc"\nlength_m = 3.0\nradius_m = 2.0', "turn", "missing"),
    ('kind = "straight"\nlength_m = 3.0\nradius_m = 2.0', "radius_m", "only arcs"),
    ('kind = "straight"\nlength_m = 0.0', "length_m", "> 0"),
    ('kind = "arc"\nlength_m = 3.0\nradius_m = 0.2\nturn = "right"', "radius_m", "too tight"),
    ('kind = "straight"\nlength_m = 3.0\nleft_marking = "dotted"', "left_marking", "'solid', 'dashed', 'none'"),
])
def test_bad_segment(tmp_path: Path, segment: str, key: str, words: str) -> None:
    err = error_of(tmp_path, "[[road.segments]]\n" + segment + "\n")
    assert err.where.endswith(f"key road.segments[0].{key}")
    assert err.where.startswith("line ")
    assert words in err.problem


@pytest.mark.parametrize(("extra", "where", "words"), [
    ('[[vehicles]]\nlane = "left"\nstart_gap_m = 1.0\nspeed_mps = 1.0', "vehicles[0].lane", "lanes_left"),
    ("[[vehicles]]\nspeed_mps = 1.0", "vehicles[0].start_gap_m", "exactly one"),
    ("[[vehicles]]\nstart_gap_m = 1.0\nspeed_profile = [[0.0, 1.0], [0.0, 2.0]]", "vehicles[0].speed_profile[1]", "increasing"),
    ("[faults.camera]\nblack = [[3.0, 2.0]]", "faults.camera.black[0]", "start < end"),
    ('[[faults.steering]]\nt_s = 1.0\nuntil_s = 2.0\nkind = "bias"', "faults.steering[0].value", "value"),
    ('[[faults.steering]]\nt_s = 1.0\nuntil_s = 2.0\nkind = "explode"', "faults.steering[0].kind", "'raise'"),
    ('[[lighting]]\nkind = "glare"\nfrom_m = 1.0', "lighting[0].to_m", "both"),
    ('[[lighting]]\nkind = "night"\nfrom_m = 1.0\nto_m = 2.0\nfrom_s = 0.0\nto_s = 1.0', "lighting[0].from_s", "not both"),
    ('[[lighting]]\nkind = "fog"', "lighting[0].kind", "'night'"),
    ("[[qr_boards]]\nstart_m = 1.0\nspacing_m = 2.0\ncount = 3\nmissing = [3]", "qr_boards[0].missing", "[0, 2]"),
    ('[[qr_boards]]\nstart_m = 1.0\nspacing_m = 2.0\ncount = 3\nroute = "a;b"', "qr_boards[0].route", "letters"),
    ('[[expect.mode_by]]\nt_s = 2.0\nmode = "PANIC"', "expect.mode_by[0].mode", "'EMERGENCY'"),
    ("[[expect.max_speed_between]]\nmax_speed_mps = 1.0\nt_s = 1.0", "expect.max_speed_between[0].t_s", "either"),
    ("[expect]\nno_collision = 1", "expect.no_collision", "true or false"),
    ("[vehicle]\nmax_brake_mps2 = 1.0", "vehicle.max_brake_mps2", "max_decel_mps2"),
    ("[sensors.ultrasonic]\nmax_range_m = 0.1", "sensors.ultrasonic.max_range_m", "min_range_m"),
])
def test_bad_values_name_their_key(tmp_path: Path, extra: str, where: str, words: str) -> None:
    err = error_of(tmp_path, ROAD + extra + "\n")
    assert err.where.endswith(f"key {where}"), err.where
    assert words in err.problem


@pytest.mark.parametrize(("value", "words"), [("nonexistent", "bundled"), ("rules/missing.toml", "does not exist")])
def test_bad_rules_reference(tmp_path: Path, value: str, words: str) -> None:
    err = error_of(tmp_path, f'rules = "{value}"\n' + ROAD)
    assert err.where == "line 1, key rules" and words in err.problem


def test_rules_path_is_relative_to_the_scenario(tmp_path: Path) -> None:
    (tmp_path / "rules").mkdir()
    shutil.copy(LIBRARY.parent / "rules" / "road_car.toml", tmp_path / "rules" / "mine.toml")
    sc = load(tmp_path, 'rules = "rules/mine.toml"\n' + ROAD)
    assert sc.rules_path == (tmp_path / "rules" / "mine.toml").resolve()


def test_syntax_error_and_missing_file(tmp_path: Path) -> None:
    err = error_of(tmp_path, "name = \n")
    assert err.where == "TOML syntax"
    with pytest.raises(ScenarioError, match="no such file"):
        load_scenario(tmp_path / "absent.toml")


def test_line_of_counts_array_of_tables_headers() -> None:
    src = TomlSource("x.toml", '[[vehicles]]\nlane = "ego"\n\n[[vehicles]]\nlane = "left"\nbraking = [{ t_s = 1 }]\n')
    assert src.line_of("vehicles[1].lane") == 5
    assert src.line_of("vehicles[0].lane") == 2
    assert src.line_of("vehicles[1].braking[0].t_s") == 6
    assert src.line_of("nothing_here") is None


# -- the library ---------------------------------------------------------------------------------
def test_library_has_every_required_scenario() -> None:
    assert REQUIRED <= {p.stem for p in LIBRARY.glob("*.toml")}


@pytest.mark.parametrize("path", sorted(LIBRARY.glob("*.toml")), ids=lambda p: p.stem)
def test_every_bundled_scenario_loads_with_expectations(path: Path) -> None:
    sc = load_scenario(path)
    assert sc.name == path.stem
    assert sc.description
    assert 8.0 <= sc.duration_s <= 45.0  # glare_zone_clear: 8 m crept at a model car's crawl speed takes 27 s
    assert sc.expectations.names(), "a library scenario must say what a safe run achieves"
    assert sc.expectations.no_collision is True
    assert math.isfinite(sc.road.length_m)
    # the route is long enough for the run at cruise speed
    assert sc.road.length_m >= 0.5 * sc.vehicle.cruise_speed_mps * sc.duration_s


def test_a_missing_key_points_at_its_table_not_at_a_namesake_elsewhere(tmp_path: Path) -> None:
    err = error_of(tmp_path, ROAD + "[[vehicles]]\nspeed_mps = 1.0\n\n[[obstacles]]\ns_m = 3.0\n\n"
                             "[[vehicles]]\nstart_gap_m = 2.0\nspeed_mps = 1.0\n")
    assert err.where == "line 4, key vehicles[0].start_gap_m"  # the [[vehicles]] header, not the second vehicle's start_gap_m


@pytest.mark.parametrize("path", sorted(LIBRARY.glob("*.toml")), ids=lambda p: p.stem)
def test_every_bundled_scenario_starts_in_a_sane_world(path: Path) -> None:
    from fearguard.sim.world import World

    sc = load_scenario(path)
    world = World(sc)
    tr = world.truth()
    assert tr.in_lane and not tr.collided and not tr.finished
    assert tr.gap_m > 0.5 * sc.vehicle.length_m  # nothing starts on the ego car's bumper
    for _ in range(5):
        sens = world.sense()
        assert sens.frame_bgr.shape == (sc.camera.height_px, sc.camera.width_px, 3)
        world.advance(0.0, sc.vehicle.cruise_speed_mps)
    assert not world.truth().collided
