"""Runs killed by a signal mid-loop (the small version of benchmarks/bench_signals.py): the log parses with
consecutive frames, the video plays at least every logged frame but the last, and SIGINT/SIGTERM leave a
summary that says interrupted with exit 130/143."""

from __future__ import annotations

import json
import os
import signal
import subprocess
import sys
import time
from pathlib import Path

import pytest

from fearguard.outputs.video import count_frames

SRC = Path(__file__).resolve().parents[1] / "src"
LONG = "name = 'long'\nduration_s = 30.0\n[[road.segments]]\nkind = 'straight'\nlength_m = 80.0\n[expect]\nno_collision = true\n"


def kill_mid_loop(argv: list[str], log: Path, signum: int, after_lines: int = 8) -> int:
    proc = subprocess.Popen([sys.executable, "-m", "fearguard.cli", *argv], stdout=subprocess.DEVNULL, stderr=subprocess.PIPE,
                            env={**os.environ, "PYTHONPATH": str(SRC)}, text=True)
    deadline = time.monotonic() + 240
    while time.monotonic() < deadline and proc.poll() is None and (not log.exists() or log.read_text().count("\n") < after_lines):
        time.sleep(0.05)
    assert proc.poll() is None, "the run ended before the signal"
    proc.send_signal(signum)
    _, err = proc.communicate(timeout=120)
    assert "Traceback" not in err, err
    return proc.returncode


def logged_frames(log: Path) -> int:
    numbers = [json.loads(line)["frame"] for line in log.read_text().splitlines()]  # every line parses
    assert numbers == list(range(len(numbers)))
    return len(numbers)


@pytest.mark.slow
@pytest.mark.parametrize("signum", [signal.SIGTERM, signal.SIGKILL], ids=["SIGTERM", "SIGKILL"])
def test_a_killed_closed_loop_run_keeps_a_valid_log_and_a_playable_video(signum: int, tmp_path: Path) -> None:
    scenario = tmp_path / "long.toml"
    scenario.write_text(LONG)
    out = tmp_path / "out"
    code = kill_mid_loop(["run", str(scenario), "--out", str(out), "--video"], out / "log.jsonl", signum)
    n = logged_frames(out / "log.jsonl")
    assert count_frames(out / "annotated.mp4") >= n - 1 >= 7
    if signum == signal.SIGKILL:
        assert code == -signal.SIGKILL
    else:
        summary = json.loads((out / "summary.json").read_text())
        assert code == 143 and summary["interrupted"] and summary["passed"] is False and summary["frames"] == n


def test_ctrl_c_in_a_replay_says_interrupted(shared_data: Path, tmp_path: Path) -> None:
    out = tmp_path / "out"
    video = shared_data / "road" / "video" / "solidWhiteRight.mp4"
    code = kill_mid_loop(["replay", str(video), "--out", str(out), "--video"], out / "log.jsonl", signal.SIGINT)
    n = logged_frames(out / "log.jsonl")
    summary = json.loads((out / "summary.json").read_text())
    assert code == 130 and summary["interrupted"] and summary["stopped_by"] == "SIGINT" and summary["processed_frames"] == n
    assert count_frames(out / "annotated.mp4") == n  # closed properly: every frame
