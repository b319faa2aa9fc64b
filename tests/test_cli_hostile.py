"""Hostile command lines and interruptions (issue 12, items 4, 7, 8): a clear usage error (exit 2) instead of a
traceback, one signal policy (finish the frame, write everything, say "interrupted", exit 130/143), and no
silent loss or escape from a recording's folder."""

from __future__ import annotations

import json
import os
import signal
import subprocess
import sys
import textwrap
from pathlib import Path

import cv2
import numpy as np
import pytest

from fearguard.cli import main
from fearguard.outputs.report import read_jsonl
from fearguard.outputs.video import count_frames

SRC = Path(__file__).resolve().parents[1] / "src"
SCENARIOS = SRC / "fearguard" / "scenarios"
SHORT = "name = 'short'\nduration_s = 1.0\n[[road.segments]]\nkind = 'straight'\nlength_m = 40.0\n[expect]\nno_collision = true\n"


def usage_error(argv: list[str], capsys) -> str:
    with pytest.raises(SystemExit) as exc:
        main(argv)
    assert exc.value.code == 2
    return capsys.readouterr().err


@pytest.fixture
def images(tmp_path: Path) -> Path:
    folder = tmp_path / "frames"
    folder.mkdir()
    for k in range(6):
        img = np.full((120, 160, 3), 90, np.uint8)
        cv2.line(img, (20 + k, 119), (75, 60), (255, 255, 255), 3)
        cv2.imwrite(str(folder / f"{k:03d}.png"), img)
    return folder


def test_every_zero_is_a_usage_error_not_a_division_by_zero(images: Path, tmp_path: Path, capsys) -> None:
    err = usage_error(["replay", str(images), "--out", str(tmp_path / "o"), "--every", "0"], capsys)
    assert "--every" in err and "must be >= 1" in err


def test_a_negative_seed_is_a_usage_error(tmp_path: Path, capsys) -> None:
    err = usage_error(["run", str(SCENARIOS / "clear_straight.toml"), "--seed", "-1", "--out", str(tmp_path / "o")], capsys)
    assert "--seed" in err and "must be >= 0" in err


def test_zero_seeds_is_a_usage_error_not_an_empty_table(tmp_path: Path, capsys) -> None:
    err = usage_error(["suite", "--seeds", "0", "--out", str(tmp_path / "o")], capsys)
    assert "--seeds" in err


@pytest.mark.parametrize("command", ["replay", "run", "plot", "suite"])
def test_out_naming_an_existing_file_is_a_usage_error(command: str, images: Path, tmp_path: Path, capsys) -> None:
    file = tmp_path / "taken.txt"
    file.write_text("mine")
    argv = {"replay": ["replay", str(images)], "run": ["run", str(SCENARIOS / "clear_straight.toml")],
            "plot": ["rules", "plot"], "suite": ["suite", "--seeds", "1"]}[command]
    for out in (file, file / "below"):
        err = usage_error([*argv, "--out", str(out)], capsys)
        assert f"{file} is a file" in err
    assert file.read_text() == "mine"


def test_a_tub_image_named_outside_the_tub_is_skipped_not_read(tmp_path: Path, images: Path) -> None:
    tub = tmp_path / "tub"
    (tub / "images").mkdir(parents=True)
    outside = tmp_path / "secret.png"
    cv2.imwrite(str(outside), np.full((120, 160, 3), 200, np.uint8))
    names = ["0.png", "../../secret.png", str(outside), str(tmp_path / "missing.png"), "1.png", "C:\\x.png"]
    for k in (0, 1):
        cv2.imwrite(str(tub / "images" / f"{k}.png"), cv2.imread(str(images / f"{k:03d}.png")))
    lines = [json.dumps({"_index": i, "_timestamp_ms": 1000 + 50 * i, "cam/image_array": n, "user/angle": 0.1})
             for i, n in enumerate(names)]
    (tub / "catalog_0.catalog").write_text("\n".join(lines) + "\n")
    (tub / "manifest.json").write_text("\n".join([
        json.dumps(["cam/image_array", "user/angle"]), json.dumps(["image_array", "float"]), json.dumps({}),
        json.dumps({"created_at": 0}), json.dumps({"paths": ["catalog_0.catalog"], "current_index": 6, "deleted_indexes": []})]))
    assert main(["replay", str(tub), "--out", str(tmp_path / "out"), "--no-plots"]) == 0
    records = read_jsonl(tmp_path / "out" / "log.jsonl")
    assert [r["frame"] for r in records] == [0, 4] and records[0]["user_angle_donkey"] == 0.1
    summary = json.loads((tmp_path / "out" / "summary.json").read_text())
    reasons = [s["reason"] for s in summary["skipped"]]
    assert len(reasons) == 4 and all("outside the tub" in r for r in reasons)


def test_an_image_folder_of_mixed_sizes_keeps_every_frame_in_the_video(images: Path, tmp_path: Path, capsys) -> None:
    for k in (1, 3):
        img = cv2.imread(str(images / f"{k:03d}.png"))
        cv2.imwrite(str(images / f"{k:03d}.png"), cv2.resize(img, (320, 200)))
    assert main(["replay", str(images), "--out", str(tmp_path / "o"), "--video", "--no-plots"]) == 0
    out = capsys.readouterr().out
    video = tmp_path / "o" / "annotated.mp4"
    assert f"video {video} (6 frames, 2 frame(s) of another size scaled to the first)" in out
    assert count_frames(video) == 6
    assert json.loads((tmp_path / "o" / "summary.json").read_text())["video"]["rescaled_frames"] == 2


def _python(code: str, *args: str) -> subprocess.CompletedProcess[str]:
    env = {**os.environ, "PYTHONPATH": str(SRC)}
    return subprocess.run([sys.executable, "-c", textwrap.dedent(code), *args], capture_output=True, text=True, env=env, timeout=300)


