"""Files of a scenario run, and the suite: every scenario × seeds × (guarded + baselines) in one table.

``run_to_folder`` writes log.jsonl (flushed per frame), summary.json, timeline.png, trajectory.png and
(optionally) the annotated video. ``run_suite`` runs without per-frame files and returns rows for the table,
appending each finished run to runs.jsonl as it goes (an interrupted suite resumes from it);
``suite_markdown`` renders them: outcomes for every controller (guarded vs unguarded vs crisp vs aeb:
outcome failures, collisions, lane departures, route completion, speed, first stop; totals with false
alarms on the hazard-free scenarios), and apart from them the supervisor-only checks, which a baseline
cannot be judged by.
"""

from __future__ import annotations

from collections.abc import Callable, Iterable, Sequence
from dataclasses import replace
from pathlib import Path
from typing import TYPE_CHECKING, Any

import numpy as np

from fearguard.drive.interrupt import StopSignal
from fearguard.drive.plan import RunSpec
from fearguard.drive.suite import Executor, PlanResult, run_plan
from fearguard.errors import ScenarioError
from fearguard.outputs.recorder import SUMMARY_NAME, write_json
from fearguard.outputs.timeline import plot_timeline
from fearguard.sim.loop import CONTROLLERS, RunResult, run_scenario
from fearguard.sim.metrics import Row
from fearguard.sim.road import Road
from fearguard.sim.scenario import BUNDLED, Scenario, load_scenario

if TYPE_CHECKING:
    from matplotlib.figure import Figure

BENIGN = ("clear_straight", "s_curves")  # scenarios without a hazard: the false-alarm check


def scenario_files(folder: str | Path | None = None) -> list[Path]:
    """The *.toml scenarios of a folder (default: the bundled library), sorted by name; a folder that is missing or
    holds none is a ScenarioError (a listing that prints nothing would look like success)."""
    where = Path(folder or BUNDLED)
    if not where.is_dir():
        raise ScenarioError(where, "folder", "no such folder; give a folder of scenario files (*.toml)")
    found = sorted(where.glob("*.toml"))
    if not found:
        raise ScenarioError(where, "folder", "holds no scenario files (*.toml); `fearguard scenarios` lists the bundled ones")
    return found


def run_to_folder(
    scenario: Scenario, out: Path, seed: int | None = None, controller: str = "guarded", video: bool = False,
    on_frame: Callable[[int, int], None] | None = None, stop: StopSignal | None = None, mcap: bool = False,
    track: str | None = None,
) -> RunResult:
    """One run with every file a person looks at (``mcap``: run.mcap too; ``track``: a track profile for the supervisor);
    the summary is on disk before the plots are drawn.

    A stop signal during the plots skips the plots not yet drawn and marks the summary interrupted.
    """
    out.mkdir(parents=True, exist_ok=True)
    result = run_scenario(scenario, seed, controller, out, video=video, on_frame=on_frame, stop=stop, mcap=mcap, track=track)
    write_json(out / SUMMARY_NAME, result.to_json())
    if result.rows:
        title = f"{scenario.name} ({controller}, seed {result.seed})"
        plots: list[Callable[[], object]] = [lambda: plot_trajectory(scenario, result.rows, out / "trajectory.png", title)]
        if controller == "guarded" and result.trace is not None:
            plots.insert(0, lambda: plot_timeline(result.trace, out / "timeline.png", title=title, with_speed=True, rules=result.rules))
        for draw in plots:
            if stop:
                break
            draw()
        if stop and not result.interrupted:  # the frames were all run; the plots were cut short
            result = replace(result, interrupted=True, stopped_by=stop.name)
            write_json(out / SUMMARY_NAME, result.to_json())
    return result


MODE_COLOURS = {"NORMAL": "tab:green", "CAUTION": "tab:orange", "EMERGENCY": "tab:red", None: "tab:blue"}  # None: unsupervised


def plot_trajectory(scenario: Scenario, rows: Sequence[Row], path: Path, title: str) -> None:
    """``trajectory_figure`` as a PNG at ``path``."""
    trajectory_figure(scenario, rows, title).savefig(path, dpi=90, pil_kwargs={"compress_level": 1})  # a fast deflate


