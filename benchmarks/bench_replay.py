"""Replay speed on 1280×720 video, decoding included, one core: frames/s, against plain decoding in the same run.

    python benchmarks/bench_replay.py

Replays the first FRAMES frames of project_video.mp4 (../shared/data) with `fearguard replay`'s engine (no
--video, no plots), and times a plain cv2.VideoCapture read of the same frames. Goal: ≥ 100 frames/s.
"""

from __future__ import annotations

import tempfile
import time
from pathlib import Path

import cv2

from fearguard.replay.run import ReplayOptions, replay

VIDEO = Path(__file__).resolve().parents[2] / "shared" / "data" / "road" / "video" / "project_video.mp4"
FRAMES = 400
ROUNDS = 3


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


def main() -> None:
    cv2.setNumThreads(1)
    for k in range(ROUNDS):
        d, r = decode_fps(), replay_fps()
        print(f"round {k + 1}: replay {r:.0f} frames/s (1280×720, decoding included), plain decoding {d:.0f} frames/s, "
              f"replay / decoding = {r / d:.2f}")


if __name__ == "__main__":
    main()
