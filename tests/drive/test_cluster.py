"""Plans on Dask (drive/cluster.py): a real ``dask scheduler`` and two ``dask worker`` processes on 127.0.0.1, and local
clusters, give the serial rows; a worker killed mid-run costs a re-run, never a row; Ctrl-C leaves a runs.jsonl that
``--resume`` completes; without Dask the command says how to install it."""

from __future__ import annotations

import json
import os
import re
import signal
import socket
import subprocess
import sys
import time
from collections import Counter
from pathlib import Path

import pytest
from tests.drive.dask_cluster import START_TIMEOUT_S, DaskProcesses

from fearguard.cli import main
from fearguard.drive.cluster import ADDRESS_FORM, DaskExecutor, executor_for, scheduler_address_ok
from fearguard.drive.interrupt import StopSignal
from fearguard.drive.plan import RunSpec, row_key
from fearguard.drive.suite import finished_rows, run_plan
from fearguard.errors import ClusterError
from fearguard.sim.scenario import BUNDLED
from fearguard.sim.suite import plan, suite_markdown, suite_table

SCENARIOS = ("clear_straight", "night", "stationary_obstacle")  # three bundled scenarios, cut to SHORT_S each
SHORT_S = 1.5  # [s] simulated per run: a real closed loop, short enough for CI


@pytest.fixture(scope="module")
def folder(tmp_path_factory: pytest.TempPathFactory) -> Path:
    """Copies of three bundled scenarios that last SHORT_S."""
    out = tmp_path_factory.mktemp("scenarios")
    for name in SCENARIOS:
        lines = [ln for ln in (BUNDLED / f"{name}.toml").read_text().splitlines() if not ln.startswith("duration_s")]
        (out / f"{name}.toml").write_text(f"duration_s = {SHORT_S}\n" + "\n".join(lines) + "\n")
    return out


@pytest.fixture(scope="module")
def specs(folder: Path) -> list[RunSpec]:
    """The suite's plan: three scenarios × 2 seeds × every controller (24 runs)."""
    return plan(sorted(folder.glob("*.toml")), 2)


@pytest.fixture(scope="module")
def serial_rows(specs: list[RunSpec]) -> list[dict]:
    """The rows run one after the other in this process: what every cluster must give."""
    return run_plan(specs).rows


def _by_key(rows: list[dict]) -> dict:
    return {row_key(r): r for r in rows}


# -- without a cluster --------------------------------------------------------------------------
@pytest.mark.parametrize(("text", "ok"), [
    ("tcp://10.0.0.5:8786", True), ("127.0.0.1:8786", True), ("scheduler", True), ("tls://[::1]:8786", True),
    ("tcp://host:0", False), ("tcp://host:70000", False), ("http://host:8786", False), ("two words", False), ("", False),
])
def test_a_scheduler_address_is_checked_by_its_form(text: str, ok: bool) -> None:
    assert scheduler_address_ok(text) is ok


def test_the_executor_is_asked_for_one_way_and_says_where_it_runs() -> None:
    for kwargs in ({}, {"jobs": 2, "scheduler": "tcp://h:1"}):
        with pytest.raises(ValueError, match="either jobs"):
            DaskExecutor(**kwargs)
    with pytest.raises(ValueError, match="jobs must be a whole number >= 1, got 0"):
        DaskExecutor(jobs=0)
    with pytest.raises(ValueError, match=re.escape(f"scheduler must be {ADDRESS_FORM}")):
        DaskExecutor(scheduler="http://h")
    assert executor_for(1) is None  # one job: the in-process loop, no Dask
    assert executor_for(2).where == "a local Dask cluster of 2 worker processes"
    assert DaskExecutor(jobs=1).where == "a local Dask cluster of 1 worker process"
    assert executor_for(5, "tcp://10.0.0.5:8786").where == "the Dask scheduler at tcp://10.0.0.5:8786"


