"""The easy real drives at every frame size a user has: no EMERGENCY, fear very low or low on most frames.

    python benchmarks/eval_replay_sizes.py [--every N]

Replays solidWhiteRight.mp4 and solidYellowLeft.mp4 (../shared/data/road/video) through ``FearGuard`` (the
Hough-lane steering, a car without range sensor or QR localisation) at the native 960×540, at 320×240 and at
Donkey's 160×120 (resized with INTER_AREA, aspect not kept: what a small camera delivers), and prints per video
and size: frames, EMERGENCY frames, the share of frames with fear level VERY_LOW or LOW, and the median
lane_confidence. Issue 11's goal: no EMERGENCY, ≥ 80 % very low/low.
"""

from __future__ import annotations

import argparse
import statistics
from dataclasses import dataclass
from pathlib import Path

import cv2

import fearguard as fg

VIDEOS = Path(__file__).resolve().parents[2] / "shared" / "data" / "road" / "video"
NAMES = ("solidWhiteRight.mp4", "solidYellowLeft.mp4")
SIZES = (None, (320, 240), (160, 120))  # None: native


@dataclass(frozen=True)
class ReplayResult:
    video: str
    size: str
    frames: int
    emergency_frames: int
    calm_share: float  # share of frames with fear level VERY_LOW or LOW
    median_confidence: float


def replay(path: Path, size: tuple[int, int] | None, every: int = 1) -> ReplayResult:
    """One video through a fresh supervisor at one frame size (every: use every Nth frame, time kept real)."""
    cap = cv2.VideoCapture(str(path))
    fps = cap.get(cv2.CAP_PROP_FPS) or 25.0
    guard = fg.FearGuard(fg.HoughLaneSteering(), vehicle=fg.VehicleLimits(has_ultrasonic=False, has_qr_localisation=False))
    modes, levels, confidences, i = [], [], [], 0
    native = ""
    while True:
        ok, frame = cap.read()
        if not ok:
            break
        native = f"{frame.shape[1]}×{frame.shape[0]}"
        if i % every == 0:
            if size is not None:
                frame = cv2.resize(frame, size, interpolation=cv2.INTER_AREA)
            cmd = guard.step(fg.Observation(t_s=i / fps, speed_mps=1.0, frame=frame))
            modes.append(cmd.mode)
            levels.append(cmd.fear_level)
            confidences.append(cmd.cues.lane_confidence)
        i += 1
    cap.release()
    calm = sum(lv <= fg.FearLevel.LOW for lv in levels) / max(1, len(levels))
    label = native if size is None else f"{size[0]}×{size[1]}"
    return ReplayResult(path.name, label, len(levels), sum(m is fg.Mode.EMERGENCY for m in modes), calm,
                        statistics.median(confidences) if confidences else float("nan"))


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--every", type=int, default=1, help="use every Nth frame (default: all)")
    args = parser.parse_args()
    for name in NAMES:
        for size in SIZES:
            r = replay(VIDEOS / name, size, args.every)
            print(f"{r.video:22s} {r.size:>8s}: {r.frames} frames, EMERGENCY {r.emergency_frames}, "
                  f"very low/low {100 * r.calm_share:.1f} %, median confidence {r.median_confidence:.2f}")


if __name__ == "__main__":
    main()
