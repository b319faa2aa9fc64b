"""The one suite: run a plan row by row, append each finished row to runs.jsonl at once, resume what is missing.

Every world's suite is a plan (``drive/plan.py``) run through ``run_plan``; the world's ``merge`` turns the rows into
its tables. Rows come back in plan order whatever order they finished in. An interrupted suite (a stop signal, Ctrl-C)
keeps every finished row in ``runs.jsonl``, a valid JSON Lines file; ``resume`` runs only the rows not in it. A run cut
short by a stop is not a result: it is left out, and the suite stops there.

``executor`` runs the rows: None runs them one after the other in this process; ``cluster.DaskExecutor`` on Dask's
workers, local or on other machines (each row is independent and deterministic: the rows are the same however they
ran). An executor is a generator: closing it (the plan stopped, Ctrl-C) cancels what it still runs.
"""

from __future__ import annotations

import json
import statistics
from collections.abc import Callable, Generator, Mapping, Sequence
from contextlib import closing
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from fearguard.drive.interrupt import StopSignal
from fearguard.drive.plan import RunSpec, row_key, run_row
from fearguard.outputs.report import JsonlLog, json_value, read_jsonl

Row = dict[str, Any]
Merge = Callable[[Sequence[Row]], tuple[list[Row], list[Row], str]]  # rows → (the table's rows, the criteria, the markdown)
Executor = Callable[[Sequence[RunSpec], StopSignal | None], Generator[tuple[int, Row], None, None]]  # (index, row) of each spec, any order


@dataclass(frozen=True)
class PlanResult:
    """Every row (resumed and new) in plan order, the size of the plan, and whether it was cut short."""

    rows: list[Row]
    planned: int  # runs in the whole plan
    resumed: int  # rows read back from an earlier, interrupted suite
    interrupted: bool = False
    stopped_by: str | None = None


def serial(specs: Sequence[RunSpec], stop: StopSignal | None = None) -> Generator[tuple[int, Row], None, None]:
    """One row after the other, in this process (a stop signal reaches the run under way: it ends after its frame)."""
    for i, spec in enumerate(specs):
        yield i, run_row(spec, stop)


def finished_rows(path: Path | None) -> list[Row]:
    """The rows of an earlier suite's runs.jsonl (a torn last line from a killed suite is left out)."""
    if path is None or not path.is_file():
        return []
    return [r for r in read_jsonl(path) if isinstance(r, dict) and row_key(r) is not None]


def run_plan(
    plan: Sequence[RunSpec], *, runs_log: Path | None = None, resume: bool = False, stop: StopSignal | None = None,
    executor: Executor | None = None, on_row: Callable[[Row], None] | None = None,
    on_progress: Callable[[int, int], None] | None = None,
) -> PlanResult:
    """Run the rows of ``plan`` not already done; each finished row appended to ``runs_log`` (flushed) as it arrives.

    ``on_row(row)`` after each new row; ``on_progress(done, planned)`` before the first and after each row (resumed
    rows count as done). A row whose run was interrupted ends the suite without being kept.
    """
    done = finished_rows(runs_log) if resume else []
    known = {row_key(r): r for r in done}
    by_index: dict[int, Row] = {i: known[spec.key] for i, spec in enumerate(plan) if spec.key in known}
    todo = [(i, spec) for i, spec in enumerate(plan) if spec.key not in known]
    log = JsonlLog(runs_log) if runs_log is not None else None  # rewritten: the resumed rows, then each new one

    def keep(index: int, row: Row) -> None:
        by_index[index] = row
        if log is not None:
            log.write(row)
        if on_row is not None:
            on_row(row)
        if on_progress is not None:
            on_progress(len(by_index), len(plan))

    interrupted = False
    try:
        for row in done if log is not None else ():
            log.write(row)
        if on_progress is not None:
            on_progress(len(by_index), len(plan))
        interrupted = _run_rows(todo, executor or serial, stop, keep)
    except KeyboardInterrupt:
        interrupted = True
    finally:
        if log is not None:
            log.close()
    ordered = [by_index[i] for i in sorted(by_index)]
    return PlanResult(ordered, len(plan), len(done), interrupted or bool(stop), stop.name if stop else None)


