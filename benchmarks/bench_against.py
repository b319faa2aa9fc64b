"""This tree's speed against another checkout of fearguard, measured in one interleaved run.

    python benchmarks/bench_against.py OTHER_CHECKOUT [--rounds 5]

Two workloads, written once here against the public API both trees share, run alternately (old, new,
new, old, ...) in subprocesses with ``PYTHONPATH`` set to each tree's ``src``:

- perception: ``FearGuard(HoughLaneSteering())`` on the real road stills at 640×480 (QR localisation on,
  as ``bench_perception.py``): the median time of one ``step``;
- reference: a bare grey + Canny + probabilistic Hough pass (``cv2.HoughLinesP``) over the same whole 640×480
  frames, timed the same way in the same process: the perception step should cost no more than this classic pass;
- closed loop: bundled scenarios rendered at 320×240 → ``FearGuard.step`` → the car (as
  ``bench_closed_loop.py``): frames per second.

Times are CPU time of the measuring process (``time.process_time``), so other jobs on a shared machine
inflate both trees alike instead of whichever happened to run during a burst. Prints the median over
the rounds and the speed ratio new/old (> 1: this tree is faster).
"""

from __future__ import annotations

import argparse
import json
import os
import statistics
import subprocess
import sys
from pathlib import Path

HERE = Path(__file__).resolve().parents[1]
STILLS = HERE.parent / "shared" / "data" / "road" / "images"
PERCEPTION = "perception step ms (median, 640x480)"
BARE = "bare Canny+HoughP ms (median, 640x480)"

WORKLOAD = f"BARE = {BARE!r}\n" + r'''
import json, math, statistics, sys, time
from pathlib import Path
import cv2
import fearguard as fg
cv2.setNumThreads(1)
clock = time.process_time
out = {}
frames = [cv2.resize(cv2.imread(str(p)), (640, 480), interpolation=cv2.INTER_AREA) for p in sorted(Path(sys.argv[1]).glob("*.jpg"))]
guard = fg.FearGuard(fg.HoughLaneSteering(), vehicle=fg.VehicleLimits(has_qr_localisation=True))
steps = []
for i in range(120):
    obs = fg.Observation(t_s=0.05 * (i + 1), speed_mps=1.0, frame=frames[i % len(frames)], ultrasonic_range_m=2.0, odometer_m=0.05 * i)
    t0 = clock()
    guard.step(obs)
    steps.append(clock() - t0)
out["perception step ms (median, 640x480)"] = 1e3 * statistics.median(steps[20:])
bare = []
for i in range(120):  # the reference: a bare grey + Canny + probabilistic Hough pass over the whole frame
    t0 = clock()
    edges = cv2.Canny(cv2.cvtColor(frames[i % len(frames)], cv2.COLOR_BGR2GRAY), 50, 150)
    cv2.HoughLinesP(edges, 1, math.pi / 180, 20, minLineLength=20, maxLineGap=10)
    bare.append(clock() - t0)
out[BARE] = 1e3 * statistics.median(bare[20:])
from fearguard.sim.scenario import load_scenario
from fearguard.sim.suite import BUNDLED
from fearguard.sim.world import World
for name in ("clear_straight", "s_curves", "night", "occluding_traffic_follow_lead", "qr_markers_missing"):
    sc = load_scenario(BUNDLED / f"{name}.toml")
    world = World(sc, seed=sc.seed)
    g = fg.FearGuard(fg.HoughLaneSteering(camera=world.camera, fps=sc.camera.fps), rules=fg.load_rules(sc.rules_path),
                     vehicle=sc.vehicle.limits, camera=world.camera)
    t0 = clock()
    for _ in range(150):
        s = world.sense()
        cmd = g.step(fg.Observation(t_s=s.t_s, speed_mps=s.speed_mps, frame=s.frame_bgr, ultrasonic_range_m=s.ultrasonic_range_m,
                                    odometer_m=s.odometer_m))
        world.advance(cmd.steering_deg, min(sc.cruise_speed_mps, cmd.speed_limit_mps))
        world.truth()
    out[f"closed loop frames/s {name}"] = 150 / (clock() - t0)
print(json.dumps(out))
'''


def measure(tree: Path) -> dict[str, float]:
    env = {**os.environ, "PYTHONPATH": str(tree / "src")}
    done = subprocess.run([sys.executable, "-c", WORKLOAD, str(STILLS)], env=env, capture_output=True, text=True, check=True)
    return json.loads(done.stdout.strip().splitlines()[-1])


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("other", type=Path, help="the other checkout (its src/ is used)")
    parser.add_argument("--rounds", type=int, default=6)
    args = parser.parse_args()
    rounds: dict[str, list[dict[str, float]]] = {"old": [], "new": []}
    trees = (("old", args.other.resolve()), ("new", HERE))
    for k in range(args.rounds):
        for label, tree in trees if k % 2 == 0 else trees[::-1]:  # old, new, new, old, ...: a drift in load cancels
            rounds[label].append(measure(tree))
            print(f"round {k + 1} {label}: {rounds[label][-1]}", file=sys.stderr)
    print(f"{'figure':50s} {'old':>8s} {'new':>8s}  speed new/old")
    for key in rounds["old"][0]:
        old = statistics.median(r[key] for r in rounds["old"])
        new = statistics.median(r[key] for r in rounds["new"])
        ratio = old / new if key in (PERCEPTION, BARE) else new / old
        print(f"{key:50s} {old:8.2f} {new:8.2f}  {ratio:.3f}")
    for label, runs in rounds.items():
        if BARE in runs[0]:
            per = statistics.median(r[PERCEPTION] / r[BARE] for r in runs)
            print(f"{label}: perception step / bare Canny+HoughP {per:.3f} (goal ≤ 1, same process, same frames)")


if __name__ == "__main__":
    main()
