"""duckietown-suite on Dask (``--jobs 2``: a local cluster of two worker processes) gives the serial rows (issue 36)."""

from __future__ import annotations

import json
from pathlib import Path

import pytest

pytest.importorskip("gym_duckietown", reason="the Duckietown simulator is not installed (bash .ci/duckietown.sh)")
pytest.importorskip("distributed", reason="Dask is not installed (pip install 'fearguard[cluster]')")

from fearguard.drive.cluster import DaskExecutor
from fearguard.worlds.duckietown.suite import run_suite

TIMING = ("controller_ms", "simulator_ms")  # per-step medians: the only fields that depend on the machine's load


def _rows(out: Path) -> dict[tuple, dict]:
    """runs.jsonl by run, without the timing fields and the run's folder (each suite writes under its own)."""
    rows = [json.loads(line) for line in (out / "runs.jsonl").read_text().splitlines()]
    return {(r["run"], r["controller"], r["range_sensor"], r["seed"]): {k: v for k, v in r.items() if k not in (*TIMING, "spec")}
            for r in rows}


def test_two_dask_workers_give_the_rows_of_the_serial_suite(tmp_path: Path) -> None:
    """One map, 2 s drives: three lane drives and the five obstacle drives, one after the other and on two workers."""
    run_suite(tmp_path / "serial", seconds=2.0, seeds=0, maps=["straight_road"])
    run_suite(tmp_path / "dask", seconds=2.0, seeds=0, maps=["straight_road"], executor=DaskExecutor(jobs=2))
    serial, dask = _rows(tmp_path / "serial"), _rows(tmp_path / "dask")
    assert len(serial) == 8 and dask == serial
    assert (tmp_path / "dask" / "suite.md").is_file() and any((tmp_path / "dask").glob("straight_road_guarded_*/summary.json"))
