"""Suites and sweeps on Dask against the in-process loop, on this machine (issue 36), in one run:

    python benchmarks/bench_cluster.py                 # 8 bundled scenarios × 1 seed × 4 controllers, then the sweep
    python benchmarks/bench_cluster.py --scenarios 16 --seeds 2

1. the suite's wall time as a user waits for it: ``fearguard suite FOLDER --jobs 1`` (the in-process loop, no Dask) and
   ``--jobs 2`` (a local Dask cluster of two single-threaded worker processes, its start-up and shut-down included),
   each in a fresh process, and their ratio (goal: ≤ 0.6 on 2 cores);
2. Dask's own cost per row: the same rows on a local cluster of ONE worker, with Dask's task stream: each row's compute
   time inside the worker against the wall time from the first submit to the last result. The difference over the
   rows is what scheduling, sending the spec and the row back cost per row, as a share of a row's time (goal: ≤ 2 %);
   the cluster's start-up is printed apart (paid once per command);
3. a sweep of 3 × 2 values × 3 scenarios × 2 seeds (``policy.hold_s=1,2,3``, ``vehicle.max_speed_mps=1.5,2``) with
   ``--jobs 2``: its wall time, runs and the safe combinations ranked by progress.

The rows of (1) are compared too: both runs.jsonl must hold the same rows. The machine is shared and noisy: the ratios
are what to read, from one run, with the load average and the cores each command got (its CPU seconds over its wall
seconds) printed beside them: a ratio above 0.6 with ``--jobs 2`` getting about one core is the machine's load, not Dask.
"""

from __future__ import annotations

import argparse
import json
import logging
import os
import resource
import subprocess
import sys
import tempfile
import time
from pathlib import Path

from fearguard.drive.cluster import WORKER_CONFIG
from fearguard.drive.plan import run_row
from fearguard.sim.scenario import BUNDLED
from fearguard.sim.suite import plan, scenario_files

SWEEP_SCENARIOS = ("camera_blackout", "night", "stationary_obstacle")
SWEEP_SETTINGS = ("policy.hold_s=1,2,3", "vehicle.max_speed_mps=1.5,2")


