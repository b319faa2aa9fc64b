"""Cost of a track profile (issue 34): familiarity and the learnt floor per 160×120 frame, and learning about 5,000 frames.

    python benchmarks/bench_track.py

One core (OpenCV limited to one thread). Familiarity: the median time of ``TrackProfile.familiarity`` plus the learnt
floor's ``FloorModel.hidden`` (what a track adds to a frame) on real 160×120 tub frames, against ``cv2.imdecode`` of the
same frames as JPEG and a whole ``FearGuard.step`` without a track, measured alternately in the same run (the ratios are
what count on a noisy machine; the goal is ≤ 1 ms). Learning: ``learn_track`` on the two shared 160×120 recordings
together (2,526 + 2,607 frames; goal ≤ 1 minute), against decoding the same frames.
"""

from __future__ import annotations

import statistics
import time
from pathlib import Path

import cv2
import numpy as np

import fearguard as fg
from fearguard.replay.recordings import open_recording
from fearguard.track.learn import LearnOptions, learn_track

SHARED = Path(__file__).resolve().parents[2] / "shared" / "data" / "modelcar"
TUB, IMAGES = SHARED / "donkey-carpet-dark", SHARED / "robocar-ucsd-window" / "images"
ROUNDS = 7


def main() -> int:
    cv2.setNumThreads(1)
    frames = [f.image_bgr for f in open_recording(TUB).iter_frames(0, None, 10)]
    jpegs = [cv2.imencode(".jpg", f)[1] for f in frames]
    profile = learn_track([TUB], LearnOptions(stop="1263f")).profile
    floor = profile.floor
    assert floor is not None, "the tub's first half shows a floor"
    fam_ms, dec_ms, step_ms = [], [], []
    for _ in range(ROUNDS):
        t0 = time.perf_counter()
        for f in frames:
            profile.familiarity(f)
            floor.hidden(f)
        t1 = time.perf_counter()
        for j in jpegs:
            cv2.imdecode(j, cv2.IMREAD_COLOR)
        t2 = time.perf_counter()
        guard = fg.FearGuard(None, vehicle=fg.VehicleLimits.preset("donkey"))
        for i, f in enumerate(frames):
            guard.step(fg.Observation(t_s=0.05 * i, speed_mps=1.0, frame=f, steering_deg=0.0))
        t3 = time.perf_counter()
        n = len(frames)
        fam_ms.append((t1 - t0) / n * 1e3)
        dec_ms.append((t2 - t1) / n * 1e3)
        step_ms.append((t3 - t2) / n * 1e3)
    fam, dec, step = (statistics.median(x) for x in (fam_ms, dec_ms, step_ms))
    print(f"familiarity and floor per 160×120 frame: {fam:.3f} ms median over {ROUNDS} rounds of {len(frames)} frames "
          f"(goal ≤ 1 ms: {'met' if fam <= 1.0 else 'NOT met'}); {fam / dec:.1f}× a JPEG decode of the frame ({dec:.3f} ms), "
          f"{100 * fam / step:.0f} % of a FearGuard.step without a track ({step:.2f} ms)")
    n_frames = sum(1 for _ in open_recording(TUB).iter_frames()) + sum(1 for _ in open_recording(IMAGES).iter_frames())
    t0 = time.perf_counter()
    for path in (TUB, IMAGES):
        for f in open_recording(path).iter_frames():
            np.asarray(f.image_bgr)
    t1 = time.perf_counter()
    learnt = learn_track([TUB, IMAGES])
    t2 = time.perf_counter()
    print(f"learning {n_frames} frames ({learnt.profile.frames_learnt} learnt): {t2 - t1:.1f} s (goal ≤ 60 s: "
          f"{'met' if t2 - t1 <= 60 else 'NOT met'}); {(t2 - t1) / (t1 - t0):.1f}× reading the same frames ({t1 - t0:.1f} s)")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
