"""The Duckietown suite: development lane maps guarded / unguarded / expert, obstacles, domain randomisation.

Rows are written as they finish (suite.json, suite.md), so an interrupted suite keeps its rows. The
criteria of issue 14 are checked at the end from the rows:
- lane maps, guarded, 0.2 m/s: no departure, no collision, progress ≥ 90 % of the expert's;
- a duck or cone in the lane, no range sensor: stops before contact, goes on once it is removed;
- domain randomisation over the seeds of one lane map: no collision, no departure, progress ≥ 80 %.
"""

from __future__ import annotations

from collections.abc import Callable, Sequence
from dataclasses import asdict, fields, replace
from pathlib import Path
from typing import Any

from fearguard.drive.plan import RunSpec
from fearguard.drive.suite import Executor, compared_with_experts, run_plan_with_tables, suite_text
from fearguard.worlds.duckietown.drive import DriveOptions, drive
from fearguard.worlds.duckietown.report import suite_markdown

LANE_MAPS = ("loop_empty", "small_loop", "zigzag_dists", "straight_road")
DOMAIN_RAND_MAP = "loop_empty"
LANE_PROGRESS_SHARE = 0.9  # [-] of the expert's progress, guarded on a lane map
DOMAIN_RAND_PROGRESS_SHARE = 0.8  # [-] likewise under domain randomisation
OBSTACLE_SECONDS = 30.0  # [s] an obstacle drive: approach, stop, wait, go on
OBSTACLE_RUNS = (  # (name, map, obstacle, range sensor, controller): 1 m ahead on a straight, and on loop_empty's first curve
    ("straight_road + duck", "straight_road", "duck", "none", "guarded"),
    ("straight_road + duck", "straight_road", "duck", "none", "unguarded"),
    ("straight_road + duck, ToF", "straight_road", "duck", "tof", "guarded"),
    ("straight_road + cone", "straight_road", "cone", "none", "guarded"),
    ("loop_empty + duck on the curve", "loop_empty", "duck", "none", "guarded"),
)


def plan(seconds: float, seeds: int, maps: Sequence[str] | None = None, rand_seconds: float | None = None,
         out_dir: str | Path | None = None) -> list[RunSpec]:
    """Every drive of the suite as rows, experts first (the other rows are compared to them); randomised drives last
    ``rand_seconds``. ``out_dir``: each drive writes its folder (log, summary, plots) there, named by absolute path (a
    Dask worker started in another folder writes it in the same place)."""
    base = DriveOptions(seconds=seconds, plots=True)
    runs: list[tuple[str, DriveOptions]] = []
    for m in maps or LANE_MAPS:
        runs += [(m, replace(base, map_name=m, controller=c)) for c in ("expert", "guarded", "unguarded")]
    for name, m, obstacle, sensor, controller in OBSTACLE_RUNS:
        runs.append((name, replace(base, map_name=m, obstacle=obstacle, range_sensor=sensor, controller=controller,
                                   seconds=min(seconds, OBSTACLE_SECONDS))))
    for seed in range(seeds):
        for c in ("expert", "guarded"):
            options = replace(base, map_name=DOMAIN_RAND_MAP, domain_rand=True, seed=seed, controller=c, seconds=rand_seconds or seconds)
            runs.append((f"{DOMAIN_RAND_MAP} rand {seed}", options))
    folder = (lambda name, o: str(_folder(Path(out_dir).resolve(), name, o))) if out_dir is not None else (lambda name, o: None)
    return [RunSpec("duckietown", name, o.controller, o.seed, {**_options_json(o), "folder": folder(name, o)}) for name, o in runs]


def _options_json(options: DriveOptions) -> dict[str, Any]:
    return {k: list(v) if isinstance(v, tuple) else v for k, v in asdict(options).items()}


def options_of(spec: RunSpec) -> DriveOptions:
    """The DriveOptions a row names."""
    known = {f.name for f in fields(DriveOptions)}
    values = {k: (tuple(v) if isinstance(v, list) else v) for k, v in spec.options.items() if k in known}
    return DriveOptions(**values)


def run_row(spec: RunSpec, stop: object = None) -> dict[str, Any]:
    """One drive of the suite (its folder written when the plan names one): the raw row; ``merge`` compares it with the
    expert's. (A drive stops on Ctrl-C only, not on a stop signal: it is short.)"""
    options = options_of(spec)
    folder = spec.options.get("folder")
    summary = drive(options, folder).summary
    return {**_raw_row(spec.name, options, summary), "interrupted": bool(summary.get("interrupted"))}


