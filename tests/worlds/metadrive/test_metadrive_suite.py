"""The MetaDrive suite's plan, merge and criteria (no simulator: rows are made by hand)."""

from __future__ import annotations

from pathlib import Path

from fearguard.drive.plan import ROW_RUNNERS, RunSpec
from fearguard.worlds.metadrive.report import suite_markdown
from fearguard.worlds.metadrive.suite import criteria, merge, options_of, plan


def test_plan_names_every_drive_once_with_the_experts_first(tmp_path: Path) -> None:
    specs = plan([0, 1], 30.0, stopped_seeds=[3], night_seeds=[4], out_dir=tmp_path)
    runs = [(s.name, options_of(s)) for s in specs]
    assert [n for n, _ in runs] == ["day 0"] * 3 + ["day 1"] * 3 + ["stopped car 3"] * 2 + ["night 4"] * 2
    for name in {n for n, _ in runs}:
        assert next(o.controller for n, o in runs if n == name) == "expert"
    assert {o.lead for n, o in runs if n.startswith("stopped")} == {"stopped"}
    assert {o.lighting for n, o in runs if n.startswith("night")} == {"night"}
    assert all(o.seconds == 30.0 and o.map_blocks == "SCSC" and o.lanes == 3 and o.traffic_density == 0.05 for _, o in runs)
    assert len({s.key for s in specs}) == len(specs) and all(s.world == "metadrive" for s in specs)  # resume finds each
    assert all(RunSpec.from_json(s.to_json()) == s for s in specs)  # a row survives JSON (runs.jsonl, another process)
    assert specs[0].options["folder"] == str(tmp_path / "day_0_expert")
    assert ROW_RUNNERS["metadrive"] == "fearguard.worlds.metadrive.suite:run_row"
    only = plan([5], 30.0, (), (), controllers=("guarded",))
    assert [(s.name, s.controller) for s in only] == [("day 5", "expert"), ("day 5", "guarded")]


def _row(run: str, controller: str, progress_m: float, **kw: object) -> dict:
    row = {"run": run, "controller": controller, "seed": 0, "map": "SCSC", "lighting": "day", "lead": None, "traffic_density": 0.05,
           "seconds": 30.0, "progress_m": progress_m, "progress_vs_expert_pct": None, "route_completion": 0.5, "out_of_road": 0,
           "centre_line_crossings": 0,
           "crashes": 0, "crashes_by_kind": None, "end_reason": None, "min_gap_m": None, "min_ttc_s": None, "emergency_s": 0.0,
           "time_in_mode_s": None, "lane_offset_rms_m": 0.2, "mean_speed_mps": 9.0, "stopped_car": None, "controller_ms": 6.0,
           "simulator_ms": 500.0}
    row.update(kw)
    return row


def test_merge_compares_with_the_expert_and_checks_issue_38s_criteria() -> None:
    car = {"contact": False, "stopped_behind": True, "stop_gap_m": 8.0, "stop_t_s": 9.0, "passed": False, "waited_behind": True}
    rows = [_row("day 0", "expert", 280.0), _row("day 0", "guarded", 266.0), _row("day 0", "unguarded", 290.0, out_of_road=1),
            _row("day 1", "expert", 280.0), _row("day 1", "guarded", 240.0),  # 86 % < 90 %
            _row("day 2", "expert", 280.0), _row("day 2", "guarded", 275.0, crashes=1),
            _row("day 3", "expert", 280.0), _row("day 3", "guarded", 275.0, centre_line_crossings=1),  # on the wrong side
            _row("stopped car 0", "expert", 250.0, lead="stopped"), _row("stopped car 0", "guarded", 60.0, lead="stopped", stopped_car=car),
            _row("night 0", "expert", 280.0, lighting="night"), _row("night 0", "guarded", 180.0, lighting="night")]  # 64 % >= 60 %
    merged, checks, markdown = merge(rows)
    assert merged[1]["progress_vs_expert_pct"] == 95.0 and "spec" not in merged[1]
    assert [c["ok"] for c in checks] == [True, False, False, False, True, True]
    assert "PASS day 0" in markdown and "FAIL day 1" in markdown and "stopped 8.0 m short, waited" in markdown
    assert "MetaDrive's step (physics + rendering at 320x240): 500.0 ms; fearguard = 1.2 % of it" in markdown
    assert criteria([_row("stopped car 1", "guarded", 50.0, lead="stopped", stopped_car={**car, "contact": True})])[0]["ok"] is False


def test_the_table_has_a_line_per_drive() -> None:
    table = suite_markdown([_row("day 0", "expert", 280.0), _row("day 0", "guarded", 266.0, progress_vs_expert_pct=95.0)])
    assert table.count("\n") == 4 and "| day 0 | 0 | guarded | 266.0 | 95 |" in table