def trajectory_figure(scenario: Scenario, rows: Sequence[Row], title: str) -> Figure:
    """The run along the road: the car's offset from the lane centre over the distance driven, coloured by mode, with
    the lane's edges, the static obstacles, the collision and the lane departures; on a road that bends, its top-down
    map below. (Top-down alone, a 25 m road with a 0.4 m lane is a short stroke in an empty square.)"""
    from matplotlib.figure import Figure

    road = Road(scenario.road)
    half = scenario.road.lane_width_m / 2
    cx, cy = road.point_at(np.linspace(0.0, road.length_m, 400), 0.0)
    span = max(float(np.ptp(cx)), float(np.ptp(cy)), 1e-9)
    bends = min(float(np.ptp(cx)), float(np.ptp(cy))) > 0.1 * span  # a straight road's map says nothing the strip does not
    height_in, heights, top, bottom = (9.5, (1, 1.5), 0.95, 0.06) if bends else (5, (1,), 0.92, 0.1)
    fig = Figure(figsize=(11, height_in))
    along, *rest = fig.subplots(len(heights), 1, squeeze=False, height_ratios=heights)[:, 0]
    fig.subplots_adjust(left=0.08, right=0.8, top=top, bottom=bottom, hspace=0.25)
    s = np.array([r.s_m for r in rows])
    lat = np.array([r.lateral_m for r in rows])
    along.axhspan(-half, half, color="0.94", lw=0)
    for edge in (-half, half):
        along.axhline(edge, color="grey", lw=1)
    modes = [r.mode for r in rows]
    for mode, colour in MODE_COLOURS.items():
        mine = np.array([m == mode for m in modes])
        if mine.any():
            along.scatter(s[mine], lat[mine], s=5, color=colour, label=mode or "no supervisor", zorder=3)
    out = np.array([not r.in_lane for r in rows])
    if out.any():
        along.scatter(s[out], lat[out], s=18, facecolors="none", edgecolors="m", label="outside the lane", zorder=4)
    hit = next((r for r in rows if r.collided), None)
    if hit is not None:
        along.plot(hit.s_m, hit.lateral_m, "kx", ms=12, mew=3, label="collision", zorder=5)
    if scenario.obstacles:
        along.plot([o.s_m for o in scenario.obstacles], [o.lateral_m for o in scenario.obstacles], "ks", ms=7, label="obstacle")
    reach = max([2.5 * half, *(1.15 * abs(v) for v in lat), *(1.3 * abs(o.lateral_m) for o in scenario.obstacles)])
    along.set(xlim=(0.0, road.length_m), ylim=(-reach, reach), xlabel="distance along the road (m)",
              ylabel="offset from the lane centre (m, + left)")
    along.legend(loc="upper left", bbox_to_anchor=(1.01, 1.0), borderaxespad=0.0, fontsize="small", frameon=False)
    if rest:
        _draw_map(rest[0], scenario, road, rows, hit)
    fig.suptitle(title)
    return fig


def _draw_map(ax: Any, scenario: Scenario, road: Road, rows: Sequence[Row], hit: Row | None) -> None:
    """The top-down panel of ``trajectory_figure``: the lane's edges, the path coloured by mode, obstacles, collision."""
    half = scenario.road.lane_width_m / 2
    s = np.linspace(0.0, road.length_m, 400)
    for edge in (-half, half):
        ax.plot(*road.point_at(s, edge), color="grey", lw=1)
    for mode, colour in MODE_COLOURS.items():
        mine = [r for r in rows if r.mode == mode]
        if mine:
            ax.scatter([r.x_m for r in mine], [r.y_m for r in mine], s=4, color=colour, zorder=3)
    if hit is not None:
        ax.plot(hit.x_m, hit.y_m, "kx", ms=12, mew=3, zorder=5)
    for ob in scenario.obstacles:
        ax.plot(*road.point_at(ob.s_m, ob.lateral_m), "ks", ms=7)
    ax.set_aspect("equal", adjustable="datalim")
    ax.set(xlabel="x (m)", ylabel="y (m)", title="top-down")


SuiteProgress = PlanResult  # what ``run_suite`` returns: every row (resumed and new), the plan's size, cut short or not


def suite_row(result: RunResult, route_m: float | None = None) -> dict[str, Any]:
    """One run's line in runs.jsonl and in the table: outcome metrics for every controller, the checks apart.

    ``failed``: outcome expectations that failed (collision, departure, speed, gap...), for every controller;
    ``supervisor_failed``: supervisor-only expectations that failed (guarded runs; a baseline has none to fail);
    ``not_applicable``: supervisor-only expectations a baseline cannot be judged by. ``route_completion``: the
    share of the route driven (``route_m``: its length); ``first_stop_t_s``: when the car first stood still.
    """
    m = result.metrics
    stops = [s.t_s for s in m.stops if s.t_s > 0.0]  # a car that starts at rest has not "stopped" at t = 0
    return {
        "scenario": result.scenario, "controller": result.controller, "seed": result.seed, "passed": result.passed,
        "collisions": m.collisions, "lane_departures": m.lane_departures, "mean_speed_mps": m.mean_speed_mps,
        "distance_m": m.distance_m, "route_completion": (min(1.0, max(0.0, m.final_s_m / route_m))
                                                         if route_m and m.final_s_m is not None else None),
        "first_stop_t_s": stops[0] if stops else None, "emergency_entries": m.emergency_entries,
        "emergency_s": m.time_in_mode_s.get("EMERGENCY", 0.0),
        "failed": [e.name for e in result.expectations if e.failed and e.outcome],
        "supervisor_failed": [e.name for e in result.expectations if e.failed and not e.outcome],
        "supervisor_checks": [e.name for e in result.expectations if not e.outcome],
        "not_applicable": [e.name for e in result.expectations if e.ok is None],
    }


