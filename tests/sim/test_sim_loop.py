"""Closed loop: every bundled scenario's expectations hold guarded (fast subset of seeds), baselines fail hazards,
the run is deterministic byte for byte, and the CLI writes what it promises."""

from __future__ import annotations

import json
from pathlib import Path

import pytest

from fearguard.cli import main
from fearguard.outputs.report import read_jsonl
from fearguard.sim.loop import run_scenario
from fearguard.sim.scenario import load_scenario
from fearguard.sim.suite import BENIGN, run_suite, scenario_files, suite_markdown

SCENARIOS = scenario_files()


def test_the_library_has_every_scenario_the_issue_asks_for():
    names = {p.stem for p in SCENARIOS}
    assert names >= {"clear_straight", "s_curves", "tunnel_exit_glare", "night", "tree_shadows", "occluding_traffic_follow_lead",
                     "unmarked_hill", "stationary_obstacle", "slower_lead", "lead_brakes_hard", "ccrs_road", "qr_markers_missing",
                     "ultrasonic_dropout", "camera_blackout", "steering_fault"}


@pytest.mark.slow
@pytest.mark.parametrize("path", SCENARIOS, ids=[p.stem for p in SCENARIOS])
def test_guarded_run_meets_every_expectation(path: Path):
    result = run_scenario(load_scenario(path))
    failed = [f"{e.name}: {e.detail}" for e in result.expectations if e.failed or e.ok is None]
    assert not failed, failed
    assert result.metrics.collisions == 0 and result.metrics.lane_departures == 0


@pytest.mark.slow
@pytest.mark.parametrize("name", ["stationary_obstacle", "occluding_traffic_follow_lead", "unmarked_hill"])
def test_the_unguarded_car_fails_the_hazard(name: str):
    result = run_scenario(load_scenario(Path(SCENARIOS[0]).parent / f"{name}.toml"), controller="unguarded")
    assert not result.passed
    assert result.metrics.collisions + result.metrics.lane_departures >= 1


@pytest.mark.slow
@pytest.mark.parametrize("name", BENIGN)
def test_benign_scenarios_no_false_alarm_and_at_least_95_percent_of_unguarded_speed(name: str):
    scenario = load_scenario(Path(SCENARIOS[0]).parent / f"{name}.toml")
    guarded, unguarded = run_scenario(scenario), run_scenario(scenario, controller="unguarded")
    assert guarded.metrics.emergency_entries == 0
    assert guarded.metrics.mean_speed_mps >= 0.95 * unguarded.metrics.mean_speed_mps


@pytest.mark.slow
def test_same_seed_same_log_byte_for_byte(tmp_path: Path):
    scenario = load_scenario(Path(SCENARIOS[0]).parent / "stationary_obstacle.toml")
    logs = []
    for k in range(2):
        run_scenario(scenario, seed=3, out_dir=tmp_path / f"run{k}")
        logs.append((tmp_path / f"run{k}" / "log.jsonl").read_bytes())
    assert logs[0] == logs[1] and len(logs[0]) > 1000
    run_scenario(scenario, seed=4, out_dir=tmp_path / "other")
    assert (tmp_path / "other" / "log.jsonl").read_bytes() != logs[0]


@pytest.mark.slow
def test_cli_run_writes_log_summary_plots_and_video(tmp_path: Path, capsys):
    out = tmp_path / "run"
    code = main(["run", str(Path(SCENARIOS[0]).parent / "stationary_obstacle.toml"), "--out", str(out), "--video"])
    assert code == 0, capsys.readouterr()
    records = read_jsonl(out / "log.jsonl")
    assert records and {"frame", "t_s", "lane_confidence", "fear", "fear_level", "mode", "strategy", "speed_limit_mps",
                        "steering_deg", "reasons"} <= set(records[0])
    summary = json.loads((out / "summary.json").read_text())
    assert summary["passed"] and summary["collisions"] == 0
    for name in ("timeline.png", "trajectory.png", "annotated.mp4"):
        assert (out / name).stat().st_size > 1000, name
    assert "stopped_before_obstacle" in capsys.readouterr().out


def test_cli_run_exit_1_when_an_expectation_fails_and_2_on_a_bad_file(tmp_path: Path, capsys):
    code = main(["run", str(Path(SCENARIOS[0]).parent / "stationary_obstacle.toml"), "--unguarded", "--out", str(tmp_path / "u")])
    assert code == 1
    bad = tmp_path / "bad.toml"
    bad.write_text("name = 'x'\nduration_s = 'long'\n")
    assert main(["run", str(bad), "--out", str(tmp_path / "b")]) == 2
    assert str(bad) in capsys.readouterr().err


@pytest.mark.slow
def test_suite_table_compares_guarded_with_baselines(tmp_path: Path):
    rows = run_suite([Path(SCENARIOS[0]).parent / "stationary_obstacle.toml"], seeds=1).rows
    assert {r["controller"] for r in rows} == {"guarded", "unguarded", "crisp", "aeb"}
    table = suite_markdown(rows)
    assert "| stationary_obstacle |" in table and "unguarded" in table.splitlines()[0]
    by = {r["controller"]: r for r in rows}
    assert by["guarded"]["not_applicable"] == [] and by["guarded"]["supervisor_checks"]
    for baseline in ("unguarded", "crisp", "aeb"):  # the mode checks are n/a for a baseline, not failures
        assert by[baseline]["not_applicable"] == by["guarded"]["supervisor_checks"]
        assert by[baseline]["supervisor_failed"] == [] and "mode_by" not in " ".join(by[baseline]["failed"])
    assert "| unguarded | 1 | 1 | 1 |" in table  # totals: one run, one outcome failure, one collision
    assert "supervisor-only checks (guarded; n/a for baselines)" in table
