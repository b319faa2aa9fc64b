"""The one suite over a plan of real simulator runs: the same rows however they ran, resume, interruption."""

from __future__ import annotations

import json
import signal
from pathlib import Path

import pytest

from fearguard.drive.cluster import DaskExecutor
from fearguard.drive.interrupt import StopSignal
from fearguard.drive.plan import RunSpec, row_key, run_row, runner
from fearguard.drive.suite import finished_rows, run_plan
from fearguard.sim.scenario import BUNDLED
from fearguard.sim.suite import plan

SHORT = BUNDLED / "clear_straight.toml"


@pytest.fixture(scope="module")
def specs(tmp_path_factory: pytest.TempPathFactory) -> list[RunSpec]:
    """Two short scenarios (1.5 s each) × 2 seeds × guarded and unguarded: eight real runs."""
    folder = tmp_path_factory.mktemp("scenarios")
    for name in ("clear_straight", "stationary_obstacle"):
        text = (BUNDLED / f"{name}.toml").read_text()
        lines = [ln for ln in text.splitlines() if not ln.startswith("duration_s")]
        (folder / f"{name}.toml").write_text("duration_s = 1.5\n" + "\n".join(lines) + "\n")
    return plan(sorted(folder.glob("*.toml")), 2, ("guarded", "unguarded"))


def _without_spec(row: dict) -> dict:
    return {k: v for k, v in row.items() if k != "spec"}


def test_serial_and_dask_workers_give_the_same_rows_in_plan_order(specs: list[RunSpec], tmp_path: Path, dask_cluster) -> None:
    """The session's real scheduler and two workers (tests/conftest.py); a local cluster: tests/drive/test_cluster.py."""
    serial = run_plan(specs, runs_log=tmp_path / "a.jsonl")
    pooled = run_plan(specs, runs_log=tmp_path / "b.jsonl", executor=DaskExecutor(scheduler=dask_cluster.address))
    assert [r["spec"] for r in serial.rows] == [s.to_json() for s in specs] == [r["spec"] for r in pooled.rows]
    assert serial.rows == pooled.rows and len(serial.rows) == 8 and not serial.interrupted
    assert sorted(map(json.dumps, finished_rows(tmp_path / "b.jsonl"))) == sorted(map(json.dumps, serial.rows))


def test_resume_runs_only_what_is_missing(specs: list[RunSpec], tmp_path: Path) -> None:
    log = tmp_path / "runs.jsonl"
    first = run_plan(specs[:3], runs_log=log)
    seen: list[str] = []
    again = run_plan(specs, runs_log=log, resume=True, on_row=lambda row: seen.append(row["spec"]["name"]))
    assert again.resumed == 3 and len(seen) == 5 and again.rows[:3] == first.rows and len(again.rows) == 8
    assert len(finished_rows(log)) == 8  # the resumed rows written again, then each new one: a valid file


def test_a_stop_keeps_the_finished_rows_and_leaves_out_the_cut_run(specs: list[RunSpec], tmp_path: Path) -> None:
    stop = StopSignal()
    progress: list[tuple[int, int]] = []

    def after(done: int, planned: int) -> None:
        progress.append((done, planned))
        if done == 2:
            stop.signum = signal.SIGTERM  # arrives while the third run drives: it ends after its frame and is left out

    result = run_plan(specs, runs_log=tmp_path / "runs.jsonl", stop=stop, on_progress=after)
    assert result.interrupted and result.stopped_by == "SIGTERM" and len(result.rows) == 2
    assert progress[0] == (0, 8) and progress[-1] == (2, 8)
    resumed = run_plan(specs, runs_log=tmp_path / "runs.jsonl", resume=True)
    assert len(resumed.rows) == 8 and resumed.resumed == 2