def plan(files: Iterable[Path], seeds: int, controllers: Sequence[str] = CONTROLLERS) -> list[RunSpec]:
    """Every scenario × seed × controller, as rows: the seeds are each scenario's own seed and the ones after it. The
    scenario files are named by absolute path: a Dask worker started in another folder reads the same file."""
    if not (isinstance(seeds, int) and seeds >= 1):
        raise ValueError(f"seeds must be a whole number >= 1, got {seeds!r}")
    specs = []
    for path in files:
        scenario = load_scenario(path)
        file = str(Path(path).resolve())
        specs += [RunSpec("sim", scenario.name, c, scenario.seed + k, {"file": file}) for k in range(seeds) for c in controllers]
    return specs


def run_row(spec: RunSpec, stop: StopSignal | None = None) -> dict[str, Any]:
    """One run of the simulator's suite, no per-frame files: its row (``"interrupted": true`` if ``stop`` cut it short).
    The options may change numbers of the rules (``"policy"``) and of the supervisor's vehicle (``"vehicle"``): a sweep."""
    scenario = load_scenario(spec.options["file"])
    result = run_scenario(scenario, spec.seed, spec.controller, stop=stop, policy=spec.options.get("policy"),
                          vehicle=spec.options.get("vehicle"))
    if result.interrupted:
        return {"interrupted": True}
    return suite_row(result, Road(scenario.road).length_m)


def row_line(row: dict[str, Any]) -> str:
    """One finished run in a line: ``night seed 3 guarded: pass``."""
    return f"{row['scenario']} seed {row['seed']} {row['controller']}: {'pass' if row['passed'] else 'FAIL'}"


def run_suite(
    files: Iterable[Path], seeds: int, controllers: Sequence[str] = CONTROLLERS, on_run: Callable[[str], None] | None = None,
    runs_log: Path | None = None, resume: bool = False, stop: StopSignal | None = None,
    on_progress: Callable[[int, int], None] | None = None, executor: Executor | None = None,
    on_row: Callable[[dict[str, Any]], None] | None = None,
) -> SuiteProgress:
    """Every scenario × seed × controller through the one suite (``drive/suite.py``): a row per finished run, appended to
    ``runs_log`` as it finishes; ``resume`` skips the runs already there; ``executor`` runs the rows (None: in this
    process, one after the other; ``cluster.DaskExecutor``: on Dask's workers)."""

    def said(row: dict[str, Any]) -> None:
        if on_row is not None:
            on_row(row)
        if on_run is not None:
            on_run(row_line(row))

    return run_plan(plan(files, seeds, controllers), runs_log=runs_log, resume=resume, stop=stop, on_row=said,
                    on_progress=on_progress, executor=executor)


def suite_table(rows: Sequence[dict[str, Any]]) -> list[dict[str, Any]]:
    """Per scenario and controller: runs, outcome failures, supervisor-check failures, collisions, departures,
    distance (summed), route completion, first stop, mean speed, emergency entries (rows of an older runs.jsonl count
    what they hold)."""
    table: dict[tuple[str, str], dict[str, Any]] = {}
    for r in rows:
        t = table.setdefault((r["scenario"], r["controller"]), {
            "scenario": r["scenario"], "controller": r["controller"], "runs": 0, "failed": 0, "supervisor_failed": 0,
            "supervisor_checks": r.get("supervisor_checks", []), "collisions": 0, "lane_departures": 0, "emergency_entries": 0,
            "false_alarm_runs": 0, "distance_m": 0.0, "speeds": [], "completion": [], "stops": []})
        t["runs"] += 1
        t["failed"] += bool(r["failed"]) if "supervisor_failed" in r else not r["passed"]
        t["supervisor_failed"] += bool(r.get("supervisor_failed"))
        t["collisions"] += r["collisions"]
        t["lane_departures"] += r["lane_departures"]
        t["emergency_entries"] += r["emergency_entries"]
        t["distance_m"] += r.get("distance_m") or 0.0
        t["false_alarm_runs"] += r["scenario"] in BENIGN and bool(r["emergency_entries"] or r.get("first_stop_t_s") is not None)
        for key, values in (("mean_speed_mps", "speeds"), ("route_completion", "completion"), ("first_stop_t_s", "stops")):
            if r.get(key) is not None:
                t[values].append(r[key])
    out = []
    for t in table.values():
        speeds, completion, stops = t.pop("speeds"), t.pop("completion"), t.pop("stops")
        t["mean_speed_mps"] = float(np.mean(speeds)) if speeds else None
        t["route_completion"] = float(np.mean(completion)) if completion else None
        t["stopped_runs"], t["mean_first_stop_t_s"] = len(stops), (float(np.mean(stops)) if stops else None)
        out.append(t)
    return out