def test_without_dask_jobs_and_scheduler_say_how_to_install_it(monkeypatch, capsys, folder: Path, tmp_path: Path) -> None:
    monkeypatch.setitem(sys.modules, "distributed", None)  # as if `pip install fearguard` had no [cluster] extra
    with pytest.raises(ClusterError, match=r"pip install 'fearguard\[cluster\]'"):
        executor_for(2)
    for option in (["--jobs", "2"], ["--scheduler", "tcp://127.0.0.1:8786"]):
        assert main(["suite", str(folder), "--seeds", "1", "--out", str(tmp_path / "out"), *option]) == 2
        err = capsys.readouterr().err.strip().splitlines()
        assert len(err) == 1 and err[0].startswith("ClusterError: ") and "pip install 'fearguard[cluster]'" in err[0], err
    assert not (tmp_path / "out").exists()  # refused before anything ran or was written


def test_one_job_runs_in_this_process_without_importing_dask(folder: Path, tmp_path: Path) -> None:
    code = ("import sys; from fearguard.cli import main; "
            f"code = main(['suite', {str(folder)!r}, '--seeds', '1', '--out', {str(tmp_path)!r}, '--jobs', '1']); "
            "assert 'distributed' not in sys.modules and 'dask' not in sys.modules, 'Dask was imported'; print(code)")
    done = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True)
    assert done.stdout.strip().splitlines()[-1] in ("0", "1") and len(finished_rows(tmp_path / "runs.jsonl")) == 12


# -- a local cluster ------------------------------------------------------------------------------
@pytest.mark.slow
def test_a_stop_before_any_row_cancels_every_run(specs: list[RunSpec]) -> None:
    stop = StopSignal()
    stop.request(signal.SIGINT)
    assert list(DaskExecutor(jobs=1)(specs, stop)) == []


@pytest.mark.slow
def test_ctrl_c_on_a_local_cluster_leaves_no_worker_behind_and_the_finished_rows(folder: Path, tmp_path: Path,
                                                                               serial_rows: list[dict]) -> None:
    psutil = pytest.importorskip("psutil")  # comes with distributed
    out = tmp_path / "out"
    cli = _start_cli(["suite", str(folder), "--seeds", "2", "--out", str(out), "--jobs", "2"])
    _wait_for_rows(cli, out / "runs.jsonl", 1)
    workers = psutil.Process(cli.pid).children(recursive=True)
    assert workers  # the local cluster's worker processes
    cli.send_signal(signal.SIGINT)
    assert cli.wait(timeout=START_TIMEOUT_S) == 130
    _gone, alive = psutil.wait_procs(workers, timeout=30)
    assert not alive, f"worker processes left running: {alive}"
    kept = finished_rows(out / "runs.jsonl")  # every line whole, each an equal serial row (--resume: the scheduler's test)
    assert 1 <= len(kept) == len((out / "runs.jsonl").read_text().splitlines()) < 24
    assert all(_by_key(serial_rows)[row_key(r)] == r for r in kept)


# -- a real scheduler and two workers -------------------------------------------------------------
@pytest.mark.slow
def test_a_suite_on_a_scheduler_gives_the_serial_rows_in_the_same_tables(dask_cluster: DaskProcesses, folder: Path, tmp_path: Path,
                                                                         serial_rows: list[dict], monkeypatch) -> None:
    """``fearguard suite --scheduler``: runs.jsonl holds the serial rows (in arrival order), the tables are the ones the
    serial suite writes (``suite_markdown`` / ``suite_table`` of the serial rows), the rows in plan order."""
    monkeypatch.chdir(folder.parent)  # a relative folder: the workers, started elsewhere, get absolute paths
    assert main(["suite", folder.name, "--seeds", "2", "--out", str(tmp_path), "--scheduler", dask_cluster.address]) in (0, 1)
    cluster = finished_rows(tmp_path / "runs.jsonl")
    assert len(serial_rows) == 24 and _by_key(cluster) == _by_key(serial_rows)  # every row, equal (sim rows have no timing)
    assert (tmp_path / "suite.md").read_text() == suite_markdown(serial_rows)
    suite = json.loads((tmp_path / "suite.json").read_text())
    assert suite["runs"] == serial_rows and suite["table"] == suite_table(serial_rows)  # plan order in the tables


