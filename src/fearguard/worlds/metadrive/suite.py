"""The MetaDrive suite: development seeds guarded / unguarded / expert by day, a stopped car in the lane, night.

A plan of rows (``drive/plan.py``) run by the one suite (``drive/suite.py``: runs.jsonl grows a row per drive, an
interrupted suite resumes); ``merge`` compares each drive with the expert's on the same run and checks issue 38's
Done-when criteria:
- day, a straight-and-curves map (SCSC), 3 lanes, light traffic (0.05), guarded: 0 crashes, 0 out of road,
  progress ≥ 90 % of MetaDrive's expert (its IDM policy) on the same seed;
- a stopped car in the ego's lane: no contact, stopped for, then passed or waited behind;
- night: no crash, progress ≥ 60 % of the expert's.
Seeds 5000-5999 are the independent test set (../shared/TEST-SET.md): the development seeds are others (a judge may
run the suite on them: nothing refuses them).
"""

from __future__ import annotations

from collections.abc import Callable, Sequence
from dataclasses import asdict, fields, replace
from pathlib import Path
from typing import Any

from fearguard.drive.interrupt import StopSignal
from fearguard.drive.plan import RunSpec
from fearguard.drive.suite import Executor, compared_with_experts, run_plan_with_tables, suite_text
from fearguard.worlds.metadrive.drive import DriveOptions, drive
from fearguard.worlds.metadrive.report import suite_markdown

DEV_SEEDS = tuple(range(10))  # development seeds (the test set is 5000-5999)
DAY_PROGRESS_SHARE = 0.9  # [-] of the expert's progress, guarded by day
NIGHT_PROGRESS_SHARE = 0.6  # [-] likewise at night
CONTROLLERS = ("expert", "guarded", "unguarded")  # experts first: the other rows are compared with them


def plan(seeds: Sequence[int] = DEV_SEEDS[:3], seconds: float = 30.0, stopped_seeds: Sequence[int] = (0,),
         night_seeds: Sequence[int] = (0,), out_dir: str | Path | None = None, base: DriveOptions | None = None,
         controllers: Sequence[str] = CONTROLLERS) -> list[RunSpec]:
    """Every drive of the suite as rows: per day seed ``controllers`` (default expert / guarded / unguarded; the
    expert always, first); per stopped-car seed expert and guarded; per night seed expert and guarded. ``base``: the
    day drive (default SCSC, 3 lanes, traffic 0.05)."""
    day = replace(base or DriveOptions(), seconds=seconds, plots=True)
    runs: list[tuple[str, DriveOptions]] = []
    for seed in seeds:
        runs += [(f"day {seed}", replace(day, seed=seed, controller=c)) for c in CONTROLLERS if c == "expert" or c in controllers]
    for seed in stopped_seeds:
        runs += [(f"stopped car {seed}", replace(day, seed=seed, controller=c, lead="stopped")) for c in ("expert", "guarded")]
    for seed in night_seeds:
        runs += [(f"night {seed}", replace(day, seed=seed, controller=c, lighting="night")) for c in ("expert", "guarded")]
    root = Path(out_dir) if out_dir is not None else None
    return [RunSpec("metadrive", name, o.controller, o.seed,
                    {**asdict(o), "folder": str(root / f"{name.replace(' ', '_')}_{o.controller}") if root else None})
            for name, o in runs]


def options_of(spec: RunSpec) -> DriveOptions:
    """The DriveOptions a row names."""
    known = {f.name for f in fields(DriveOptions)}
    return DriveOptions(**{k: v for k, v in spec.options.items() if k in known})


def run_row(spec: RunSpec, stop: StopSignal | None = None) -> dict[str, Any]:
    """One drive of the suite (its folder written when the plan names one): the raw row; ``merge`` compares it with the
    expert's. A stop signal ends the drive after its step (the row says ``interrupted``: not a result)."""
    options = options_of(spec)
    result = drive(options, spec.options.get("folder"), stop=stop)
    return {**raw_row(spec.name, options, result.summary), "interrupted": result.interrupted}