def suite_totals(rows: Sequence[dict[str, Any]], controllers: Sequence[str] = CONTROLLERS) -> list[dict[str, Any]]:
    """Per controller over every scenario: runs, outcome failures, collisions, departures, route completion, false alarms,
    and progress: the distance driven as a share of the unguarded car's over the same runs."""
    table = suite_table(rows)
    unguarded = sum(t["distance_m"] for t in table if t["controller"] == "unguarded")
    out = []
    for c in controllers:
        mine = [t for t in table if t["controller"] == c]
        if not mine:
            continue
        completion = [t["route_completion"] for t in mine if t["route_completion"] is not None]
        benign = sum(t["runs"] for t in mine if t["scenario"] in BENIGN)
        out.append({"controller": c, "runs": sum(t["runs"] for t in mine), "failed": sum(t["failed"] for t in mine),
                    "collisions": sum(t["collisions"] for t in mine), "lane_departures": sum(t["lane_departures"] for t in mine),
                    "route_completion": float(np.mean(completion)) if completion else None,
                    "progress": sum(t["distance_m"] for t in mine) / unguarded if unguarded > 0 else None,
                    "false_alarm_runs": sum(t["false_alarm_runs"] for t in mine), "benign_runs": benign,
                    "supervisor_failed": sum(t["supervisor_failed"] for t in mine) if c == "guarded" else None})
    return out


def _percent(share: float | None) -> str:
    return f"{100 * share:.0f} %" if share is not None else "–"


def _outcome_cell(t: dict[str, Any] | None) -> str:
    if t is None:
        return "–"
    verdict = "pass" if t["failed"] == 0 else f"**{t['failed']}/{t['runs']} fail**"
    speed = f"{t['mean_speed_mps']:.2f} m/s" if t["mean_speed_mps"] is not None else "–"
    stop = f", stop {t['mean_first_stop_t_s']:.1f} s" if t["mean_first_stop_t_s"] is not None else ""
    return f"{verdict}; coll {t['collisions']}, dep {t['lane_departures']}, {t['distance_m'] / t['runs']:.1f} m, {speed}{stop}"


def suite_markdown(rows: Sequence[dict[str, Any]], controllers: Sequence[str] = CONTROLLERS) -> str:
    """The comparison: outcomes for every controller (one line per scenario, then totals), the supervisor-only checks apart.

    Outcome cell: runs failing an outcome expectation, collisions, lane departures, mean distance driven, mean
    speed and the mean time of the first stop (runs that stopped). The supervisor checks (modes, strategies, emergency
    counts) judge fearguard's modes: guarded only, n/a for the baselines.
    """
    table = {(t["scenario"], t["controller"]): t for t in suite_table(rows)}
    scenarios = list(dict.fromkeys(r["scenario"] for r in rows))
    lines = ["| scenario | " + " | ".join(controllers) + " |", "|" + "---|" * (len(controllers) + 1)]
    lines += [f"| {name} | " + " | ".join(_outcome_cell(table.get((name, c))) for c in controllers) + " |" for name in scenarios]
    lines += ["", "| controller | runs | outcome failures | collisions | lane departures | progress (of unguarded) | route completion "
              f"| false alarms ({', '.join(BENIGN)}) |", "|---|---|---|---|---|---|---|---|"]
    for t in suite_totals(rows, controllers):
        alarms = f"{t['false_alarm_runs']}/{t['benign_runs']} runs" if t["benign_runs"] else "–"
        lines.append(f"| {t['controller']} | {t['runs']} | {t['failed']} | {t['collisions']} | {t['lane_departures']} | "
                     f"{_percent(t['progress'])} | {_percent(t['route_completion'])} | {alarms} |")
    checked = [(name, table[(name, "guarded")]) for name in scenarios
               if (name, "guarded") in table and table[(name, "guarded")]["supervisor_checks"]]
    if checked:
        lines += ["", "| scenario | supervisor-only checks (guarded; n/a for baselines) | guarded |", "|---|---|---|"]
        for name, t in checked:
            verdict = "pass" if t["supervisor_failed"] == 0 else f"**{t['supervisor_failed']}/{t['runs']} fail**"
            lines.append(f"| {name} | {', '.join(t['supervisor_checks'])} | {verdict} |")
    return "\n".join(lines) + "\n"