def cli(*argv: str) -> tuple[float, float, int]:
    """``fearguard ARGV`` in a fresh process (as a user runs it): wall seconds, CPU seconds and exit code.

    The CPU seconds are those of the command and every process under it that ended (its local cluster's workers), from
    ``getrusage(RUSAGE_CHILDREN)``: on a machine shared with other jobs, CPU / wall says how many cores the command got.
    """
    before = resource.getrusage(resource.RUSAGE_CHILDREN)
    start = time.perf_counter()
    done = subprocess.run([sys.executable, "-m", "fearguard.cli", *argv], stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
    wall = time.perf_counter() - start
    after = resource.getrusage(resource.RUSAGE_CHILDREN)
    return wall, (after.ru_utime - before.ru_utime) + (after.ru_stime - before.ru_stime), done.returncode


def rows(path: Path) -> dict[str, dict]:
    """A runs.jsonl by spec (its lines are in arrival order, which differs between --jobs 1 and --jobs 2)."""
    return {json.dumps(r["spec"], sort_keys=True): r for r in map(json.loads, path.read_text().splitlines())}


def dask_overhead(files: list[Path], seeds: int) -> tuple[float, float, float, int]:
    """(start-up s, mean compute s per row, overhead s per row, rows) on a local cluster of one worker."""
    import dask.config
    import distributed

    specs = plan(files, seeds)
    start = time.perf_counter()
    with dask.config.set(WORKER_CONFIG), \
            distributed.LocalCluster(n_workers=1, threads_per_worker=1, processes=True, dashboard_address=None,
                                     silence_logs=logging.ERROR) as cluster, \
            distributed.Client(cluster, set_as_default=False) as client:
        client.submit(run_row, specs[0], pure=False).result()  # the worker imports fearguard and warms up (once per worker)
        startup = time.perf_counter() - start
        with distributed.get_task_stream(client) as stream:
            began = time.perf_counter()
            client.gather([client.submit(run_row, spec, pure=False) for spec in specs])
            wall = time.perf_counter() - began
    compute = sum(ss["stop"] - ss["start"] for task in stream.data for ss in task["startstops"] if ss["action"] == "compute")
    return startup, compute / len(specs), (wall - compute) / len(specs), len(specs)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--scenarios", type=int, default=8, help="bundled scenarios in the suite (every other one by name)")
    parser.add_argument("--seeds", type=int, default=1)
    args = parser.parse_args()
    every = scenario_files()
    picked = every[:: max(1, len(every) // args.scenarios)][: args.scenarios]
    print(f"load average before: {' '.join(f'{x:.1f}' for x in os.getloadavg())} on {os.cpu_count()} cores")
    with tempfile.TemporaryDirectory() as tmp:
        folder = Path(tmp) / "scenarios"
        folder.mkdir()
        for path in picked:
            (folder / path.name).write_bytes(path.read_bytes())
        runs = len(picked) * args.seeds * 4
        print(f"suite: {len(picked)} bundled scenarios × {args.seeds} seed(s) × 4 controllers = {runs} runs "
              f"({', '.join(p.stem for p in picked)})")
        one, cpu_one, _ = cli("suite", str(folder), "--seeds", str(args.seeds), "--out", f"{tmp}/j1", "--jobs", "1")
        two, cpu_two, _ = cli("suite", str(folder), "--seeds", str(args.seeds), "--out", f"{tmp}/j2", "--jobs", "2")
        same = rows(Path(tmp, "j1", "runs.jsonl")) == rows(Path(tmp, "j2", "runs.jsonl"))
        print(f"  --jobs 1 (in this process): {one:6.1f} s   ({one / runs:.2f} s per run; CPU {cpu_one:.1f} s = "
              f"{cpu_one / one:.2f} cores on average)")
        print(f"  --jobs 2 (local Dask, 2 workers): {two:6.1f} s   ratio {two / one:.2f} (goal <= 0.6); CPU {cpu_two:.1f} s = "
              f"{cpu_two / two:.2f} cores on average; the same rows: {same}")

        startup, row_s, overhead_s, n = dask_overhead(sorted(folder.glob("*.toml")), args.seeds)
        print(f"Dask per row, one worker, {n} rows: compute {row_s:.2f} s, overhead {1000 * overhead_s:.1f} ms = "
              f"{100 * overhead_s / row_s:.2f} % of a row (goal <= 2 %); start-up of a local cluster (and the worker's imports): "
              f"{startup:.1f} s, once per command")

        sweep = Path(tmp) / "sweep"
        sweep.mkdir()
        for name in SWEEP_SCENARIOS:
            (sweep / f"{name}.toml").write_bytes((BUNDLED / f"{name}.toml").read_bytes())
        sets = [a for s in SWEEP_SETTINGS for a in ("--set", s)]
        wall, _cpu, code = cli("sweep", str(sweep), *sets, "--seeds", "2", "--out", f"{tmp}/sw", "--jobs", "2")
        result = json.loads(Path(tmp, "sw", "sweep.json").read_text())
        print(f"sweep {' '.join(SWEEP_SETTINGS)} × {len(SWEEP_SCENARIOS)} scenarios × 2 seeds, --jobs 2: {wall:.1f} s for "
              f"{result['finished_runs']} runs ({len(result['combinations'])} combinations guarded + the unguarded car once), exit {code}")
        for t in result["combinations"]:
            progress = f"{100 * t['progress']:.0f} %" if t["progress"] is not None else "–"
            print(f"  {t['combination']:<42} collisions {t['collisions']}, departures {t['lane_departures']}, progress {progress}, "
                  f"EMERGENCY {t['emergency_s']:.1f} s{'  (Pareto)' if t['pareto'] else ''}")
        print(f"  safe, most progress first: {'; '.join(result['safe_ranked']) or 'none'}")
    print(f"load average after: {' '.join(f'{x:.1f}' for x in os.getloadavg())}")


if __name__ == "__main__":
    main()
