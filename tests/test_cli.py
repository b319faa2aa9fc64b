"""The command line as a person uses it: demo, rules explain, rules plot, and bad input (exit 2)."""

from __future__ import annotations

import subprocess
import sys
from pathlib import Path

import pytest

from fearguard.cli import main


def test_demo_walks_through_every_strategy(capsys) -> None:
    assert main(["demo"]) == 0
    out = capsys.readouterr().out
    for word in ("tunnel exit glare", "FOLLOW_LEAD", "STOP", "CRAWL", "PASS_THROUGH", "entered EMERGENCY"):
        assert word in out


def test_explain_shows_fear_rules_and_the_command(capsys) -> None:
    assert main(["rules", "explain", "--cues", "lane_confidence=0.2,occlusion=0.8",
                 "--lead-bearing", "3", "--lead-range", "2"]) == 0
    out = capsys.readouterr().out
    assert "level VERY_HIGH" in out and "IF occlusion IS heavy AND lane_confidence IS low" in out
    assert "mode EMERGENCY, strategy FOLLOW_LEAD" in out and "steering +3.0 deg" in out


def test_explain_accepts_nan_as_unknown(capsys) -> None:
    assert main(["rules", "explain", "--cues", "obstacle_range_m=nan"]) == 0
    assert "strategy STOP" in capsys.readouterr().out


@pytest.mark.parametrize("cues", ["speed=3", "lane_confidence", "occlusion=lots"])
def test_explain_rejects_bad_cues_with_exit_2(cues, capsys) -> None:
    assert main(["rules", "explain", "--cues", cues]) == 2
    assert capsys.readouterr().err.startswith("FearguardError: --cues:")


def test_plot_writes_pngs(tmp_path: Path, capsys) -> None:
    assert main(["rules", "plot", "--out", str(tmp_path)]) == 0
    names = {p.name for p in tmp_path.glob("*.png")}
    assert {"memberships.png", "fear_by_cue.png", "fear_road_lost.png", "fear_collision.png"} <= names
    assert all((tmp_path / n).stat().st_size > 5000 for n in names)
    assert str(tmp_path / "memberships.png") in capsys.readouterr().out


def test_console_script_runs() -> None:
    out = subprocess.run([sys.executable, "-m", "fearguard.cli", "rules", "check"], capture_output=True, text=True)
    assert out.returncode == 0 and "OK" in out.stdout
