"""Killed runs: N runs per signal (SIGINT, SIGTERM, SIGKILL) at seeded random moments, rotating over
``replay``, ``run``, ``run --video`` and ``suite``; every run's files are checked.

    python benchmarks/bench_signals.py [--runs-per-signal 20] [--seed 0] [--keep DIR]

First each command runs once uninterrupted (its wall time W); then each killed run gets its signal after
a delay drawn uniformly from [0.05 s, 1.1 W], so the moments cover start-up (imports), the frame loop,
the plots and, now and then, a run that had already finished. Checks, per run:

- log: every line of log.jsonl (suite: runs.jsonl) parses and the frame numbers are consecutive;
- video (``run --video``): it decodes at least (logged frames − 1) frames;
- SIGINT / SIGTERM: summary.json (suite: suite.json) says ``"interrupted": true`` and the exit code is
  130 / 143, unless the command had finished before the signal (then: interrupted false, exit 0/1) or the
  signal came after every file was final (then: interrupted false, exit 130 / 143, or exit 0/1 with the
  complete log when it came while the process was exiting and signals are ignored; counted as "late"),
  or it came during interpreter start-up before any handler existed (then: killed by the signal, nothing
  written; counted as "early").

Prints one line per run and a table of counts per signal. Takes about 10 minutes on 2 cores.
"""

from __future__ import annotations

import argparse
import json
import os
import random
import shutil
import signal
import subprocess
import sys
import tempfile
import time
from dataclasses import dataclass
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
SRC = ROOT / "src"
DATA = ROOT.parent / "shared" / "data"
SIGNALS = (signal.SIGINT, signal.SIGTERM, signal.SIGKILL)
COMMANDS = ("replay", "run", "run --video", "suite")
SHORT = "name = 'short'\nduration_s = 2.0\n[[road.segments]]\nkind = 'straight'\nlength_m = 40.0\n[expect]\nno_collision = true\n"


@dataclass
class Outcome:
    command: str
    signum: int
    delay_s: float
    exit_code: int
    finished_first: bool  # the command was done before the signal arrived
    log_ok: bool
    logged: int
    video_ok: bool | None  # None: no video asked
    decoded: int | None
    summary_ok: bool | None  # None: SIGKILL (no summary expected)
    exit_ok: bool
    note: str = ""

    @property
    def ok(self) -> bool:
        return self.log_ok and self.video_ok is not False and self.summary_ok is not False and self.exit_ok


def argv(command: str, out: Path, work: Path) -> list[str]:
    cli = [sys.executable, "-m", "fearguard.cli"]
    if command == "replay":
        return [*cli, "replay", str(DATA / "road" / "video" / "solidWhiteRight.mp4"), "--out", str(out)]
    if command == "suite":
        return [*cli, "suite", str(work / "suite_scenarios"), "--seeds", "1", "--out", str(out)]
    video = ["--video"] if command.endswith("--video") else []
    return [*cli, "run", str(SRC / "fearguard" / "scenarios" / "stationary_obstacle.toml"), "--out", str(out), *video]


def check_log(path: Path, key: str) -> tuple[bool, int, str]:
    """(every line parses and the numbers are consecutive, lines, why not)."""
    if not path.exists():
        return True, 0, "no log (stopped before the first frame)"
    lines = path.read_text(encoding="utf-8").splitlines()
    try:
        records = [json.loads(line) for line in lines]
    except json.JSONDecodeError as exc:
        return False, len(lines), f"a line does not parse: {exc}"
    numbers = [r["frame"] for r in records] if key == "frame" else []
    if numbers and numbers != list(range(numbers[0], numbers[0] + len(numbers))):
        return False, len(records), "frame numbers are not consecutive"
    return True, len(records), ""


def count_frames(path: Path) -> int:
    import cv2

    cap = cv2.VideoCapture(str(path))
    n = 0
    while cap.isOpened() and cap.read()[0]:
        n += 1
    cap.release()
    return n