@pytest.mark.slow
def test_a_worker_killed_after_the_first_row_costs_a_rerun_never_a_row(dask_cluster: DaskProcesses, specs: list[RunSpec],
                                                                       serial_rows: list[dict], tmp_path: Path) -> None:
    arrived: list[dict] = []

    def on_row(row: dict) -> None:
        arrived.append(row)
        if len(arrived) == 1:
            dask_cluster.kill_worker()  # mid-plan: the other worker has a run under way, the killed one had one too

    try:
        result = run_plan(specs, runs_log=tmp_path / "runs.jsonl", executor=DaskExecutor(scheduler=dask_cluster.address),
                          on_row=on_row)
    finally:
        dask_cluster.add_workers(1)  # two workers again for the other tests
    keys = Counter(row_key(r) for r in finished_rows(tmp_path / "runs.jsonl"))
    assert len(keys) == 24 and set(keys.values()) == {1}  # every row exactly once
    assert not result.interrupted and result.rows == serial_rows and len(arrived) == 24


@pytest.mark.slow
def test_ctrl_c_leaves_a_valid_runs_jsonl_that_resume_completes(dask_cluster: DaskProcesses, folder: Path, tmp_path: Path,
                                                                 serial_rows: list[dict]) -> None:
    out = tmp_path / "out"
    cli = _start_cli(["suite", str(folder), "--seeds", "2", "--out", str(out), "--scheduler", dask_cluster.address])
    _wait_for_rows(cli, out / "runs.jsonl", 1)
    cli.send_signal(signal.SIGINT)
    assert cli.wait(timeout=START_TIMEOUT_S) == 130
    lines = (out / "runs.jsonl").read_text().splitlines()
    assert 1 <= len(lines) < 24 and all(isinstance(json.loads(line), dict) for line in lines)  # every line whole
    assert "run the same command with --resume" in cli.stdout.read()
    _resume_and_compare(folder, out, serial_rows, ["--scheduler", dask_cluster.address])


@pytest.mark.slow
def test_a_scheduler_nobody_answers_is_one_clear_error(specs: list[RunSpec]) -> None:
    with socket.socket() as s:  # a free port nothing listens on
        s.bind(("127.0.0.1", 0))
        port = s.getsockname()[1]
    executor = DaskExecutor(scheduler=f"tcp://127.0.0.1:{port}", connect_timeout_s=1.0)
    with pytest.raises(ClusterError, match=f"cannot reach the Dask scheduler at tcp://127.0.0.1:{port}.*dask scheduler"):
        run_plan(specs[:2], executor=executor)


@pytest.mark.slow
def test_a_lost_scheduler_ends_the_plan_with_the_finished_rows_kept(tmp_path: Path, specs: list[RunSpec]) -> None:
    lost = DaskProcesses(tmp_path / "dask")
    try:
        lost.add_workers(1)

        def on_row(row: dict) -> None:
            if lost.scheduler.poll() is None:
                os.killpg(lost.scheduler.pid, signal.SIGKILL)

        with pytest.raises(ClusterError, match=r"was cancelled on the Dask scheduler at .* with --resume"):
            run_plan(specs, runs_log=tmp_path / "runs.jsonl", executor=DaskExecutor(scheduler=lost.address), on_row=on_row)
    finally:
        lost.close()
    assert 1 <= len(finished_rows(tmp_path / "runs.jsonl")) < len(specs)


def _start_cli(argv: list[str]) -> subprocess.Popen:
    """The fearguard command in a process of its own (its stdout piped: the last lines say how to go on)."""
    return subprocess.Popen([sys.executable, "-m", "fearguard.cli", *argv], stdout=subprocess.PIPE, stderr=subprocess.DEVNULL,
                            text=True)


def _wait_for_rows(cli: subprocess.Popen, runs: Path, n: int) -> None:
    deadline = time.monotonic() + START_TIMEOUT_S
    while time.monotonic() < deadline:
        assert cli.poll() is None, f"the suite ended ({cli.returncode}) before it was interrupted"
        if runs.is_file() and len(runs.read_text().splitlines()) >= n:
            return
        time.sleep(0.05)
    pytest.fail(f"no row in {runs} after {START_TIMEOUT_S:.0f} s")


def _resume_and_compare(folder: Path, out: Path, serial_rows: list[dict], option: list[str]) -> None:
    """``--resume`` runs what is missing; then every row is there exactly once and equals the serial row."""
    assert main(["suite", str(folder), "--seeds", "2", "--out", str(out), "--resume", *option]) in (0, 1)
    rows = finished_rows(out / "runs.jsonl")
    assert len(rows) == 24 and Counter(map(row_key, rows)).most_common(1)[0][1] == 1
    assert _by_key(rows) == _by_key(serial_rows)
