"""The command line fits a user's habits (issue 15 item 4): --version, bundled scenarios by name and listed,
--out optional (a timestamped folder under ./fearguard-out/, printed), replay with your steering function and
vehicle, warnings as one line, the suite's totals and its honest split of outcomes and supervisor checks."""

from __future__ import annotations

import json
import re
import sys
from pathlib import Path

import pytest

from fearguard.cli import main
from fearguard.errors import ScenarioError
from fearguard.sim.scenario import BUNDLED, find_scenario, load_scenario
from fearguard.sim.suite import scenario_files

VIDEO = "road/video/solidWhiteRight.mp4"
SHORT = "name = 'short'\nduration_s = 1.0\n[[road.segments]]\nkind = 'straight'\nlength_m = 40.0\n[expect]\nno_collision = true\n"


def test_version_prints_the_package_version(capsys) -> None:
    with pytest.raises(SystemExit) as exc:
        main(["--version"])
    assert exc.value.code == 0
    assert re.fullmatch(r"fearguard (\d+\.\d+\.\d+.*|\(not installed: run from a source tree\))\n", capsys.readouterr().out)


def test_scenarios_lists_every_bundled_one_with_its_description(capsys) -> None:
    assert main(["scenarios"]) == 0
    lines = capsys.readouterr().out.splitlines()
    assert len(lines) == len(scenario_files())
    for line, path in zip(lines, scenario_files(), strict=True):
        sc = load_scenario(path)
        assert line.split()[0] == sc.name and line.endswith(sc.description) and sc.description


def test_a_bundled_scenario_is_found_by_name_and_a_path_stays_a_path(tmp_path: Path, monkeypatch) -> None:
    monkeypatch.chdir(tmp_path)
    assert find_scenario("night") == BUNDLED / "night.toml"
    assert find_scenario("other/night.toml") == Path("other/night.toml")  # a path is never swapped for a bundled file
    (tmp_path / "night").write_text(SHORT)
    assert find_scenario("night") == Path("night")  # a file of that name in the working folder wins
    with pytest.raises(ScenarioError, match="no bundled scenario of that name; bundled: camera_blackout"):
        find_scenario("nigth")


def test_run_by_name_without_out_writes_a_timestamped_folder_and_says_where(tmp_path: Path, monkeypatch, capsys) -> None:
    monkeypatch.chdir(tmp_path)
    (tmp_path / "short.toml").write_text(SHORT)
    assert main(["run", "short.toml", "--baseline", "crisp"]) == 0
    out = capsys.readouterr().out
    folders = list((tmp_path / "fearguard-out").iterdir())
    assert len(folders) == 1 and re.fullmatch(r"run-short-crisp-\d{8}-\d{6}", folders[0].name)
    assert f"wrote fearguard-out/{folders[0].name}/log.jsonl, summary.json, trajectory.png" in out
    assert "timeline.png" not in out  # a baseline has no supervisor timeline, and the line does not claim one
    assert main(["run", "short.toml", "--baseline", "crisp"]) == 0  # the same second: a second folder, not the same one
    assert len(list((tmp_path / "fearguard-out").iterdir())) == 2


def test_a_baseline_run_shows_supervisor_checks_as_not_applicable(tmp_path: Path, capsys) -> None:
    scenario = tmp_path / "modes.toml"
    scenario.write_text(SHORT + "[[expect.mode_by]]\nt_s = 0.5\nmode = 'EMERGENCY'\n")
    assert main(["run", str(scenario), "--baseline", "crisp", "--out", str(tmp_path / "o")]) == 0  # n/a is not a failure
    out = capsys.readouterr().out
    assert "  n/a  mode_by EMERGENCY by 0.5 s: n/a: judges the supervisor's mode" in out and "unguarded run" not in out
    summary = json.loads((tmp_path / "o" / "summary.json").read_text())
    na = "n/a: judges the supervisor's mode, and this controller has none (a baseline)"
    assert summary["passed"] and {"name": "mode_by EMERGENCY by 0.5 s", "ok": None, "detail": na} in summary["expectations"]


