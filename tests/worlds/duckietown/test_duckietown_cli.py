"""`fearguard duckietown`: arguments and errors a person can act on."""

from __future__ import annotations

import importlib.util

import pytest

from fearguard.cli import main


def test_missing_map_is_a_usage_error(capsys: pytest.CaptureFixture[str]) -> None:
    assert main(["duckietown", "--out", "x"]) == 2
    assert "give a MAP" in capsys.readouterr().err


def test_bad_numbers_are_usage_errors(capsys: pytest.CaptureFixture[str], tmp_path) -> None:
    with pytest.raises(SystemExit) as exc:  # rejected while parsing, before the simulator is imported
        main(["duckietown", "loop_empty", "--out", str(tmp_path), "--seconds", "-1"])
    assert exc.value.code == 2
    assert "argument --seconds: must be > 0, got -1" in capsys.readouterr().err


@pytest.mark.skipif(importlib.util.find_spec("gym_duckietown") is not None, reason="the simulator is installed here")
def test_without_the_simulator_the_error_says_how_to_install_it(capsys: pytest.CaptureFixture[str], tmp_path) -> None:
    assert main(["duckietown", "loop_empty", "--out", str(tmp_path), "--seconds", "1"]) == 2
    assert ".ci/duckietown.sh" in capsys.readouterr().err


def test_an_unknown_lane_model_is_a_usage_error(capsys: pytest.CaptureFixture[str], tmp_path) -> None:
    with pytest.raises(SystemExit) as exc:
        main(["duckietown", "loop_empty", "--out", str(tmp_path), "--lane", "spec"])
    assert exc.value.code == 2
    assert "argument --lane: invalid choice: 'spec'" in capsys.readouterr().err
    from fearguard.worlds.duckietown.drive import DriveOptions

    with pytest.raises(ValueError, match="lane model 'spec': choose one of preset, camera"):
        DriveOptions(lane="spec")
