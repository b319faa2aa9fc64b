"""Closed-loop speed: rendered 320×240 frames → perception → supervisor → car, frames per second, one core.

    python benchmarks/bench_closed_loop.py

Runs bundled scenarios closed loop (guarded) and times each stage: render (World.sense), perception +
fear + policy (FearGuard.step), world update (advance + truth). Also times cv2.imdecode of a 320×240 JPEG
in the same run, as the machine's yardstick. Goal: ≥ 200 closed-loop frames/s.
"""

from __future__ import annotations

import statistics
import time

import cv2
import numpy as np

from fearguard.fuzzy.loader import load_rules
from fearguard.observation import Observation
from fearguard.sim.scenario import load_scenario
from fearguard.sim.suite import BUNDLED
from fearguard.sim.world import World
from fearguard.supervisor import FearGuard
from fearguard.vision.lane_steering import HoughLaneSteering

SCENARIOS = ("clear_straight", "s_curves", "night", "occluding_traffic_follow_lead", "qr_markers_missing")
FRAMES = 200


def run(name: str) -> dict[str, list[float]]:
    sc = load_scenario(BUNDLED / f"{name}.toml")
    world = World(sc, seed=sc.seed)
    lanes = HoughLaneSteering(camera=world.camera, fps=sc.camera.fps)
    guard = FearGuard(lanes, rules=load_rules(sc.rules_path), vehicle=sc.vehicle.limits, camera=world.camera)
    stages: dict[str, list[float]] = {"render": [], "perception+supervisor": [], "world": []}
    for _ in range(FRAMES):
        t0 = time.perf_counter()
        s = world.sense()
        t1 = time.perf_counter()
        cmd = guard.step(Observation(t_s=s.t_s, speed_mps=s.speed_mps, frame=s.frame_bgr, ultrasonic_range_m=s.ultrasonic_range_m,
                                     odometer_m=s.odometer_m))
        t2 = time.perf_counter()
        world.advance(cmd.steering_deg, min(sc.cruise_speed_mps, cmd.speed_limit_mps))
        world.truth()
        t3 = time.perf_counter()
        for name_, dt in zip(stages, (t1 - t0, t2 - t1, t3 - t2), strict=True):
            stages[name_].append(dt * 1e3)
    return stages


def main() -> None:
    cv2.setNumThreads(1)
    jpeg = cv2.imencode(".jpg", np.random.default_rng(0).integers(0, 255, (240, 320, 3), dtype=np.uint8))[1]
    start = time.perf_counter()
    for _ in range(500):
        cv2.imdecode(jpeg, cv2.IMREAD_COLOR)
    decode_ms = (time.perf_counter() - start) / 500 * 1e3
    print(f"yardstick: cv2.imdecode of a 320×240 JPEG {decode_ms:.3f} ms")
    for name in SCENARIOS:
        stages = run(name)
        means = {k: statistics.fmean(v) for k, v in stages.items()}
        total = sum(means.values())
        shares = ", ".join(f"{k} {v:.2f} ms ({100 * v / total:.0f} %)" for k, v in means.items())
        print(f"{name}: {1000 / total:.0f} closed-loop frames/s ({total:.2f} ms/frame = {total / decode_ms:.1f}× a decode); {shares}")


if __name__ == "__main__":
    main()
