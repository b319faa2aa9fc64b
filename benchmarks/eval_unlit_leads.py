"""Vehicles without visible tail lights, drawn: boxed as the lead once seen moving; dark patches and next-lane cars not.

    python benchmarks/eval_unlit_leads.py [--cases N]

Per road (straight to R 500 m, bends R 100-250 m, bends R 40-100 m), N seeded cases (default 40) of the drawing of
tests/vision/test_lead_far_ahead.py with grey lamps (tests/vision/test_lead_unlit.py): a camera 1.2-1.6 m up with a
60-90° lens pitched 1-5°, a car 1.6-2.0 m wide 10-25 m ahead doing 0.7-1.0 × the car's 8-25 m/s, 2 s at 10 Hz with
the car's speed given. Prints how often the car in the ego lane is boxed at its bearing (1.5°) at the end, how
often the same car one lane to either side is boxed on any frame, and how often a dark patch (0.8-2.4 × 0.3-3 m,
grey 10-45) lying on the road is. docs/perception.md, "A vehicle whose tail lights are not seen", holds the table.
"""

from __future__ import annotations

import argparse
import math
import sys
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))
from tests.vision.test_bend import PAINTS, camera  # the drawings live with the tests (importable once the root is on the path)
from tests.vision.test_lead_far_ahead import BODIES, true_bearing_deg
from tests.vision.test_lead_unlit import GREY_LAMPS, dark_patch, drive, with_vehicle

ROADS = {"straight to R 500 m": None, "bends R 100-250 m": (100.0, 250.0), "bends R 40-100 m": (40.0, 100.0)}


def radius_m(rng: np.random.Generator, bend: tuple[float, float] | None) -> float:
    """A left or right bend of the row's radii; the straight row draws straight roads and R 500-2000 m half each."""
    if bend is None:
        return math.inf if rng.random() < 0.5 else float(rng.choice([-1, 1]) * rng.uniform(500.0, 2000.0))
    return float(rng.choice([-1, 1]) * rng.uniform(*bend))


def row(bend: tuple[float, float] | None, cases: int) -> tuple[int, int, int]:
    """(ego-lane car boxed, next-lane car boxed, dark patch boxed) over ``cases`` seeded cases."""
    rng = np.random.default_rng(11)
    found = beside = patch = 0
    for _ in range(cases):
        cam = camera(rng.uniform(60, 90), rng.uniform(1.2, 1.6), rng.uniform(1, 5))
        r = radius_m(rng, bend)
        lane, paint = rng.uniform(3.0, 3.8), str(rng.choice(sorted(PAINTS)))
        grey, seed = int(rng.integers(80, 141)), int(rng.integers(1000))
        own, share, ahead = rng.uniform(8, 25), rng.uniform(0.7, 1.0), rng.uniform(10, 25)
        width, body, side = rng.uniform(1.6, 2.0), BODIES[str(rng.choice(sorted(BODIES)))], float(rng.choice([-1.0, 1.0]))

        def gap(t: float, ahead: float = ahead, share: float = share, own: float = own) -> float:
            return max(7.0, ahead + (share - 1.0) * own * t)

        def car(lateral_m: float, cam=cam, r=r, width=width, body=body, gap=gap):  # the case's values bound now
            return lambda frame, t: with_vehicle(frame, cam, r, gap(t), lateral_m, width, body, lamps=GREY_LAMPS)

        last = drive(cam, r, lane, paint, grey, seed, car(0.0), own, 2.0)[-1]
        found += last.lead is not None and abs(last.lead.bearing_deg - true_bearing_deg(cam, r, gap(1.9), 0.0)) <= 1.5
        beside += any(a.lead is not None for a in drive(cam, r, lane, paint, grey, seed, car(side * lane), own, 2.0))
        lying = dark_patch(cam, r, 0.0, rng.uniform(-0.3, 0.3) * lane, rng.uniform(0.8, 2.4), rng.uniform(0.3, 3.0),
                           int(rng.integers(10, 46)))

        def still(frame, t, lying=lying, own=own, ahead=ahead):  # the patch stands on the road: it closes at the car's speed
            return lying(frame, ahead + 5 - own * t)

        patch += any(a.lead is not None for a in drive(cam, r, lane, paint, grey, seed, still, own, 2.0))
    return found, beside, patch


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--cases", type=int, default=40, help="seeded cases per road (default 40)")
    n = ap.parse_args().cases
    print("| road | lamp-less car in the ego lane boxed within 2 s | in the next lane boxed (any frame) | dark patch boxed (any frame) |")
    print("|---|---|---|---|")
    for name, bend in ROADS.items():
        found, beside, patch = row(bend, n)
        print(f"| {name} | {found} / {n} | {beside} / {n} | {patch} / {n} |", flush=True)


if __name__ == "__main__":
    main()