def _raw_row(name: str, options: DriveOptions, s: dict[str, Any]) -> dict[str, Any]:
    """A drive's row before it is compared with the expert's (``merge`` adds ``progress_vs_expert_pct``)."""
    timing = s.get("timing", {})
    return {
        "run": name, "controller": options.controller, "map": options.map_name, "seed": options.seed, "domain_rand": options.domain_rand,
        "obstacle_kind": options.obstacle, "range_sensor": options.range_sensor,
        "progress_m": s["progress_m"], "progress_vs_expert_pct": None,
        "departures": s["departures"], "centre_line_crossings": s["centre_line_crossings"], "collisions": s["collisions"],
        "invalid_pose": s["invalid_pose"], "emergency_s": s["time_in_mode_s"]["EMERGENCY"], "lane_offset_rms_m": s.get("lane_offset_rms_m"),
        "lane_offset_max_m": s.get("lane_offset_max_m"), "marking_share": s["marking_share"], "obstacle": s.get("obstacle"),
        "controller_ms": timing.get("controller_ms_median"), "simulator_ms": timing.get("simulator_ms_median"),
    }


def criteria(rows: Sequence[dict[str, Any]]) -> list[dict[str, Any]]:
    """Issue 14's Done-when criteria, each with ok and the numbers behind it."""
    out = []
    lane = [r for r in rows if r["controller"] == "guarded" and r["obstacle_kind"] is None and not r["domain_rand"]]
    for r in lane:
        share = (r["progress_vs_expert_pct"] or 0) / 100
        ok = r["departures"] == 0 and r["collisions"] == 0 and not r["invalid_pose"] and share >= LANE_PROGRESS_SHARE
        out.append({"criterion": f"{r['run']}: no departure, no collision, progress >= 90 % of the expert's", "ok": ok,
                    "detail": f"departures {r['departures']}, collisions {r['collisions']}, invalid pose {r['invalid_pose']}, "
                              f"progress {100 * share:.0f} %"})
    for r in rows:
        if r["obstacle_kind"] is not None and r["controller"] == "guarded" and r["range_sensor"] == "none":
            ob = r["obstacle"] or {}
            ok = bool(ob.get("stopped_before_contact")) and bool(ob.get("went_on"))
            out.append({"criterion": f"{r['run']}, no range sensor: stops before contact, goes on once removed", "ok": ok,
                        "detail": f"contact {ob.get('contact')}, stopped before contact {ob.get('stopped_before_contact')}, "
                                  f"went on {ob.get('went_on')}"})
    rand = [r for r in rows if r["controller"] == "guarded" and r["domain_rand"]]
    if rand:
        bad = [r["run"] for r in rand if r["departures"] or r["collisions"] or r["invalid_pose"]
               or (r["progress_vs_expert_pct"] or 0) < 100 * DOMAIN_RAND_PROGRESS_SHARE]
        shares = [r["progress_vs_expert_pct"] or 0 for r in rand]
        out.append({"criterion": f"{DOMAIN_RAND_MAP}, domain randomisation, {len(rand)} seeds: no collision, no departure, "
                                 "progress >= 80 %", "ok": not bad,
                    "detail": f"failing seeds: {', '.join(bad) or 'none'}; progress {min(shares):.0f}–{max(shares):.0f} % of the expert's"})
    return out


def _folder(out: Path, name: str, options: DriveOptions) -> Path:
    return out / f"{name.replace(' ', '_').replace(',', '').replace('+', 'with')}_{options.controller}_{options.range_sensor}"


def merge(rows: Sequence[dict[str, Any]]) -> tuple[list[dict[str, Any]], list[dict[str, Any]], str]:
    """The rows compared with the expert's progress on the same run, the criteria, and the markdown (table, cost line,
    PASS/FAIL per criterion)."""
    merged = compared_with_experts(rows, lambda r: r["obstacle_kind"] is None)
    checks = criteria(merged)
    markdown = suite_text(suite_markdown(merged), merged, checks)
    return merged, checks, markdown


def run_suite(out_dir: str | Path, seconds: float = 60.0, seeds: int = 10, maps: Sequence[str] | None = None,
              rand_seconds: float | None = None, executor: Executor | None = None, on_run: Callable[[str], None] | None = None,
              resume: bool = False, on_progress: Callable[[int, int], None] | None = None,
              on_row: Callable[[dict[str, Any]], None] | None = None) -> str:
    """The plan through the one suite (``drive/suite.py``; ``executor``: e.g. ``cluster.DaskExecutor(jobs=2)``, two
    drives at a time, each in its own worker process); runs.jsonl grows a row per drive, suite.md / suite.json are
    rewritten after every drive. Returns the markdown."""
    out = Path(out_dir)
    specs = plan(seconds, seeds, maps, rand_seconds, out)

    def said(row: dict[str, Any]) -> None:
        if on_row is not None:
            on_row(row)
        if on_run is not None:
            on_run(f"{row['run']} {row['controller']}: progress {row['progress_m']:.2f} m, departures {row['departures']}, "
                   f"collisions {row['collisions']}, EMERGENCY {row['emergency_s']:.1f} s")

    _, markdown = run_plan_with_tables(specs, out, merge, resume=resume, executor=executor, on_row=said, on_progress=on_progress)
    return markdown
