"""Speed of the scenario renderer against a plain ``np.zeros`` + ``cv2.fillPoly`` road trapezoid, in the same run.

    python benchmarks/bench_render.py [SCENARIO.toml ...]

For each scenario (the bundled ones below by default) a World is driven along its lane for
FRAMES frames; the poses are recorded, then the renderer alone draws them, round after round,
alternating with the reference so both see the same machine. Prints ms/frame of the renderer, of a
whole world step (``sense`` + ``truth`` + ``advance``), and the renderer's ratio to the reference. The closed loop needs
rendering ≲ 1 ms/frame at 320×240 on one core; machines here are shared and noisy, so read the
ratio as well as the absolute time.
"""

from __future__ import annotations

import math
import statistics
import sys
import time
from pathlib import Path

import cv2
import numpy as np

from fearguard.sim.lighting import light_at
from fearguard.sim.scenario import load_scenario
from fearguard.sim.world import World

SCENARIOS = ("clear_straight", "s_curves", "night", "tree_shadows", "occluding_traffic_follow_lead", "qr_markers_missing",
             "tunnel_exit_glare", "ccrs_road")
FRAMES = 120  # [frames] per scenario
WARM_UP = 10  # [frames] before timing a whole world step
ROUNDS = 5  # [-] rounds of renderer vs reference, alternated
LOOKAHEAD_WHEELBASES = 3.0  # [-] pure-pursuit look-ahead of the recording driver


def record(world: World, frames: int) -> list[tuple]:
    """Drive along the lane centre (pure pursuit on truth) and keep each frame's render inputs."""
    sc = world.scenario
    out = []
    for _ in range(frames):
        pose = world.camera_pose()
        s_cam = float(world.road.project(pose[0], pose[1])[0])
        out.append((pose, s_cam, world.boxes(), light_at(sc.lighting, s_cam, world.t_s)))
        tr, e = world.truth(), world.ego
        look = max(LOOKAHEAD_WHEELBASES * sc.vehicle.wheelbase_m, 0.5 * tr.speed_mps)
        x, y = world.road.point_at(tr.s_m + look, 0.0)
        alpha = math.atan2(float(y) - e.y_m, float(x) - e.x_m) - e.yaw_rad
        steer = math.degrees(math.atan2(2 * sc.vehicle.wheelbase_m * math.sin(alpha), look))
        world.advance(steer, sc.vehicle.cruise_speed_mps)
    return out


def reference_s(width: int, height: int, frames: int) -> float:
    trapezoid = [np.array([[0, height], [int(0.45 * width), int(0.3 * height)], [int(0.55 * width), int(0.3 * height)],
                           [width, height]], np.int32)]
    start = time.perf_counter()
    for _ in range(frames):
        frame = np.zeros((height, width, 3), np.uint8)
        cv2.fillPoly(frame, trapezoid, (100, 100, 100))
    return (time.perf_counter() - start) / frames


def main() -> None:
    root = Path(__file__).resolve().parents[1] / "scenarios"
    paths = [Path(p) for p in sys.argv[1:]] or [root / f"{name}.toml" for name in SCENARIOS]
    print(f"{'scenario':32s} {'render ms':>10s} {'step ms':>8s} {'reference ms':>13s} {'ratio':>7s}")
    all_ratios = []
    for path in paths:
        sc = load_scenario(path)
        world = World(sc)
        inputs = record(world, FRAMES)
        renderer = world.renderer
        renders, refs, ratios = [], [], []
        for _ in range(ROUNDS):
            start = time.perf_counter()
            for args in inputs:
                renderer.render(*args)
            renders.append((time.perf_counter() - start) / len(inputs))
            refs.append(reference_s(sc.camera.width_px, sc.camera.height_px, len(inputs)))
            ratios.append(renders[-1] / refs[-1])
        fresh = World(sc)
        for _ in range(WARM_UP):  # one-off work (noise sheets, night maps, QR images) is not per-frame cost
            fresh.sense()
            fresh.advance(0.0, sc.vehicle.cruise_speed_mps)
        start = time.perf_counter()
        for _ in range(FRAMES):
            fresh.sense()
            fresh.truth()
            fresh.advance(0.0, sc.vehicle.cruise_speed_mps)
        step_s = (time.perf_counter() - start) / FRAMES
        ratio = statistics.median(ratios)
        all_ratios.append(ratio)
        print(f"{sc.name:32s} {statistics.median(renders) * 1e3:10.3f} {step_s * 1e3:8.3f} {statistics.median(refs) * 1e3:13.4f} "
              f"{ratio:6.1f}x")
    print(f"median ratio over scenarios: {statistics.median(all_ratios):.1f}x the zeros+fillPoly reference")


if __name__ == "__main__":
    main()
