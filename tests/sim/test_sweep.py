"""``fearguard sweep``: dotted keys checked like the files, combinations × scenarios × seeds as plan rows that change the
rules and the vehicle of real closed-loop runs, the table, the safe combinations ranked, the Pareto front and its plot."""

from __future__ import annotations

import json
from pathlib import Path

import pytest

from fearguard.cli import main
from fearguard.drive.plan import RunSpec, run_row
from fearguard.errors import SweepError
from fearguard.sim.scenario import BUNDLED
from fearguard.sim.sweep import (
    Setting,
    combinations,
    label,
    merge,
    parse_setting,
    plan,
    ranked_safe,
    row_line,
    split,
    sweep_markdown,
    unguarded_totals,
)

BLACKOUT = BUNDLED / "camera_blackout.toml"  # the camera goes dark: EMERGENCY, held for hold_s after it comes back


@pytest.fixture(scope="module")
def short(tmp_path_factory: pytest.TempPathFactory) -> Path:
    """Two bundled scenarios cut to 1.5 s."""
    out = tmp_path_factory.mktemp("scenarios")
    for name in ("clear_straight", "stationary_obstacle"):
        lines = [ln for ln in (BUNDLED / f"{name}.toml").read_text().splitlines() if not ln.startswith("duration_s")]
        (out / f"{name}.toml").write_text("duration_s = 1.5\n" + "\n".join(lines) + "\n")
    return out


def test_a_setting_is_a_known_dotted_key_and_toml_values() -> None:
    assert parse_setting("policy.hold_s=1, 2,3.5") == Setting("policy.hold_s", (1, 2, 3.5))
    assert parse_setting("vehicle.has_ultrasonic=true,false").values == (True, False)
    assert parse_setting('vehicle.qr_route="campus"').values == ("campus",)


@pytest.mark.parametrize(("text", "says"), [
    ("policy.hold=1,2", "unknown key 'policy.hold' (did you mean 'policy.hold_s'?)"),
    ("vehicle.max_speed=2", "did you mean 'vehicle.max_speed_mps'?"),
    ("polcy.hold_s=1", "did you mean 'policy.hold_s'?"),
    ("policy.hold_s", "write KEY=V1,V2"),
    ("=1", "write KEY=V1,V2"),
    ("policy.hold_s=1,,2", "an empty value between commas"),
    ("policy.hold_s=fast", "'fast' is not a value; give a number"),
    ("policy.hold_s=1,1", "a value is given twice"),
    ("policy.speed_fraction=0.5", "is not swept; write one rule file per variant"),
])
def test_a_bad_setting_says_how_to_fix_it(text: str, says: str) -> None:
    with pytest.raises(SweepError) as exc:
        parse_setting(text)
    assert says in str(exc.value)


def test_an_unknown_key_is_a_usage_error_at_parse_time(capsys) -> None:
    with pytest.raises(SystemExit) as exc:
        main(["sweep", "--set", "policy.hold=1,2"])
    err = capsys.readouterr().err.strip().splitlines()[-1]
    assert exc.value.code == 2 and "argument --set: " in err and "did you mean 'policy.hold_s'?" in err


@pytest.mark.parametrize(("text", "says"), [
    ("policy.emergency_exit_fear=0.9", "below emergency_enter_fear (hysteresis), got 0.9"),
    ("policy.enter_frames=2.5", "must be a whole number"),
    ("policy.hold_s=-1", "must be >= 0, got -1"),
    ("vehicle.max_speed_mps=0", "VehicleLimits.max_speed_mps must be > 0, got 0"),
    ("vehicle.has_ultrasonic=1", "VehicleLimits.has_ultrasonic must be true or false, got 1"),
])
def test_every_combination_is_checked_against_each_scenarios_files_before_anything_runs(text: str, says: str) -> None:
    with pytest.raises(SweepError) as exc:
        plan([BLACKOUT], 1, [parse_setting(text)])
    assert says in str(exc.value) and "camera_blackout" in str(exc.value)  # names the scenario whose files it breaks


def test_the_plan_runs_the_unguarded_car_once_and_every_combination_guarded(short: Path) -> None:
    settings = [parse_setting("policy.hold_s=1,2,3"), parse_setting("vehicle.max_speed_mps=1.5,2")]
    specs = plan(sorted(short.glob("*.toml")), 2, settings)
    assert len(specs) == 2 * 2 + 6 * 2 * 2 and len({s.key for s in specs}) == len(specs)
    assert [s.controller for s in specs[:4]] == ["unguarded"] * 4 and {s.controller for s in specs[4:]} == {"guarded"}
    first = specs[4]
    assert first.name == "clear_straight [policy.hold_s=1 vehicle.max_speed_mps=1.5]"
    assert first.options["policy"] == {"hold_s": 1} and first.options["vehicle"] == {"max_speed_mps": 1.5}
    assert RunSpec.from_json(json.loads(json.dumps(first.to_json()))) == first  # JSON-able: runs.jsonl, a worker elsewhere
    with pytest.raises(SweepError, match="given more than once"):
        combinations([parse_setting("policy.hold_s=1"), parse_setting("policy.hold_s=2")])
    with pytest.raises(ValueError, match="seeds must be"):
        plan([BLACKOUT], 0, settings)
    assert split({"policy.hold_s": 1, "vehicle.width_m": 0.2}) == {"policy": {"hold_s": 1}, "vehicle": {"width_m": 0.2}}
    assert label({"vehicle.has_ultrasonic": False, "vehicle.qr_route": "a", "policy.hold_s": 2.5}) == \
        'vehicle.has_ultrasonic=false vehicle.qr_route="a" policy.hold_s=2.5'


