"""The Duckietown suite's plan and its criteria (no simulator: rows are made by hand)."""

from __future__ import annotations

from fearguard.drive.plan import RunSpec
from fearguard.worlds.duckietown.report import suite_markdown
from fearguard.worlds.duckietown.suite import LANE_MAPS, criteria, merge, options_of, plan


def test_plan_has_experts_before_the_runs_compared_to_them() -> None:
    specs = plan(60.0, 2, rand_seconds=30.0)
    runs = [(s.name, options_of(s)) for s in specs]
    names = [n for n, _ in runs]
    for m in LANE_MAPS:
        assert names.index(m) == next(i for i, (n, o) in enumerate(runs) if n == m and o.controller == "expert")
    rand = [o for _, o in runs if o.domain_rand]
    assert len(rand) == 4 and {o.seconds for o in rand} == {30.0} and {o.seed for o in rand} == {0, 1}
    assert any(o.obstacle == "duck" and o.range_sensor == "none" and o.controller == "guarded" for _, o in runs)
    assert len({s.key for s in specs}) == len(specs)  # every row named uniquely: resume finds each
    assert all(RunSpec.from_json(s.to_json()) == s for s in specs)  # a row survives JSON (runs.jsonl, another process)


def test_merge_compares_each_drive_with_the_experts_on_the_same_run() -> None:
    rows = [_row("loop_empty", "expert", None, progress_m=12.0), _row("loop_empty", "guarded", None, progress_m=11.4)]
    merged, checks, markdown = merge(rows)
    assert merged[1]["progress_vs_expert_pct"] == 95.0 and checks[0]["ok"] and "PASS loop_empty" in markdown


def _row(run: str, controller: str, pct: float | None, **kw: object) -> dict:
    row = {"run": run, "controller": controller, "map": run, "seed": 0, "domain_rand": False, "obstacle_kind": None, "range_sensor": "none",
           "progress_m": 10.0, "progress_vs_expert_pct": pct, "departures": 0, "centre_line_crossings": 0, "collisions": 0,
           "invalid_pose": False, "emergency_s": 0.0, "lane_offset_rms_m": 0.01, "lane_offset_max_m": 0.03, "marking_share": 0.0,
           "obstacle": None, "controller_ms": 5.0, "simulator_ms": 20.0}
    row.update(kw)
    return row


def test_criteria_pass_and_fail_as_issue_14_says() -> None:
    rows = [_row("loop_empty", "guarded", 95.0), _row("small_loop", "guarded", 85.0),
            _row("zigzag_dists", "guarded", 99.0, departures=1),
            _row("straight_road + duck", "guarded", None, obstacle_kind="duck",
                 obstacle={"stopped_before_contact": True, "went_on": False, "contact": False, "stop_gap_m": 0.1, "removed_t_s": 9.0}),
            _row("loop_empty rand 0", "guarded", 82.0, domain_rand=True), _row("loop_empty rand 1", "guarded", 79.0, domain_rand=True)]
    checks = criteria(rows)
    # loop_empty 95 % passes; small_loop 85 % < 90 %; zigzag left the road; the duck stayed stopped; seed 1 made 79 % < 80 %
    assert [c["ok"] for c in checks] == [True, False, False, False, False]
    assert "loop_empty rand 1" in checks[-1]["detail"] and "79–82 %" in checks[-1]["detail"]
    table = suite_markdown(rows)
    assert "stopped 0.10 m short (no supervisor), did not go on" in table and table.count("\n") == len(rows) + 2
