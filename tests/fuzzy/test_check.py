"""`fearguard rules check`: passes on shipped files, fails (exit 1) on non-monotone or incomplete ones."""

from __future__ import annotations

from pathlib import Path

import pytest
from tests.conftest import RULES_DIR

import fearguard as fg
from fearguard.cli import main
from fearguard.fuzzy.check import check_rules

# the obvious 3×3 grid over lane_confidence × occlusion: Mamdani centroid makes it non-monotone
GRID_GROUP = '''[groups.road_grid]
cause = "road"
rules = [
  "IF lane_confidence IS high AND occlusion IS none THEN fear IS very_low",
  "IF lane_confidence IS high AND occlusion IS partial THEN fear IS low",
  "IF lane_confidence IS high AND occlusion IS heavy THEN fear IS high",
  "IF lane_confidence IS medium AND occlusion IS none THEN fear IS low",
  "IF lane_confidence IS medium AND occlusion IS partial THEN fear IS medium",
  "IF lane_confidence IS medium AND occlusion IS heavy THEN fear IS very_high",
  "IF lane_confidence IS low AND occlusion IS none THEN fear IS high",
  "IF lane_confidence IS low AND (occlusion IS partial OR occlusion IS heavy) THEN fear IS very_high",
]

[groups.visibility]'''


@pytest.mark.parametrize("path", sorted(RULES_DIR.glob("*.toml")), ids=lambda p: p.name)
def test_shipped_rule_files_pass(path: Path, capsys) -> None:
    assert main(["rules", "check", str(path)]) == 0
    assert "OK: every group is complete and monotone" in capsys.readouterr().out


def test_grid_rule_base_is_reported_non_monotone(write_rules, capsys) -> None:
    path = write_rules(("[groups.visibility]", GRID_GROUP))
    assert main(["rules", "check", str(path)]) == 1
    out = capsys.readouterr().out
    assert "road_grid" in out and "NOT MONOTONE" in out and "fear falls" in out


def test_inverted_consequent_is_reported_non_monotone(write_rules) -> None:
    path = write_rules(('"IF obstacle_range_m IS near THEN fear IS high"', '"IF obstacle_range_m IS near THEN fear IS very_low"'))
    report = check_rules(fg.load_rules(path))
    assert not report.ok
    bad = [g for g in report.groups if not g.ok]
    assert [g.group for g in bad] == ["collision"] and "obstacle_range_m" in bad[0].violations[0]


def test_brightness_rising_into_the_band_must_not_raise_fear(write_rules) -> None:
    # dim and normal as two rules (max, not one trapezoid): their crossing dips, so fear rises entering the band
    path = write_rules(('"IF brightness IS usable THEN fear IS very_low"',
                        '"IF brightness IS normal THEN fear IS very_low", "IF brightness IS dim THEN fear IS very_low"'))
    report = check_rules(fg.load_rules(path))
    assert [g.group for g in report.groups if g.violations] == ["visibility"]


def test_incomplete_rule_base_fails(write_rules, capsys) -> None:
    path = write_rules(('  "IF qr_staleness_s IS aging THEN fear IS low",\n', ""))
    assert main(["rules", "check", str(path)]) == 1
    out = capsys.readouterr().out
    assert "localisation" in out and "INCOMPLETE" in out and "no rule fires at qr_staleness_s=" in out


def test_bad_file_exits_2(tmp_path: Path, capsys) -> None:
    assert main(["rules", "check", str(tmp_path / "missing.toml")]) == 2
    assert "RuleError:" in capsys.readouterr().err


def test_rules_check_fails_a_file_whose_lost_lane_rule_shrugs(write_rules) -> None:
    """Issue 31: complete and monotone, yet a lost lane gave NORMAL at full speed; the promises line catches it."""
    from fearguard.fuzzy.check import check_rules

    path = write_rules(('"IF lane_confidence IS low THEN fear IS high"', '"IF lane_confidence IS low THEN fear IS low"'))
    report = check_rules(fg.load_rules(path))
    assert not report.ok and all(g.ok for g in report.groups) and report.thresholds.ok
    text = "\n".join(report.lines())
    assert "UNREACHED lane_confidence 0 alone (its worst value" in text and "'IF lane_confidence IS low THEN fear IS low'" in text


@pytest.mark.parametrize("name", ["default.toml", "road_car.toml", "duckiebot.toml"])
def test_every_bundled_rule_file_keeps_every_promise(name: str) -> None:
    from fearguard.fuzzy.promises import check_promises

    reaches = check_promises(fg.load_rules(f"rules/{name}"))
    assert len(reaches) >= 15 and all(r.ok for r in reaches), [r.line() for r in reaches if not r.ok]