def test_replay_wraps_your_steering_function_and_vehicle(shared_data: Path, tmp_path: Path, monkeypatch, capsys) -> None:
    (tmp_path / "my_pilot_for_replay.py").write_text("def steer(frame):\n    return 2.5\n")
    monkeypatch.chdir(tmp_path)
    monkeypatch.setattr(sys, "path", [str(tmp_path), *sys.path])
    code = main(["replay", str(shared_data / VIDEO), "--to", "3s", "--every", "2", "--no-plots", "--steer", "my_pilot_for_replay:steer",
                 "--vehicle", "road_car", "--rules", str(BUNDLED.parent / "rules" / "road_car.toml")])
    assert code == 0
    out = capsys.readouterr().out
    folder = next((tmp_path / "fearguard-out").iterdir())
    assert folder.name.startswith("replay-solidWhiteRight-") and f"wrote fearguard-out/{folder.name}/log.jsonl" in out
    records = [json.loads(line) for line in (folder / "log.jsonl").read_text().splitlines()]
    assert {r["steering_deg"] for r in records} == {2.5}  # the user's function, passed through
    assert max(r["speed_limit_mps"] for r in records) > 2.0  # a road car is not capped at the 1:10 car's 2 m/s


def test_replay_counts_the_frames_its_range_selects_not_the_whole_recording(shared_data: Path, tmp_path: Path, capsys) -> None:
    assert main(["replay", str(shared_data / VIDEO), "--to", "20f", "--every", "2", "--no-plots", "--out", str(tmp_path / "o")]) == 0
    out = capsys.readouterr().out
    assert "frames 10 of 10 selected by --from/--to/--every (221 in the recording)" in out
    summary = json.loads((tmp_path / "o" / "summary.json").read_text())
    assert (summary["selected_frames"], summary["processed_frames"], summary["expected_frames"]) == (10, 10, 221)


@pytest.mark.parametrize(("args", "says"), [
    (["--steer", "no_such_module_xyz:steer"], "SteerImportError: --steer no_such_module_xyz:steer: cannot import"),
    (["--vehicle", "no_such_car"], "VehicleFileError: no_such_car, --vehicle: neither a preset"),
])
def test_replay_rejects_a_bad_steer_or_vehicle_with_exit_2(tmp_path: Path, capsys, args: list[str], says: str) -> None:
    assert main(["replay", str(tmp_path / "none.mp4"), "--out", str(tmp_path / "o"), *args]) == 2
    assert capsys.readouterr().err.startswith(says)


def test_a_warning_is_one_line_without_python_source(shared_data: Path, tmp_path: Path, capsys) -> None:
    log = tmp_path / "sensors.csv"
    log.write_text("t_s,speed_mps,wheel_temp\n0.0,1.0,40\n")
    argv = ["replay", str(shared_data / VIDEO), "--to", "2f", "--no-plots", "--sensor-log", str(log), "--out", str(tmp_path / "o")]
    assert main(argv) == 0
    err = capsys.readouterr().err
    assert f"warning: {log}: unknown columns ignored: wheel_temp" in err
    other = [line for line in err.strip().splitlines() if not line.startswith("replay: ")]  # progress lines without a terminal
    assert "SensorLogWarning" not in err and "warnings.warn" not in err and len(other) == 1


def test_suite_prints_totals_and_keeps_supervisor_checks_apart(tmp_path: Path, capsys) -> None:
    folder = tmp_path / "scenarios"
    folder.mkdir()
    (folder / "short.toml").write_text(SHORT + "no_emergency = true\n")
    assert main(["suite", str(folder), "--seeds", "1", "--out", str(tmp_path / "s")]) == 0
    out = capsys.readouterr().out
    assert ("totals: guarded 0 of 1 runs failed an outcome (0 collisions, 0 departures), 0 failed a supervisor check; "
            "unguarded 0 of 1") in out
    assert "| short | no_emergency | pass |" in out  # the supervisor-only check: guarded only
    rows = [json.loads(line) for line in (tmp_path / "s" / "runs.jsonl").read_text().splitlines()]
    assert {r["controller"]: r["not_applicable"] for r in rows} == {"guarded": [], "unguarded": ["no_emergency"],
                                                                     "crisp": ["no_emergency"], "aeb": ["no_emergency"]}