def test_a_row_names_its_run_and_old_rows_are_recognised() -> None:
    spec = RunSpec("sim", "clear_straight", "guarded", 3, {"file": str(SHORT)})
    assert RunSpec.from_json(json.loads(json.dumps(spec.to_json()))) == spec
    assert row_key({"spec": spec.to_json()}) == ("sim", "clear_straight", "guarded", 3)
    assert row_key({"scenario": "night", "seed": 2, "controller": "aeb", "passed": True}) == ("sim", "night", "aeb", 2)  # before plans
    assert row_key({"spec": {"world": "sim"}}) is None and row_key({"frames": 3}) is None
    with pytest.raises(ValueError, match="unknown world 'carla'; known: sim, duckietown, replay"):
        runner("carla")
    row = run_row(RunSpec("sim", "clear_straight", "unguarded", 1, {"file": str(SHORT)}))
    assert row["spec"]["controller"] == "unguarded" and row["scenario"] == "clear_straight" and row["collisions"] == 0


def test_run_plan_with_tables_rewrites_the_tables_after_every_row_resumed_ones_included(specs: list[RunSpec], tmp_path: Path) -> None:
    from fearguard.drive.suite import run_plan_with_tables

    def merge(rows: list[dict]) -> tuple[list[dict], list[dict], str]:
        return rows, [{"criterion": "rows", "ok": True}], "\n".join(r["scenario"] + " " + r["controller"] for r in rows) + "\n"

    seen: list[int] = []
    first, _ = run_plan_with_tables(specs[:3], tmp_path, merge, on_row=lambda row: seen.append(len(json.loads(
        (tmp_path / "suite.json").read_text())["rows"])))
    assert seen == [1, 2, 3] and len(first.rows) == 3  # the table grew with every row
    result, markdown = run_plan_with_tables(specs, tmp_path, merge, resume=True)
    table = json.loads((tmp_path / "suite.json").read_text())
    assert result.resumed == 3 and len(table["rows"]) == len(specs) and table["criteria"] == [{"criterion": "rows", "ok": True}]
    assert (tmp_path / "suite.md").read_text() == markdown and markdown.count("\n") == len(specs)
    assert [r["scenario"] for r in table["rows"]] == [r["scenario"] for r in result.rows]  # plan order


def test_compared_with_experts_divides_by_the_experts_progress_on_the_same_run() -> None:
    from fearguard.drive.suite import compared_with_experts

    rows = [{"run": "a", "controller": "expert", "progress_m": 200.0, "spec": {}, "interrupted": False},
            {"run": "a", "controller": "guarded", "progress_m": 180.0},
            {"run": "b", "controller": "guarded", "progress_m": 50.0},  # no expert on b
            {"run": "a", "controller": "unguarded", "progress_m": 190.0, "skip": True}]
    out = compared_with_experts(rows, lambda r: not r.get("skip"))
    assert [r["progress_vs_expert_pct"] for r in out] == [100.0, 90.0, None, None]
    assert "spec" not in out[0] and "interrupted" not in out[0]
    assert compared_with_experts(rows)[3]["progress_vs_expert_pct"] == 95.0


def test_suite_text_is_the_table_the_cost_and_a_line_per_criterion() -> None:
    from fearguard.drive.suite import cost_line, suite_text

    rows = [{"controller": "guarded", "controller_ms": 4.0, "simulator_ms": 100.0},
            {"controller": "guarded", "controller_ms": 6.0, "simulator_ms": 300.0},
            {"controller": "expert", "controller_ms": None, "simulator_ms": 1.0}]
    checks = [{"criterion": "a", "ok": True, "detail": "1"}, {"criterion": "b", "ok": False, "detail": "2"}]
    text = suite_text("| t |\n", rows, checks)
    assert text.startswith("| t |\n") and text.endswith("- PASS a (1)\n- FAIL b (2)\n")
    assert "5.0 ms median over 2 guarded drives; the simulator's step (physics + rendering): 200.0 ms; fearguard = 2.5 % of it" in text
    assert "; the world's step: 200.0 ms" in suite_text("", rows, [], "the world's step")
    assert cost_line(rows[2:]) == ""  # no guarded row: no cost line
