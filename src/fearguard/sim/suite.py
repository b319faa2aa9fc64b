"""Files of a scenario run, and the suite: every scenario × seeds × (guarded + baselines) in one table.

``run_to_folder`` writes log.jsonl (flushed per frame), summary.json, timeline.png, trajectory.png and
(optionally) the annotated video. ``run_suite`` runs without per-frame files and returns rows for the table,
appending each finished run to runs.jsonl as it goes (an interrupted suite resumes from it);
``suite_markdown`` renders them (guarded vs unguarded vs crisp vs aeb: failures, collisions, lane
departures, mean speed, emergency entries).
"""

from __future__ import annotations

from collections.abc import Callable, Iterable, Sequence
from dataclasses import dataclass, replace
from pathlib import Path
from typing import Any

import numpy as np

from fearguard.interrupt import StopSignal
from fearguard.recorder import SUMMARY_NAME, write_json
from fearguard.report import JsonlLog, read_jsonl
from fearguard.sim.loop import CONTROLLERS, RunResult, run_scenario
from fearguard.sim.metrics import Row
from fearguard.sim.road import Road
from fearguard.sim.scenario import Scenario, load_scenario
from fearguard.timeline import plot_timeline

BUNDLED = Path(__file__).resolve().parents[1] / "scenarios"
BENIGN = ("clear_straight", "s_curves")  # scenarios without a hazard: the false-alarm check


def scenario_files(folder: str | Path | None = None) -> list[Path]:
    """The *.toml scenarios of a folder (default: the bundled library), sorted by name."""
    return sorted(Path(folder or BUNDLED).glob("*.toml"))


def run_to_folder(
    scenario: Scenario, out: Path, seed: int | None = None, controller: str = "guarded", video: bool = False,
    on_frame: Callable[[int, int], None] | None = None, stop: StopSignal | None = None,
) -> RunResult:
    """One run with every file a person looks at; the summary is on disk before the plots are drawn.

    A stop signal during the plots skips the plots not yet drawn and marks the summary interrupted.
    """
    out.mkdir(parents=True, exist_ok=True)
    result = run_scenario(scenario, seed, controller, out, video=video, on_frame=on_frame, stop=stop)
    write_json(out / SUMMARY_NAME, result.to_json())
    if result.rows:
        title = f"{scenario.name} ({controller}, seed {result.seed})"
        plots: list[Callable[[], object]] = [lambda: plot_trajectory(scenario, result.rows, out / "trajectory.png", title)]
        if controller == "guarded" and result.trace is not None:
            plots.insert(0, lambda: plot_timeline(result.trace, out / "timeline.png", title=title, with_speed=True))
        for draw in plots:
            if stop:
                break
            draw()
        if stop and not result.interrupted:  # the frames were all run; the plots were cut short
            result = replace(result, interrupted=True, stopped_by=stop.name)
            write_json(out / SUMMARY_NAME, result.to_json())
    return result


def plot_trajectory(scenario: Scenario, rows: Sequence[Row], path: Path, title: str) -> None:
    """Top-down view: lane boundaries, the car's path coloured by mode, collisions and lane departures marked."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    road = Road(scenario.road)
    s = np.linspace(0.0, road.length_m, 400)
    half = scenario.road.lane_width_m / 2
    fig, ax = plt.subplots(figsize=(8, 8))
    for lat in (-half, half):
        x, y = road.point_at(s, lat)
        ax.plot(x, y, color="grey", lw=1)
    colours = {"NORMAL": "tab:green", "CAUTION": "tab:orange", "EMERGENCY": "tab:red", None: "tab:blue"}
    ax.scatter([r.x_m for r in rows], [r.y_m for r in rows], s=4, c=[colours.get(r.mode, "tab:blue") for r in rows])
    hit = next((r for r in rows if r.collided), None)
    if hit is not None:
        ax.plot(hit.x_m, hit.y_m, "kx", ms=12, mew=3)
    out_of_lane = [(r.x_m, r.y_m) for r in rows if not r.in_lane]
    if out_of_lane:
        ax.scatter(*zip(*out_of_lane, strict=True), s=10, facecolors="none", edgecolors="m", label="outside the lane")
    for ob in scenario.obstacles:
        ox, oy = road.point_at(ob.s_m, ob.lateral_m)
        ax.plot(ox, oy, "ks", ms=8)
    ax.set_aspect("equal", adjustable="datalim")
    ax.set_title(title + "  (green NORMAL, orange CAUTION, red EMERGENCY, blue unsupervised)")
    ax.set_xlabel("x [m]")
    ax.set_ylabel("y [m]")
    fig.tight_layout()
    fig.savefig(path, dpi=90)
    plt.close(fig)


@dataclass(frozen=True)
class SuiteProgress:
    """What ``run_suite`` returns: every row (resumed and new), the runs still to do, and whether it was cut short."""

    rows: list[dict[str, Any]]
    planned: int  # runs in the whole suite
    resumed: int  # rows read back from an earlier, interrupted suite
    interrupted: bool = False
    stopped_by: str | None = None


def suite_row(result: RunResult) -> dict[str, Any]:
    """One run's line in runs.jsonl and in the table."""
    m = result.metrics
    return {
        "scenario": result.scenario, "controller": result.controller, "seed": result.seed, "passed": result.passed,
        "collisions": m.collisions, "lane_departures": m.lane_departures, "mean_speed_mps": m.mean_speed_mps,
        "emergency_entries": m.emergency_entries, "failed": [e.name for e in result.expectations if not e.ok],
    }