def test_a_suite_of_one_controller_runs_and_tables_only_it(tmp_path: Path, capsys) -> None:
    folder = tmp_path / "scenarios"
    folder.mkdir()
    (folder / "short.toml").write_text(SHORT + "no_emergency = true\n")
    argv = ["suite", str(folder), "--seeds", "2", "--controllers", "aeb", "guarded", "--out", str(tmp_path / "s")]
    assert main(argv) == 0
    captured = capsys.readouterr()
    assert "× guarded, aeb →" in captured.err  # the table's order, whatever the order asked
    assert "| scenario | guarded | aeb |" in captured.out and "| unguarded |" not in captured.out
    assert "| guarded | 2 | 0 | 0 | 0 | – |" in captured.out  # progress is a share of the unguarded car's: none here
    assert "totals: guarded 0 of 2 runs failed an outcome" in captured.out and "; aeb 0 of 2 runs" in captured.out
    rows = [json.loads(line) for line in (tmp_path / "s" / "runs.jsonl").read_text().splitlines()]
    assert sorted((r["controller"], r["seed"]) for r in rows) == [("aeb", 0), ("aeb", 1), ("guarded", 0), ("guarded", 1)]


def test_the_cli_names_the_simulators_controllers_as_the_simulator_does(capsys) -> None:
    from fearguard.cli import SIM_CONTROLLERS
    from fearguard.sim.loop import CONTROLLERS

    assert SIM_CONTROLLERS == CONTROLLERS
    with pytest.raises(SystemExit) as exc:
        main(["suite", "--controllers", "autopilot"])
    assert exc.value.code == 2 and "invalid choice: 'autopilot'" in capsys.readouterr().err


def _readme_commands() -> list[str]:
    """Every `.venv/bin/fearguard ...` line of README's bash blocks (continuations joined, comments cut)."""
    text = (Path(__file__).resolve().parents[1] / "README.md").read_text(encoding="utf-8")
    blocks = re.findall(r"```bash\n(.*?)```", text, flags=re.S)
    joined = "\n".join(blocks).replace("\\\n", " ")
    return [line.split("  #")[0].split(" || ")[0].strip() for line in joined.splitlines() if line.startswith(".venv/bin/fearguard ")]


def test_every_readme_command_is_one_the_parser_accepts() -> None:
    import shlex

    from fearguard.cli import build_parser

    commands = _readme_commands()
    assert len(commands) >= 12
    for line in commands:
        argv = shlex.split(line)[1:]
        try:
            build_parser().parse_args(argv)
        except SystemExit as exc:  # argparse's usage error
            raise AssertionError(f"README command does not parse: {line}") from exc


def test_the_progress_line_without_rich_is_one_line_redrawn_on_stderr(monkeypatch, capsys) -> None:
    import fearguard.cli as cli

    monkeypatch.setitem(sys.modules, "rich.console", None)  # the core install: no rich
    monkeypatch.setattr(sys.stderr, "isatty", lambda: True)
    with cli._Progress("suite", unit="runs") as bar:
        bar.update(0, 4)
        bar.update(4, 4)
    err = capsys.readouterr().err
    assert err.startswith("\rsuite: 0/4 runs") and "\rsuite: 4/4 runs" in err and err.endswith("\n") and err.count("\n") == 1


def test_without_a_terminal_a_long_job_prints_a_line_per_step_or_per_5_percent(monkeypatch, capsys) -> None:
    """Issue 37: a CI log or a pipe sees progress too: a line per run / image / invariant, every 5 % of a long replay."""
    import fearguard.cli as cli

    assert [n for n in range(1, 8) if cli.plain_line_due(n, 7)] == list(range(1, 8))  # short: every step
    assert [n for n in range(1, 401) if cli.plain_line_due(n, 400)] == list(range(20, 401, 20))  # long: every 5 %, the end
    assert [n for n in range(1, 1001) if cli.plain_line_due(n, None)] == [500, 1000]  # unknown length
    assert not cli.plain_line_due(0, 10)
    monkeypatch.setattr(sys.stderr, "isatty", lambda: False)
    with cli._Progress("suite", unit="runs") as bar:
        for done in range(4):
            bar.update(done, 3)
    lines = capsys.readouterr().err.splitlines()
    assert [line.split(" runs")[0] for line in lines] == ["suite: 1/3", "suite: 2/3", "suite: 3/3"]
    assert lines[-1].startswith("suite: 3/3 runs (100 %)")


def test_verify_says_how_many_examples_of_each_invariant_are_done(tmp_path: Path) -> None:
    from fearguard.testing.verify import verify_command

    rows: list[str] = []
    progress: list[str] = []
    assert verify_command(None, None, None, 8, 0, tmp_path, ("1",), echo=rows.append, progress=progress.append) == 0
    assert progress == [f"verify: invariant 1 (limits in range): {n}/8 examples" for n in (2, 4, 6)]
    assert any(row.lstrip().startswith("1  limits in range") for row in rows)