CTRL_C_DURING_IMPORT = """
    import builtins, os, signal, sys
    real = builtins.__import__
    def hook(name, *a, **k):  # Ctrl-C while the library is being imported
        if name == sys.argv[1]:
            builtins.__import__ = real
            os.kill(os.getpid(), signal.SIGINT)
        return real(name, *a, **k)
    builtins.__import__ = hook
    from fearguard.cli import main
    sys.exit(main(sys.argv[2:]))
"""


def test_ctrl_c_while_a_command_starts_is_a_one_line_message(tmp_path: Path) -> None:
    done = _python(CTRL_C_DURING_IMPORT, "fearguard.fuzzy.loader", "rules", "check")
    assert done.returncode == 130 and "Traceback" not in done.stderr and "interrupted by SIGINT" in done.stderr


def test_ctrl_c_while_a_run_starts_writes_an_interrupted_summary(tmp_path: Path) -> None:
    scenario = tmp_path / "short.toml"
    scenario.write_text(SHORT)
    done = _python(CTRL_C_DURING_IMPORT, "fearguard.sim.scenario", "run", str(scenario), "--out", str(tmp_path / "o"))
    assert done.returncode == 130 and "Traceback" not in done.stderr, done.stderr
    summary = json.loads((tmp_path / "o" / "summary.json").read_text())
    assert summary["interrupted"] and summary["passed"] is False and summary["stopped_by"] == "SIGINT"
    assert " ok " not in done.stdout and "interrupted by SIGINT" in done.stdout


def test_a_signal_while_plotting_marks_the_run_interrupted(tmp_path: Path, monkeypatch, capsys) -> None:
    import fearguard.sim.suite as suite

    scenario = tmp_path / "short.toml"
    scenario.write_text(SHORT)
    monkeypatch.setattr(suite, "plot_timeline", lambda *a, **k: os.kill(os.getpid(), signal.SIGTERM))
    assert main(["run", str(scenario), "--out", str(tmp_path / "o")]) == 143
    summary = json.loads((tmp_path / "o" / "summary.json").read_text())
    assert summary["interrupted"] and summary["stopped_by"] == "SIGTERM" and not summary["passed"]
    assert summary["frames"] == len(read_jsonl(tmp_path / "o" / "log.jsonl")) > 0
    assert not (tmp_path / "o" / "trajectory.png").exists()  # the plots after the signal are skipped


def test_a_signal_while_the_replay_plots_marks_the_replay_interrupted(images: Path, tmp_path: Path, monkeypatch, capsys) -> None:
    import fearguard.outputs.recorder as recorder

    def plot(*args, **kwargs):
        os.kill(os.getpid(), signal.SIGINT)

    monkeypatch.setattr(recorder, "plot_timeline", plot)
    assert main(["replay", str(images), "--out", str(tmp_path / "o")]) == 130
    summary = json.loads((tmp_path / "o" / "summary.json").read_text())
    assert summary["interrupted"] and summary["stopped_by"] == "SIGINT" and summary["processed_frames"] == 6


def test_sigterm_finishes_the_frame_and_writes_everything(images: Path, tmp_path: Path, monkeypatch, capsys) -> None:
    import fearguard.replay.run as run

    real = run._observation
    calls = []

    def observe(*args):
        calls.append(1)
        if len(calls) == 3:
            os.kill(os.getpid(), signal.SIGTERM)
        return real(*args)

    monkeypatch.setattr(run, "_observation", observe)
    assert main(["replay", str(images), "--out", str(tmp_path / "o"), "--video"]) == 143
    records = read_jsonl(tmp_path / "o" / "log.jsonl")
    assert [r["frame"] for r in records] == [0, 1, 2]  # the third frame was finished
    summary = json.loads((tmp_path / "o" / "summary.json").read_text())
    assert summary["interrupted"] and summary["stopped_by"] == "SIGTERM" and summary["processed_frames"] == 3
    assert count_frames(tmp_path / "o" / "annotated.mp4") == 3
    assert "interrupted by SIGTERM" in capsys.readouterr().out


def test_an_interrupted_suite_keeps_its_finished_runs_and_resumes(tmp_path: Path, monkeypatch, capsys) -> None:
    import fearguard.sim.suite as suite

    folder = tmp_path / "scenarios"
    folder.mkdir()
    (folder / "short.toml").write_text(SHORT)
    real, runs, resuming = suite.run_scenario, [], False

    def run_scenario(*args, **kwargs):
        runs.append(args[2])
        if len(runs) == 3 and not resuming:
            os.kill(os.getpid(), signal.SIGINT)  # during the third run: it is cut short and left out
        return real(*args, **kwargs)

    monkeypatch.setattr(suite, "run_scenario", run_scenario)
    out = tmp_path / "suite"
    assert main(["suite", str(folder), "--seeds", "2", "--out", str(out)]) == 130
    assert "--resume" in capsys.readouterr().out
    done = read_jsonl(out / "runs.jsonl")
    assert [(r["seed"], r["controller"]) for r in done] == [(0, "guarded"), (0, "unguarded")]
    data = json.loads((out / "suite.json").read_text())
    assert data["interrupted"] and data["finished_runs"] == 2 and data["planned_runs"] == 8
    with (out / "runs.jsonl").open("a") as fh:
        fh.write('{"scenario": "short", "se')  # a torn line, as SIGKILL would leave
    runs.clear()
    resuming = True
    assert main(["suite", str(folder), "--seeds", "2", "--out", str(out), "--resume"]) == 0
    assert len(runs) == 6 and len(read_jsonl(out / "runs.jsonl")) == 8
    assert json.loads((out / "suite.json").read_text())["resumed_runs"] == 2
