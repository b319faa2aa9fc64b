"""Every batch command (suite, sweep, fleet replay, duckietown-suite) reports its runs: without a terminal a line per
finished run with the runs done of the plan, the failures, the workers and the time left (issue 36)."""

from __future__ import annotations

from pathlib import Path

import pytest

from fearguard.cli import _duration, _RunProgress, main
from fearguard.sim.scenario import BUNDLED


@pytest.fixture(scope="module")
def one_scenario(tmp_path_factory: pytest.TempPathFactory) -> Path:
    out = tmp_path_factory.mktemp("scenario")
    lines = [ln for ln in (BUNDLED / "clear_straight.toml").read_text().splitlines() if not ln.startswith("duration_s")]
    (out / "clear_straight.toml").write_text("duration_s = 1.0\n" + "\n".join(lines) + "\n")
    return out


def test_a_suite_without_a_terminal_says_each_finished_run_and_resume_says_what_was_done(one_scenario: Path, tmp_path: Path,
                                                                                          capsys) -> None:
    main(["suite", str(one_scenario), "--seeds", "1", "--out", str(tmp_path)])
    lines = [ln for ln in capsys.readouterr().err.splitlines() if ln.startswith("suite: ") and " runs, " in ln]
    assert len(lines) == 4  # one per run (guarded and three baselines)
    assert lines[0].startswith("suite: 1/4 runs, ") and " failed, 1 worker, " in lines[0] and " left: clear_straight seed " in lines[0]
    assert lines[-1].startswith("suite: 4/4 runs, ") and "left" not in lines[-1]
    main(["suite", str(one_scenario), "--seeds", "1", "--out", str(tmp_path), "--resume"])
    assert "suite: 4/4 runs, 0 failed, 1 worker (resumed)" in capsys.readouterr().err


def test_failures_count_what_the_command_counts_and_workers_come_from_the_executor(capsys) -> None:
    class Cluster:
        workers = 2

    with _RunProgress("sweep", Cluster(), line=lambda r: r["name"], failed=lambda r: r["bad"]) as bar:
        bar.update(1, 3)  # one run resumed
        bar.row({"name": "a", "bad": True})
        bar.update(2, 3)
        bar.row({"name": "b", "bad": False})
        bar.update(3, 3)
    err = capsys.readouterr().err.splitlines()
    assert err == ["sweep: 1/3 runs, 0 failed, 2 workers (resumed)", err[1], "sweep: 3/3 runs, 1 failed, 2 workers: b"]
    assert err[1].startswith("sweep: 2/3 runs, 1 failed, 2 workers, ") and err[1].endswith(" left: a")


@pytest.mark.parametrize(("seconds", "text"), [(12.4, "12 s"), (600.0, "10 min"), (9000.0, "2.5 h")])
def test_time_left_reads_as_a_person_says_it(seconds: float, text: str) -> None:
    assert _duration(seconds) == text
