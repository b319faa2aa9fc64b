"""Replay speed on 1280×720 video, one core: frames/s against plain decoding of the same file, in the same run.

    python benchmarks/bench_replay.py
    python benchmarks/bench_replay.py --against /work/base/src   # the user's figure of this tree and another, interleaved

Two figures per round, everything pinned to one core (``sched_setaffinity``):

- engine: the first FRAMES frames of project_video.mp4 (../shared/data) through `fearguard replay`'s engine
  (no --video, no plots) in this process, against a plain cv2.VideoCapture read of the same frames;
- what a user waits for: ``fearguard replay project_video.mp4 --out DIR`` as a fresh process over the whole
  video, wall time including start-up (imports) and the plots at the end, against decoding the whole file.

``--against SRC``: the user's figure for this tree and for the tree at SRC, alternating round by round, each against its
own decoding of the whole file just before (the machines here swing by ±15 % within a minute): medians and every round.

Each tree measured is byte-compiled first (``compileall``), as an installed package is: a user's runs read cached
bytecode, while a machine with PYTHONDONTWRITEBYTECODE set (as these are) would otherwise recompile fearguard's
modules on every start (~0.25 s of a 17 s replay).

Then, on a machine with more cores, the user's figure on all of them (the next frames decode on another core while
one is analysed: replay/read_ahead.py) against decoding alone on the same cores.

Goal (issue 15): the user's figure at least half the decode-only frame rate on one core.
"""

from __future__ import annotations

import argparse
import compileall
import os
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import cv2

from fearguard.replay.run import ReplayOptions, replay

VIDEO = Path(__file__).resolve().parents[2] / "shared" / "data" / "road" / "video" / "project_video.mp4"
FRAMES = 400
ROUNDS = 3
ONE_CORE = {0}


def decode_fps() -> float:
    cap = cv2.VideoCapture(str(VIDEO))
    start = time.perf_counter()
    for _ in range(FRAMES):
        cap.read()
    return FRAMES / (time.perf_counter() - start)


def replay_fps() -> float:
    with tempfile.TemporaryDirectory() as out:
        start = time.perf_counter()
        result = replay(VIDEO, out, ReplayOptions(stop=f"{FRAMES}f", plots=False))
        elapsed = time.perf_counter() - start
    assert result.summary["processed_frames"] == FRAMES
    return FRAMES / elapsed


def decode_all_fps() -> tuple[float, int]:
    """Frames/s of decoding the whole video, and its frame count."""
    cap = cv2.VideoCapture(str(VIDEO))
    n, start = 0, time.perf_counter()
    while cap.read()[0]:
        n += 1
    return n / (time.perf_counter() - start), n


def cli_fps(frames: int, src: Path | None = None, cores: set[int] = ONE_CORE) -> float:
    """Frames/s of ``fearguard replay VIDEO --out DIR`` as a user runs it: a fresh process, start-up and plots included
    (``src``: the fearguard package of another tree, ahead of the installed one; ``cores``: where it may run)."""
    env = dict(os.environ, PYTHONPATH=str(src)) if src is not None else None
    with tempfile.TemporaryDirectory() as out:
        start = time.perf_counter()
        subprocess.run([sys.executable, "-m", "fearguard.cli", "replay", str(VIDEO), "--out", out], check=True,
                       capture_output=True, env=env, preexec_fn=lambda: os.sched_setaffinity(0, cores))
        return frames / (time.perf_counter() - start)


HERE = Path(__file__).resolve().parents[1] / "src"


def byte_compile(src: Path) -> None:
    """Cached bytecode for a tree's modules, as pip writes it for an installed package."""
    compileall.compile_dir(src / "fearguard", quiet=1)


def compare(against: Path, rounds: int) -> None:
    """The user's ratio (replay / decoding) of this tree and of ``against``, interleaved round by round."""
    here = HERE
    for tree in (here, against):
        byte_compile(tree)
    ratios: dict[str, list[float]] = {"new": [], "old": []}
    for k in range(rounds):
        for name, src in (("new", here), ("old", against)):
            d_all, n = decode_all_fps()
            ratios[name].append(cli_fps(n, src) / d_all)
        print(f"round {k + 1}: ratio new {ratios['new'][-1]:.3f}, old ({against}) {ratios['old'][-1]:.3f}", flush=True)
    for name, values in ratios.items():
        print(f"{name}: median ratio {statistics.median(values):.3f} over {rounds} rounds "
              f"({', '.join(f'{v:.3f}' for v in values)})")


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--against", type=Path, help="src folder of another fearguard tree to compare with")
    parser.add_argument("--rounds", type=int, default=5, help="interleaved rounds of --against (default 5, ~3 min)")
    args = parser.parse_args()
    every_core = os.sched_getaffinity(0)
    os.sched_setaffinity(0, ONE_CORE)  # one core, for this process and the decoding
    cv2.setNumThreads(1)
    if args.against is not None:
        compare(args.against, args.rounds)
        return
    byte_compile(HERE)
    for k in range(ROUNDS):
        d, r = decode_fps(), replay_fps()
        print(f"round {k + 1}: engine: replay {r:.0f} frames/s (1280×720, decoding included), plain decoding {d:.0f} frames/s, "
              f"replay / decoding = {r / d:.2f}", flush=True)
        d_all, n = decode_all_fps()
        c = cli_fps(n)
        print(f"round {k + 1}: user: `fearguard replay` {c:.0f} frames/s over {n} frames (start-up and plots included), "
              f"decoding alone {d_all:.0f} frames/s, ratio = {c / d_all:.2f}", flush=True)
    if len(every_core) > 1:  # the frames decoded on another core while one is analysed (replay/read_ahead.py)
        os.sched_setaffinity(0, every_core)
        cv2.setNumThreads(len(every_core))
        d_all, n = decode_all_fps()
        c = cli_fps(n, cores=every_core)
        print(f"all {len(every_core)} cores: user: `fearguard replay` {c:.0f} frames/s (start-up and plots included), "
              f"decoding alone {d_all:.0f} frames/s on the same cores, ratio = {c / d_all:.2f}", flush=True)


if __name__ == "__main__":
    main()