def raw_row(name: str, options: DriveOptions, s: dict[str, Any]) -> dict[str, Any]:
    """A drive's row before it is compared with the expert's (``merge`` adds ``progress_vs_expert_pct``)."""
    timing = s.get("timing", {})
    return {
        "run": name, "controller": options.controller, "seed": options.seed, "map": options.map_blocks, "lighting": options.lighting,
        "lead": options.lead, "traffic_density": options.traffic_density, "seconds": options.seconds,
        "progress_m": s["progress_m"], "progress_vs_expert_pct": None, "route_completion": s.get("route_completion"),
        "out_of_road": s["out_of_road"], "centre_line_crossings": s.get("centre_line_crossings"),
        "crashes": s["crashes"], "crashes_by_kind": s.get("crashes_by_kind"),
        "end_reason": s.get("end_reason"), "min_gap_m": s.get("min_gap_m"), "min_ttc_s": s.get("min_ttc_s"),
        "emergency_s": (s.get("time_in_mode_s") or {}).get("EMERGENCY"), "time_in_mode_s": s.get("time_in_mode_s"),
        "lane_offset_rms_m": s.get("lane_offset_rms_m"), "mean_speed_mps": s.get("mean_speed_mps"),
        "stopped_car": s.get("stopped_car"), "controller_ms": timing.get("controller_ms_median"),
        "simulator_ms": timing.get("simulator_ms_median"),
    }


def criteria(rows: Sequence[dict[str, Any]]) -> list[dict[str, Any]]:
    """Issue 38's Done-when criteria over the guarded rows, each with ok and the numbers behind it."""
    out = []
    for r in rows:
        if r["controller"] != "guarded":
            continue
        share = (r["progress_vs_expert_pct"] or 0.0) / 100
        if r["lead"] == "stopped":
            car = r["stopped_car"] or {}
            went = bool(car.get("passed") or car.get("waited_behind"))
            ok = not car.get("contact") and r["crashes"] == 0 and bool(car.get("stopped_behind")) and went
            out.append({"criterion": f"{r['run']}: stopped for (no crash), then passed or waited behind", "ok": ok,
                        "detail": f"contact {car.get('contact')}, stopped behind {car.get('stopped_behind')} "
                                  f"(gap {car.get('stop_gap_m')}), passed {car.get('passed')}, waited {car.get('waited_behind')}"})
            continue
        need = NIGHT_PROGRESS_SHARE if r["lighting"] == "night" else DAY_PROGRESS_SHARE
        stayed = r["out_of_road"] == 0 and not r.get("centre_line_crossings")
        ok = r["crashes"] == 0 and (r["lighting"] == "night" or stayed) and share >= need
        lane = "" if r["lighting"] == "night" else ", never out of road nor over the centre line"
        out.append({"criterion": f"{r['run']}: no crash{lane}"
                                 + f", progress >= {100 * need:.0f} % of the expert's", "ok": ok,
                    "detail": f"crashes {r['crashes']}, out of road {r['out_of_road']}, centre-line crossings "
                              f"{r.get('centre_line_crossings')}, progress {100 * share:.0f} %"})
    return out


def merge(rows: Sequence[dict[str, Any]]) -> tuple[list[dict[str, Any]], list[dict[str, Any]], str]:
    """The rows compared with the expert's progress on the same run, the criteria, and the markdown (table, cost line,
    PASS/FAIL per criterion)."""
    merged = compared_with_experts(rows)
    checks = criteria(merged)
    markdown = suite_text(suite_markdown(merged), merged, checks, "MetaDrive's step (physics + rendering at 320x240)")
    return merged, checks, markdown


def run_suite(out_dir: str | Path, specs: Sequence[RunSpec], executor: Executor | None = None,
              on_run: Callable[[str], None] | None = None, resume: bool = False, stop: StopSignal | None = None,
              on_progress: Callable[[int, int], None] | None = None,
              on_row: Callable[[dict[str, Any]], None] | None = None) -> tuple[str, bool]:
    """The plan through the one suite (``executor``: e.g. ``cluster.DaskExecutor(jobs=2)``, each drive in a worker
    process: one MetaDrive engine per process); runs.jsonl grows a row per drive, suite.md / suite.json are rewritten
    after every drive. Returns the markdown and whether the suite was cut short."""

    def said(row: dict[str, Any]) -> None:
        if on_row is not None:
            on_row(row)
        if on_run is not None:
            on_run(f"{row['run']} {row['controller']}: progress {row['progress_m']:.1f} m, out of road {row['out_of_road']}, "
                   f"crashes {row['crashes']}, EMERGENCY {row['emergency_s'] or 0:.1f} s")

    result, markdown = run_plan_with_tables(specs, Path(out_dir), merge, resume=resume, stop=stop,
                                            executor=executor, on_row=said, on_progress=on_progress)
    return markdown, result.interrupted