def one(command: str, signum: int, delay_s: float, work: Path, k: int, full_lines: int) -> Outcome:
    """One killed run; ``full_lines``: the log lines of the same command run uninterrupted."""
    out = work / f"{k:03d}-{command.replace(' --', '-')}-{signal.Signals(signum).name}"
    env = {**os.environ, "PYTHONPATH": str(SRC)}
    proc = subprocess.Popen(argv(command, out, work), stdout=subprocess.DEVNULL, stderr=subprocess.PIPE, env=env, text=True)
    time.sleep(delay_s)
    finished_first = proc.poll() is not None
    if not finished_first:
        proc.send_signal(signum)
    try:
        _, err = proc.communicate(timeout=300)
    except subprocess.TimeoutExpired:
        proc.kill()
        _, err = proc.communicate()
    code = proc.returncode
    suite = command == "suite"
    log_ok, logged, why = check_log(out / ("runs.jsonl" if suite else "log.jsonl"), "run" if suite else "frame")
    video_ok = decoded = None
    if command.endswith("--video"):
        video = out / "annotated.mp4"
        decoded = count_frames(video) if video.exists() else 0
        video_ok = decoded >= logged - 1
    summary_ok, late, early = None, False, False
    if signum != signal.SIGKILL:
        summary = out / ("suite.json" if suite else "summary.json")
        data = json.loads(summary.read_text()) if summary.exists() else None
        if data is None and code == -signum and logged == 0 and not any(out.iterdir() if out.exists() else ()):
            summary_ok, early = True, True  # killed during interpreter start-up, before the handlers existed: nothing written, nothing lost
        elif data is None:
            summary_ok, why = False, why or "no summary"
        elif not finished_first and data.get("interrupted") is False and code == 128 + signum:
            summary_ok, late = True, True  # the signal came after every file was final: complete, and the exit code says so
        elif not finished_first and data.get("interrupted") is False and code in (0, 1) and logged == full_lines:
            # the signal came while the process was exiting, its work written (signals are ignored then, by design)
            summary_ok, late, finished_first = True, True, True
        else:
            summary_ok = data.get("interrupted") is (not finished_first)
            if summary_ok and not finished_first and not suite:
                summary_ok = data.get("passed") is not True
    if signum == signal.SIGKILL or early:
        exit_ok = finished_first or code == -signum
    else:
        exit_ok = code in (0, 1) if finished_first else code == 128 + signum
    if "Traceback" in (err or ""):
        exit_ok, why = False, why + " traceback on stderr"
    return Outcome(command, signum, delay_s, code, finished_first, log_ok, logged, video_ok, decoded, summary_ok, exit_ok,
                   why + (" signal after the work was done" if late else "")
                   + (" killed during start-up, before any handler" if early else ""))


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--runs-per-signal", type=int, default=20)
    parser.add_argument("--seed", type=int, default=0)
    parser.add_argument("--keep", default=None, help="keep the run folders here (default: a temporary folder, removed)")
    args = parser.parse_args()
    work = Path(args.keep) if args.keep else Path(tempfile.mkdtemp(prefix="fearguard-signals-"))
    work.mkdir(parents=True, exist_ok=True)
    (work / "suite_scenarios").mkdir(exist_ok=True)
    (work / "suite_scenarios" / "short.toml").write_text(SHORT)
    rng = random.Random(args.seed)
    wall: dict[str, float] = {}
    full_lines: dict[str, int] = {}
    for command in COMMANDS:  # the uninterrupted wall time of each command, and how many log lines it writes
        t0 = time.perf_counter()
        full = work / f"full-{command.replace(' --', '-')}"
        subprocess.run(argv(command, full, work), capture_output=True, env={**os.environ, "PYTHONPATH": str(SRC)}, check=False)
        wall[command] = time.perf_counter() - t0
        suite = command == "suite"
        full_lines[command] = check_log(full / ("runs.jsonl" if suite else "log.jsonl"), "run" if suite else "frame")[1]
        print(f"uninterrupted {command}: {wall[command]:.1f} s", flush=True)
    outcomes: list[Outcome] = []
    plan = [(s, COMMANDS[i % len(COMMANDS)]) for s in SIGNALS for i in range(args.runs_per_signal)]
    for k, (signum, command) in enumerate(plan):
        delay = rng.uniform(0.05, 1.1 * wall[command])
        o = one(command, signum, delay, work, k, full_lines[command])
        outcomes.append(o)
        print(f"{k:3d} {signal.Signals(signum).name:7s} {command:12s} at {delay:5.1f} s: exit {o.exit_code:4d} "
              f"{'finished first ' if o.finished_first else ''}log {'ok' if o.log_ok else 'BAD'} ({o.logged})"
              + (f" video {o.decoded}/{o.logged} {'ok' if o.video_ok else 'BAD'}" if o.video_ok is not None else "")
              + (f" summary {'ok' if o.summary_ok else 'BAD'}" if o.summary_ok is not None else "")
              + (f" exit {'ok' if o.exit_ok else 'BAD'}") + (f"  [{o.note}]" if o.note else ""), flush=True)
    print("\n| signal | runs | cut short | valid log | video ≥ logged−1 | summary says interrupted | exit code | all checks |")
    print("|---|---|---|---|---|---|---|---|")
    for signum in SIGNALS:
        rows = [o for o in outcomes if o.signum == signum]
        videos = [o for o in rows if o.video_ok is not None]
        cut = [o for o in rows if not o.finished_first]
        summaries = "–" if signum == signal.SIGKILL else f"{sum(bool(o.summary_ok) for o in cut)}/{len(cut)}"
        print(f"| {signal.Signals(signum).name} | {len(rows)} | {len(cut)} | {sum(o.log_ok for o in rows)}/{len(rows)} | "
              f"{sum(bool(o.video_ok) for o in videos)}/{len(videos)} | {summaries} | {sum(o.exit_ok for o in rows)}/{len(rows)} | "
              f"{sum(o.ok for o in rows)}/{len(rows)} |")
    if not args.keep:
        shutil.rmtree(work, ignore_errors=True)
    return 0 if all(o.ok for o in outcomes) else 1


if __name__ == "__main__":
    sys.exit(main())
