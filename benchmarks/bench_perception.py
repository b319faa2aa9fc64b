"""Speed of one supervised frame: all cues + fear + command, against reading (decoding) the same frame.

    python benchmarks/bench_perception.py                       # this tree
    python benchmarks/bench_perception.py --against /work/base/src   # + ratios against another tree, interleaved

For 640×480 and 1280×720 frames made from the real road stills (../shared/data/road/images): the
median time of ``FearGuard.step`` on a frame (perception with QR scan, lane steering, fuzzy fear,
policy), the ratio to ``cv2.imdecode`` of the same frame as JPEG measured in the same run, and the
share of each stage. One core: OpenCV is limited to one thread. Goal: ≤ 5 ms median at 640×480.

``--against SRC``: the full per-frame perception (``Perception.perceive``: lanes, confidence, occlusion, lead, QR every
3rd frame) of this tree and of the tree whose ``src`` folder is SRC, each in its own worker process, timed round by round
alternately with a bare Canny + probabilistic Hough pass over the whole 640×480 frame (in this process) — the ratios
new/old and new/Hough come from one interleaved run, so machine load affects all three alike. It also prints new/old
round by round (median and quartiles): the spread of a tree against itself (``--against`` its own ``src``) is the noise
floor, about ±3 % in the median here.
"""

from __future__ import annotations

import argparse
import math
import statistics
import subprocess
import sys
import time
from pathlib import Path

import cv2
import numpy as np

import fearguard as fg

DATA = Path(__file__).resolve().parents[2] / "shared" / "data" / "road" / "images"
ROUNDS = 5  # decode and step timed alternately, round by round
FRAMES_PER_ROUND = 40


def frames_at(size: tuple[int, int]) -> list[np.ndarray]:
    return [cv2.resize(cv2.imread(str(p)), size, interpolation=cv2.INTER_AREA) for p in sorted(DATA.glob("*.jpg"))]


def bench(size: tuple[int, int]) -> None:
    frames = frames_at(size)
    jpegs = [cv2.imencode(".jpg", f)[1] for f in frames]
    guard = fg.FearGuard(fg.HoughLaneSteering(), vehicle=fg.VehicleLimits(has_qr_localisation=True))
    decode_ms, step_ms, stages, all_steps = [], [], {}, []
    t_s = 0.0
    for _ in range(ROUNDS):
        start = time.perf_counter()
        for i in range(FRAMES_PER_ROUND):
            cv2.imdecode(jpegs[i % len(jpegs)], cv2.IMREAD_COLOR)
        decode_ms.append((time.perf_counter() - start) / FRAMES_PER_ROUND * 1e3)
        per_frame = []
        for i in range(FRAMES_PER_ROUND):
            t_s += 0.05
            obs = fg.Observation(t_s=t_s, speed_mps=1.0, frame=frames[i % len(frames)], ultrasonic_range_m=2.0, odometer_m=t_s)
            start = time.perf_counter()
            cmd = guard.step(obs)
            per_frame.append((time.perf_counter() - start) * 1e3)
            all_steps.append(per_frame[-1])
            assert cmd.perceived is not None  # a frame was given: perception ran
            for name, ms in cmd.perceived.timings_ms.items():
                stages.setdefault(name, []).append(ms)
        step_ms.append(statistics.median(per_frame))
    step, decode = statistics.median(step_ms), statistics.median(decode_ms)
    print(f"{size[0]}×{size[1]}: step {step:.2f} ms median (rounds {min(step_ms):.2f}–{max(step_ms):.2f}), "
          f"mean {statistics.fmean(all_steps):.2f} ms (the QR scan runs on every 3rd frame), "
          f"JPEG decode {decode:.2f} ms, ratio step/decode {step / decode:.2f}")
    vision = statistics.median(stages["vision"])
    rest = step - vision - statistics.median(stages["ultrasonic"]) - statistics.median(stages["localisation"])
    parts = {k[7:]: statistics.fmean(v) if k == "vision.qr" else statistics.median(v) for k, v in stages.items() if k.startswith("vision.")}
    parts.update(ultrasonic=statistics.median(stages["ultrasonic"]), localisation=statistics.median(stages["localisation"]),
                 fear_policy_steer=max(0.0, rest))
    total = sum(parts.values())
    print("   stage shares (medians; qr: mean): " + ", ".join(f"{k} {v:.2f} ms ({100 * v / total:.0f} %)" for k, v in parts.items()))


