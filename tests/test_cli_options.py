"""Every CLI option that takes a value is checked before anything runs: exit 2 and one line naming the option (issue 31).

A new user's mistakes (`--speed-mps -1`, `--from 999s` on a 9 s video, `scenarios README.md`, `verify --examples 0`)
used to be accepted without a word.
"""

from __future__ import annotations

from pathlib import Path

import pytest

from fearguard.cli import main
from tests.conftest import SHARED_DATA as DATA

VIDEO = str(DATA / "road" / "video" / "solidWhiteRight.mp4")  # 221 frames, 25 fps

PARSE_TIME = [  # argparse rejects these: usage error, exit 2, "argument --NAME: why"
    (["replay", VIDEO, "--speed-mps", "-1"], "--speed-mps", "must be >= 0"),
    (["replay", VIDEO, "--speed-mps", "nan"], "--speed-mps", "finite"),
    (["replay", VIDEO, "--fps", "0"], "--fps", "must be > 0"),
    (["replay", VIDEO, "--fps", "inf"], "--fps", "finite"),
    (["replay", VIDEO, "--from", "soon"], "--from", "use seconds"),
    (["replay", VIDEO, "--to=-3s"], "--to", "use seconds"),
    (["replay", VIDEO, "--every", "0"], "--every", "must be >= 1"),
    (["scenarios", "no_such_folder"], "folder", "not an existing folder"),
    (["scenarios", "README.md"], "folder", "it is a file"),
    (["suite", "no_such_folder"], "folder", "not an existing folder"),
    (["suite", "--seeds", "0"], "--seeds", "must be >= 1"),
    (["run", "night", "--seed", "-1"], "--seed", "must be >= 0"),
    (["verify", "--examples", "0"], "--examples", "must be >= 1"),
    (["verify", "--seed", "-2"], "--seed", "must be >= 0"),
    (["rules", "explain", "--cues", "lane_confidence=1", "--top", "0"], "--top", "must be >= 1"),
    (["rules", "explain", "--cues", "lane_confidence=1", "--lead-range", "-1"], "--lead-range", "must be >= 0"),
    (["rules", "explain", "--cues", "lane_confidence=1", "--lead-bearing", "95"], "--lead-bearing", "must be < 90"),
    (["calibrate", "x.jpg", "--square-m", "0"], "--square-m", "must be > 0"),
    (["calibrate", "x.jpg", "--mount-height-m", "-0.1"], "--mount-height-m", "must be > 0"),
    (["calibrate", "x.jpg", "--front-offset-m", "-0.1"], "--front-offset-m", "must be >= 0"),
    (["calibrate", "x.jpg", "--pitch-deg", "90"], "--pitch-deg", "must be < 90"),
    (["duckietown", "--seconds", "0"], "--seconds", "must be > 0"),
    (["duckietown", "--cruise-mps", "-0.2"], "--cruise-mps", "must be > 0"),
    (["duckietown", "--ahead", "0"], "--ahead", "must be > 0"),
    (["duckietown", "--remove-after", "-1"], "--remove-after", "must be >= 0"),
    (["duckietown", "--seed", "-1"], "--seed", "must be >= 0"),
    (["duckietown", "--width", "8"], "--width", "must be >= 40"),
    (["duckietown-suite", "--seconds", "-5"], "--seconds", "must be > 0"),
    (["duckietown-suite", "--seeds", "-1"], "--seeds", "must be >= 0"),
    (["duckietown-suite", "--rand-seconds", "0"], "--rand-seconds", "must be > 0"),
    (["duckietown-suite", "--jobs", "0"], "--jobs", "must be >= 1"),
    (["suite", "--jobs", "0"], "--jobs", "must be >= 1"),
    (["suite", "--jobs", "two"], "--jobs", "not a whole number"),
    (["suite", "--scheduler", "http://10.0.0.5:8786"], "--scheduler", "is not a Dask scheduler address"),
    (["suite", "--scheduler", "tcp://10.0.0.5:99999"], "--scheduler", "such as tcp://10.0.0.5:8786"),
    (["suite", "--jobs", "2", "--scheduler", "tcp://10.0.0.5:8786"], "--scheduler", "not allowed with argument --jobs"),
    (["duckietown-suite", "--scheduler", "two words"], "--scheduler", "is not a Dask scheduler address"),
]


IDS = [" ".join(a[:1] + a[2:] if a[0] == "replay" else a) for a, _, _ in PARSE_TIME]


@pytest.mark.parametrize(("argv", "option", "says"), PARSE_TIME, ids=IDS)
def test_a_bad_option_value_is_a_usage_error_naming_the_option(capsys, monkeypatch, argv, option, says) -> None:
    monkeypatch.chdir(Path(__file__).resolve().parents[1])
    with pytest.raises(SystemExit) as exc:
        main(argv)
    err = capsys.readouterr().err.strip().splitlines()
    assert exc.value.code == 2
    assert f"argument {option}: " in err[-1] and says in err[-1], err


@pytest.mark.parametrize(("argv", "option", "says"), [
    (["replay", VIDEO, "--from", "999s"], "--from", "the recording has 221 frames"),
    (["replay", VIDEO, "--from", "221f"], "--from", "start inside it"),
    (["replay", VIDEO, "--from", "2s", "--to", "1s"], "--to", "is not after --from"),
])
def test_a_position_outside_the_recording_is_exit_2_naming_the_option(tmp_path, capsys, argv, option, says) -> None:
    assert main([*argv, "--out", str(tmp_path / "out")]) == 2
    err = capsys.readouterr().err
    assert f", {option}: " in err and says in err and err.count("\n") == 1, err


def test_a_folder_without_scenarios_is_exit_2(tmp_path, capsys) -> None:
    (tmp_path / "notes.txt").write_text("not a scenario")
    assert main(["scenarios", str(tmp_path)]) == 2
    assert "holds no scenario files" in capsys.readouterr().err
