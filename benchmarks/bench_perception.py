"""Speed of one supervised frame: all cues + fear + command, against reading (decoding) the same frame.

    python benchmarks/bench_perception.py

For 640×480 and 1280×720 frames made from the real road stills (../shared/data/road/images): the
median time of ``FearGuard.step`` on a frame (perception with QR scan, lane steering, fuzzy fear,
policy), the ratio to ``cv2.imdecode`` of the same frame as JPEG measured in the same run, and the
share of each stage. One core: OpenCV is limited to one thread. Goal: ≤ 5 ms median at 640×480.
"""

from __future__ import annotations

import statistics
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


def main() -> None:
    cv2.setNumThreads(1)
    for size in ((640, 480), (1280, 720)):
        bench(size)


if __name__ == "__main__":
    main()
