"""`fearguard metadrive`: every option checked while parsing (exit 2, one line naming it), and the set-up hint."""

from __future__ import annotations

import importlib.util

import pytest

from fearguard.cli import main


@pytest.mark.parametrize(("args", "message"), [
    (["--map", "SQ"], "argument --map: 'SQ' is not a MetaDrive block string"),
    (["--lanes", "0"], "argument --lanes: must be >= 1, got 0"),
    (["--lanes", "7"], "argument --lanes: must be <= 6, got 7"),
    (["--traffic", "-0.1"], "argument --traffic: must be >= 0"),
    (["--lighting", "noon"], "argument --lighting: invalid choice: 'noon'"),
    (["--seed", "-1"], "argument --seed: must be >= 0, got -1"),
    (["--seconds", "0"], "argument --seconds: must be > 0, got 0"),
    (["--baseline", "crisp"], "argument --baseline: invalid choice: 'crisp'"),
    (["--range", "lidar"], "argument --range: invalid choice: 'lidar'"),
    (["--lead", "fast"], "argument --lead: invalid choice: 'fast'"),
    (["--width", "64"], "argument --width: must be >= 160, got 64"),
    (["--cruise-mps", "40"], "argument --cruise-mps: must be < 22.3, got 40"),
])
def test_bad_options_are_usage_errors_before_anything_runs(args: list[str], message: str, capsys: pytest.CaptureFixture[str],
                                                           tmp_path) -> None:
    with pytest.raises(SystemExit) as exc:
        main(["metadrive", "--out", str(tmp_path), *args])
    assert exc.value.code == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert message in err[-1]


@pytest.mark.skipif(importlib.util.find_spec("metadrive") is not None, reason="the simulator is installed here")
def test_without_the_simulator_the_error_says_how_to_install_it(capsys: pytest.CaptureFixture[str], tmp_path) -> None:
    assert main(["metadrive", "--out", str(tmp_path / "run"), "--seconds", "1"]) == 2
    err = capsys.readouterr().err
    assert "bash .ci/metadrive.sh" in err and len(err.strip().splitlines()) == 1


@pytest.mark.parametrize(("args", "message"), [
    (["--seeds", "-1"], "argument --seeds: must be >= 0, got -1"),
    (["--controllers", "expert"], "argument --controllers: invalid choice: 'expert'"),
    (["--map", "SQ"], "argument --map: 'SQ' is not a MetaDrive block string"),
    (["--jobs", "0"], "argument --jobs: must be >= 1, got 0"),
])
def test_the_suites_bad_options_are_usage_errors(args: list[str], message: str, capsys: pytest.CaptureFixture[str], tmp_path) -> None:
    with pytest.raises(SystemExit) as exc:
        main(["metadrive-suite", "--out", str(tmp_path), *args])
    assert exc.value.code == 2 and message in capsys.readouterr().err.strip().splitlines()[-1]
