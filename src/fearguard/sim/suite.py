"""Files of a scenario run, and the suite: every scenario × seeds × (guarded + baselines) in one table.

``run_to_folder`` writes log.jsonl (flushed per frame), summary.json, timeline.png, trajectory.png and
(optionally) annotated.mp4. ``run_suite`` runs without per-frame files and returns rows for the table;
``suite_markdown`` renders them (guarded vs unguarded vs crisp vs aeb: failures, collisions, lane
departures, mean speed, emergency entries).
"""

from __future__ import annotations

import json
from collections.abc import Callable, Iterable, Sequence
from pathlib import Path
from typing import Any

import numpy as np

from fearguard.report import json_value, plot_timeline, read_jsonl
from fearguard.sim.loop import CONTROLLERS, RunResult, run_scenario
from fearguard.sim.road import Road
from fearguard.sim.scenario import Scenario, load_scenario

BUNDLED = Path(__file__).resolve().parents[1] / "scenarios"
BENIGN = ("clear_straight", "s_curves")  # scenarios without a hazard: the false-alarm check


def scenario_files(folder: str | Path | None = None) -> list[Path]:
    """The *.toml scenarios of a folder (default: the bundled library), sorted by name."""
    return sorted(Path(folder or BUNDLED).glob("*.toml"))


def run_to_folder(
    scenario: Scenario, out: Path, seed: int | None = None, controller: str = "guarded", video: bool = False,
    on_frame: Callable[[int, int], None] | None = None,
) -> RunResult:
    """One run with every file a person looks at."""
    out.mkdir(parents=True, exist_ok=True)
    result = run_scenario(scenario, seed, controller, out / "log.jsonl", out / "annotated.mp4" if video else None, on_frame)
    summary = {"scenario": scenario.name, "controller": controller, "seed": result.seed, "frames": result.frames,
               "interrupted": result.interrupted, "passed": result.passed, "expectations": result.expectations, **result.summary}
    (out / "summary.json").write_text(json.dumps(json_value(summary), indent=2, allow_nan=False) + "\n", encoding="utf-8")
    records = read_jsonl(out / "log.jsonl")
    if records:
        title = f"{scenario.name} ({controller}, seed {result.seed})"
        if controller == "guarded":
            plot_timeline(records, out / "timeline.png", title=title, extra_speed="speed_mps")
        plot_trajectory(scenario, records, out / "trajectory.png", title)
    return result


def plot_trajectory(scenario: Scenario, records: Sequence[dict[str, Any]], path: Path, title: str) -> None:
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
    xs = [r["x_m"] for r in records]
    ys = [r["y_m"] for r in records]
    ax.scatter(xs, ys, s=4, c=[colours.get(r.get("mode"), "tab:blue") for r in records])
    for r in records:
        if r.get("collided"):
            ax.plot(r["x_m"], r["y_m"], "kx", ms=12, mew=3)
            break
    out_of_lane = [(r["x_m"], r["y_m"]) for r in records if r.get("in_lane") is False]
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


def run_suite(
    files: Iterable[Path], seeds: int, controllers: Sequence[str] = CONTROLLERS, on_run: Callable[[str], None] | None = None,
) -> list[dict[str, Any]]:
    """Every scenario × seed × controller, no per-frame files; one row per run."""
    rows = []
    for path in files:
        scenario = load_scenario(path)
        for k in range(seeds):
            seed = scenario.seed + k
            for controller in controllers:
                result = run_scenario(scenario, seed, controller)
                s = result.summary
                rows.append({
                    "scenario": scenario.name, "controller": controller, "seed": seed, "passed": result.passed,
                    "collisions": s.get("collisions", 0), "lane_departures": s.get("lane_departures", 0),
                    "mean_speed_mps": s.get("mean_speed_mps"), "emergency_entries": s.get("emergency_entries", 0),
                    "failed": [e["name"] for e in result.expectations if not e["ok"]],
                })
                if on_run is not None:
                    on_run(f"{scenario.name} seed {seed} {controller}: {'pass' if result.passed else 'FAIL'}")
    return rows


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