def run_suite(
    files: Iterable[Path], seeds: int, controllers: Sequence[str] = CONTROLLERS, on_run: Callable[[str], None] | None = None,
    runs_log: Path | None = None, resume: bool = False, stop: StopSignal | None = None,
) -> SuiteProgress:
    """Every scenario × seed × controller, no per-frame files; one row per finished run.

    With ``runs_log`` each finished run is appended to it as a flushed JSON line (so an interrupted
    suite keeps every finished run); with ``resume`` the runs already in it are skipped. A run cut
    short by ``stop`` is not a result: it is left out, and the suite stops there.
    """
    if not (isinstance(seeds, int) and seeds >= 1):
        raise ValueError(f"seeds must be a whole number >= 1, got {seeds!r}")
    plan = [(path, k, controller) for path in files for k in range(seeds) for controller in controllers]
    done = _finished_runs(runs_log) if (resume and runs_log is not None) else []
    keys = {(r["scenario"], r["seed"], r["controller"]) for r in done}
    rows, resumed = list(done), len(done)
    log = JsonlLog(runs_log) if runs_log is not None else None  # rewritten: the resumed rows, then each new one
    scenarios: dict[Path, Scenario] = {}
    try:
        for row in done if log is not None else ():
            log.write(row)
        for path, k, controller in plan:
            if stop:
                break
            if path not in scenarios:
                scenarios[path] = load_scenario(path)
            scenario = scenarios[path]
            seed = scenario.seed + k
            if (scenario.name, seed, controller) in keys:
                continue
            result = run_scenario(scenario, seed, controller, stop=stop)
            if result.interrupted:
                break
            row = suite_row(result)
            rows.append(row)
            if log is not None:
                log.write(row)
            if on_run is not None:
                on_run(f"{scenario.name} seed {seed} {controller}: {'pass' if result.passed else 'FAIL'}")
    finally:
        if log is not None:
            log.close()
    return SuiteProgress(rows, len(plan), resumed, bool(stop), stop.name if stop else None)


def _finished_runs(path: Path) -> list[dict[str, Any]]:
    """The rows of an earlier suite's runs.jsonl (a torn last line from a killed suite is left out)."""
    if not path.is_file():
        return []
    return [r for r in read_jsonl(path) if isinstance(r, dict) and {"scenario", "seed", "controller", "passed"} <= r.keys()]


def suite_table(rows: Sequence[dict[str, Any]]) -> list[dict[str, Any]]:
    """Per scenario and controller: runs, failed runs, collisions, lane departures, mean speed, emergency entries."""
    table: dict[tuple[str, str], dict[str, Any]] = {}
    for r in rows:
        t = table.setdefault((r["scenario"], r["controller"]), {"scenario": r["scenario"], "controller": r["controller"], "runs": 0,
                                                                 "failed": 0, "collisions": 0, "lane_departures": 0,
                                                                 "speeds": [], "emergency_entries": 0})
        t["runs"] += 1
        t["failed"] += not r["passed"]
        t["collisions"] += r["collisions"]
        t["lane_departures"] += r["lane_departures"]
        t["emergency_entries"] += r["emergency_entries"]
        if r["mean_speed_mps"] is not None:
            t["speeds"].append(r["mean_speed_mps"])
    out = []
    for t in table.values():
        speeds = t.pop("speeds")
        t["mean_speed_mps"] = float(np.mean(speeds)) if speeds else None
        out.append(t)
    return out


def suite_markdown(rows: Sequence[dict[str, Any]], controllers: Sequence[str] = CONTROLLERS) -> str:
    """The comparison table: one line per scenario, for each controller 'failed/runs, collisions, departures, speed'."""
    table = {(t["scenario"], t["controller"]): t for t in suite_table(rows)}
    scenarios = list(dict.fromkeys(r["scenario"] for r in rows))
    head = "| scenario | " + " | ".join(controllers) + " |"
    lines = [head, "|" + "---|" * (len(controllers) + 1)]
    for name in scenarios:
        cells = []
        for c in controllers:
            t = table.get((name, c))
            if t is None:
                cells.append("–")
                continue
            speed = f"{t['mean_speed_mps']:.2f} m/s" if t["mean_speed_mps"] is not None else "–"
            verdict = "pass" if t["failed"] == 0 else f"**{t['failed']}/{t['runs']} fail**"
            cells.append(f"{verdict}; coll {t['collisions']}, dep {t['lane_departures']}, emerg {t['emergency_entries']}, {speed}")
        lines.append(f"| {name} | " + " | ".join(cells) + " |")
    return "\n".join(lines) + "\n"