def _run_rows(todo: Sequence[tuple[int, RunSpec]], executor: Executor, stop: StopSignal | None,
              keep: Callable[[int, Row], None]) -> bool:
    """Run the rows still to do, keeping each as it arrives; True when a run was cut short (its row is not kept)."""
    if stop or not todo:
        return False
    with closing(executor([spec for _, spec in todo], stop)) as rows:  # closed at once on the way out: nothing left running
        for k, row in rows:
            if row.get("interrupted"):
                return True
            keep(todo[k][0], row)
            if stop:
                return False
    return False


def run_plan_with_tables(
    plan: Sequence[RunSpec], out: Path, merge: Merge, *, resume: bool = False, stop: StopSignal | None = None,
    executor: Executor | None = None, on_row: Callable[[Row], None] | None = None,
    on_progress: Callable[[int, int], None] | None = None,
) -> tuple[PlanResult, str]:
    """``run_plan`` into ``out/runs.jsonl``, with the world's tables rewritten after every row: ``merge(rows)`` of every
    finished row (resumed ones too) in plan order → ``out/suite.md`` and ``out/suite.json`` (its rows and criteria), so
    an interrupted suite keeps a table of what it finished. Returns the plan's result and the last markdown."""
    out.mkdir(parents=True, exist_ok=True)
    runs_log = out / "runs.jsonl"
    order = {spec.key: i for i, spec in enumerate(plan)}
    finished = finished_rows(runs_log) if resume else []
    markdown = ""

    def write(rows: Sequence[Row]) -> None:
        nonlocal markdown
        merged, checks, markdown = merge(sorted(rows, key=lambda r: order.get(row_key(r), len(order))))
        (out / "suite.md").write_text(markdown, encoding="utf-8")
        (out / "suite.json").write_text(json.dumps(json_value({"rows": merged, "criteria": checks}), indent=2) + "\n", encoding="utf-8")

    def kept(row: Row) -> None:
        finished.append(row)
        write(finished)
        if on_row is not None:
            on_row(row)

    result = run_plan(plan, runs_log=runs_log, resume=resume, stop=stop, executor=executor, on_row=kept, on_progress=on_progress)
    write(result.rows)
    return result, markdown


def compared_with_experts(rows: Sequence[Mapping[str, Any]], comparable: Callable[[Mapping[str, Any]], bool] | None = None) -> list[Row]:
    """Each row without its spec and interrupted flag, with ``progress_vs_expert_pct``: 100 × its ``progress_m`` over that
    of the ``expert`` row of the same ``run`` (None without one, or when ``comparable(row)`` is False)."""
    experts = {r["run"]: r["progress_m"] for r in rows if r["controller"] == "expert"}
    out = []
    for r in rows:
        expert = experts.get(r["run"]) if comparable is None or comparable(r) else None
        row = {k: v for k, v in r.items() if k not in ("spec", "interrupted")}
        row["progress_vs_expert_pct"] = 100 * r["progress_m"] / expert if expert else None
        out.append(row)
    return out


def cost_line(rows: Sequence[Mapping[str, Any]], simulator: str = "the simulator's step (physics + rendering)") -> str:
    """fearguard's per-step cost over every guarded row (the median of the rows' ``controller_ms`` medians) against the
    world's step (``simulator_ms``), and its share; "" without guarded rows that carry both."""
    g = [r["controller_ms"] for r in rows if r["controller"] == "guarded" and r.get("controller_ms") is not None]
    s = [r["simulator_ms"] for r in rows if r["controller"] == "guarded" and r.get("simulator_ms") is not None]
    if not g or not s:
        return ""
    gm, sm = statistics.median(g), statistics.median(s)
    return (f"fearguard per step (perception + supervisor): {gm:.1f} ms median over {len(g)} guarded drives; {simulator}: "
            f"{sm:.1f} ms; fearguard = {100 * gm / sm:.1f} % of it")


def suite_text(table: str, rows: Sequence[Mapping[str, Any]], checks: Sequence[Mapping[str, Any]], simulator: str | None = None) -> str:
    """A suite's markdown: its table, the cost line, then PASS/FAIL and the numbers of each criterion."""
    cost = cost_line(rows) if simulator is None else cost_line(rows, simulator)
    return table + "\n" + cost + "\n\n" + "\n".join(
        f"- {'PASS' if c['ok'] else 'FAIL'} {c['criterion']} ({c['detail']})" for c in checks) + "\n"