WORKER = r"""
import sys, time, statistics, cv2, numpy as np
cv2.setNumThreads(1)
sys.path.insert(0, sys.argv[1])
import fearguard as fg
from fearguard.perception import Perception
from pathlib import Path
frames = [cv2.resize(cv2.imread(str(p)), (640, 480), interpolation=cv2.INTER_AREA) for p in sorted(Path(sys.argv[2]).glob("*.jpg"))]
perception = Perception(fg.VehicleLimits(has_qr_localisation=True))
t_s = 0.0
for line in sys.stdin:
    times = []
    for i in range(int(line)):
        t_s += 0.05
        obs = fg.Observation(t_s=t_s, speed_mps=1.0, frame=frames[i % len(frames)], ultrasonic_range_m=2.0, odometer_m=t_s)
        start = time.perf_counter()
        perception.perceive(obs)
        times.append((time.perf_counter() - start) * 1e3)
    print(statistics.fmean(times), flush=True)
"""


def canny_hough_ms(frames: list[np.ndarray], count: int) -> float:
    """Mean time of the bare classic pass: grey, Canny, probabilistic Hough over the whole frame."""
    start = time.perf_counter()
    for i in range(count):
        gray = cv2.cvtColor(frames[i % len(frames)], cv2.COLOR_BGR2GRAY)
        cv2.HoughLinesP(cv2.Canny(gray, 50, 150), 1, math.pi / 180, 20, minLineLength=20, maxLineGap=10)
    return (time.perf_counter() - start) / count * 1e3


def compare(against: Path, rounds: int = 40, per_round: int = 42) -> None:
    """Per-frame perception of this tree vs the tree at ``against`` and vs Canny + Hough, interleaved round by round."""
    here = Path(__file__).resolve().parents[1] / "src"
    workers = {name: subprocess.Popen([sys.executable, "-c", WORKER, str(src), str(DATA)], stdin=subprocess.PIPE,
                                      stdout=subprocess.PIPE, text=True) for name, src in (("new", here), ("old", against))}
    frames = frames_at((640, 480))
    times: dict[str, list[float]] = {"new": [], "old": [], "hough": []}
    for r in range(rounds + 1):  # round 0 warms up (imports, caches) and is not counted
        for name, proc in workers.items():
            proc.stdin.write(f"{per_round}\n")
            proc.stdin.flush()
            ms = float(proc.stdout.readline())
            if r:
                times[name].append(ms)
        ms = canny_hough_ms(frames, per_round)
        if r:
            times["hough"].append(ms)
    for proc in workers.values():
        proc.stdin.close()
        proc.wait()
    med = {k: statistics.median(v) for k, v in times.items()}
    print(f"640×480 per-frame perception (mean per round, median of {rounds} rounds): new {med['new']:.2f} ms, "
          f"old ({against}) {med['old']:.2f} ms, Canny + HoughP {med['hough']:.2f} ms")
    print(f"   ratio new/old {med['new'] / med['old']:.3f} (goal ≤ 1.05), new/Canny+Hough {med['new'] / med['hough']:.3f} (goal ≤ 1)")
    paired = statistics.quantiles([n / o for n, o in zip(times["new"], times["old"], strict=True)], n=4)  # same-round pairs
    print(f"   new/old round by round: median {paired[1]:.3f}, quartiles {paired[0]:.3f}–{paired[2]:.3f}")


def main() -> None:
    cv2.setNumThreads(1)
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--against", type=Path, help="src folder of another fearguard tree to compare with")
    parser.add_argument("--rounds", type=int, default=40, help="interleaved rounds of --against (default 40, ~30 s)")
    args = parser.parse_args()
    if args.against is not None:
        compare(args.against, args.rounds)
        return
    for size in ((640, 480), (1280, 720)):
        bench(size)


if __name__ == "__main__":
    main()