def test_a_row_runs_with_the_changed_rules_and_vehicle(tmp_path: Path) -> None:
    """camera_blackout cut to 10 s (black frames 4-5.5 s, frozen 8-9 s), seed 1: a longer hold keeps EMERGENCY longer; a
    lower speed cap drives less far. Same spec, same row."""
    cut = tmp_path / "camera_blackout.toml"
    cut.write_text(BLACKOUT.read_text().replace("duration_s = 14.0", "duration_s = 10.0"))

    def row(**options: object) -> dict:
        return run_row(RunSpec("sim", "camera_blackout [x]", "guarded", 1, {"file": str(cut), **options}))

    short_hold, long_hold = row(policy={"hold_s": 0.0}), row(policy={"hold_s": 4.0})
    assert long_hold["emergency_s"] > short_hold["emergency_s"] + 3.0
    slow = row(vehicle={"max_speed_mps": 0.5})
    assert slow["distance_m"] < short_hold["distance_m"] and row(vehicle={"max_speed_mps": 0.5}) == slow  # deterministic


def _row(scenario: str, seed: int, controller: str, distance: float, combination: str | None = None, **kw: object) -> dict:
    options = {"combination": combination, "policy": {"hold_s": 1}, "vehicle": {}} if combination else {}
    return {"spec": {"world": "sim", "name": scenario, "controller": controller, "seed": seed, "options": options},
            "scenario": scenario, "seed": seed, "controller": controller, "distance_m": distance, "collisions": 0,
            "lane_departures": 0, "emergency_s": 1.0, **kw}


def test_the_table_ranks_the_safe_combinations_and_marks_the_pareto_front() -> None:
    rows = [_row("a", 1, "unguarded", 10.0, collisions=1), _row("a", 2, "unguarded", 10.0),
            _row("a", 1, "guarded", 9.0, "A"), _row("a", 2, "guarded", 9.0, "A"),              # safe, 90 %
            _row("a", 1, "guarded", 8.0, "B"), _row("a", 2, "guarded", 8.0, "B"),              # safe, 80 %: dominated by A
            _row("a", 1, "guarded", 10.0, "C", collisions=1), _row("a", 2, "guarded", 10.0, "C"),  # 100 %, one collision
            _row("b", 1, "guarded", 5.0, "D", lane_departures=2)]                                # no unguarded twin
    table = {t["combination"]: t for t in merge(rows)}
    assert table["A"]["progress"] == pytest.approx(0.9) and table["A"]["safe"] and table["A"]["pareto"]
    assert not table["B"]["pareto"] and table["C"]["pareto"] and not table["C"]["safe"]
    assert table["D"]["progress"] is None and table["D"]["incidents"] == 2 and table["D"]["compared_runs"] == 0
    assert [t["combination"] for t in ranked_safe(list(table.values()))] == ["A", "B"]
    reference = unguarded_totals(rows)
    assert reference == {"runs": 2, "collisions": 1, "lane_departures": 0, "distance_m": 20.0}
    markdown = sweep_markdown(list(table.values()), reference)
    assert "| 1 | A | 90 % | 2.0 |" in markdown and "| D | 1 | 0 | 2 | – |" in markdown and "2 runs, 1 collisions" in markdown
    assert "none: every combination" in sweep_markdown([table["C"]], reference)
    assert row_line(rows[2]) == "a seed 1 guarded [A]: collisions 0, departures 0, 9.0 m"


@pytest.mark.slow
def test_the_sweep_command_on_two_dask_workers_gives_the_serial_table_and_a_plot(short: Path, tmp_path: Path, capsys,
                                                                                 dask_cluster) -> None:
    """``--scheduler``: the session's real scheduler and two workers (tests/conftest.py)."""
    argv = ["sweep", str(short), "--set", "policy.hold_s=1,3", "--set", "vehicle.max_speed_mps=1,2", "--seeds", "1"]
    assert main([*argv, "--out", str(tmp_path / "serial")]) == 0
    assert main([*argv, "--out", str(tmp_path / "dask"), "--scheduler", dask_cluster.address]) == 0
    out = capsys.readouterr().out
    serial, dask = (json.loads((tmp_path / name / "sweep.json").read_text()) for name in ("serial", "dask"))
    assert dask["combinations"] == serial["combinations"] and len(serial["combinations"]) == 4
    assert serial["finished_runs"] == 2 + 4 * 2 and serial["safe_ranked"][0].endswith("vehicle.max_speed_mps=2")
    assert (tmp_path / "dask" / "sweep.png").stat().st_size > 10_000 and "most progress first" in out
    assert main([*argv, "--out", str(tmp_path / "dask"), "--resume"]) == 0  # nothing left to run: the same table
    assert json.loads((tmp_path / "dask" / "sweep.json").read_text())["combinations"] == serial["combinations"]
