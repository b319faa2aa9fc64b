"""Does something over or in the lane ahead raise occlusion and fear? Boxes on the shared road stills (issue 33).

    python benchmarks/eval_occluders.py [--json OUT.json] [--verbose]

For each of the 14 road stills of ``../shared/data/road/images``: a supervisor (``HoughLaneSteering``, no camera model,
no range sensor) watches the clean still for 5 frames, then sees it with a filled box for 3 frames. A case passes
when occlusion ≥ 0.3 and fear ≥ the clean still's fear + 0.2 (the issue's bar: ≥ 90 % of the cases). The boxes are
not the ones the tests use (``tests/perturb.py``: black, grey, white, silver, red at three placements), so that a
change is not judged on the boxes it was built with: 5 colours × 3 sizes (a share of the picture's width, 0.45× as
tall) × 3 places (the box's centre as shares of the picture; "left"/"right" lie on or near the lane's lines of most
stills). Prints the share per place × size, per colour and per still.
"""

from __future__ import annotations

import argparse
import copy
import json
import sys
from collections import defaultdict
from pathlib import Path

import cv2
import numpy as np

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))
from tests.perturb import watched, with_box  # noqa: E402  (one home for the perturbations)

import fearguard as fg  # noqa: E402

STILLS = ROOT.parent / "shared" / "data" / "road" / "images"
WARM_FRAMES = 5
BOXED_FRAMES = 3
COLOURS_BGR = {"orange": (0, 120, 240), "blue": (160, 60, 20), "green": (40, 140, 40), "brown": (40, 70, 110),
               "dark_grey": (60, 60, 60)}
PLACES = {"centre": (0.5, 0.74), "left": (0.38, 0.72), "right": (0.62, 0.72)}  # the box's centre (u, v), shares
SIZES = {"small": 0.15, "medium": 0.3, "large": 0.5}  # the box's width, share of the picture's width


def boxed(img: np.ndarray, place: tuple[float, float], size: float, colour: tuple[int, int, int]) -> np.ndarray:
    """The still with a box ``size`` of its width wide, 0.45× as tall, centred at ``place`` (shares of the picture)."""
    h, w = img.shape[:2]
    half_u, half_v = size / 2, 0.45 * size * w / h / 2
    return with_box(img, (place[0] - half_u, place[1] - half_v, place[0] + half_u, place[1] + half_v), colour)


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--json", type=Path, default=None, help="write every case here")
    parser.add_argument("--verbose", action="store_true", help="print every failing case")
    args = parser.parse_args(argv)
    paths = sorted(STILLS.glob("*.jpg"))
    if not paths:
        print(f"no road stills in {STILLS}", file=sys.stderr)
        return 2
    cases = []
    for path in paths:
        img = cv2.imread(str(path))
        guard = fg.FearGuard(fg.HoughLaneSteering(), vehicle=fg.VehicleLimits(has_ultrasonic=False, has_qr_localisation=False))
        clean = watched(guard, [img] * WARM_FRAMES)
        for place, centre in PLACES.items():
            for size, share in SIZES.items():
                for colour, bgr in COLOURS_BGR.items():
                    cmd = watched(copy.deepcopy(guard), [boxed(img, centre, share, bgr)] * BOXED_FRAMES, WARM_FRAMES)
                    ok = cmd.cues.occlusion >= 0.3 and cmd.fear >= clean.fear + 0.2
                    cases.append({"still": path.name, "place": place, "size": size, "colour": colour, "passed": bool(ok),
                                  "occlusion": cmd.cues.occlusion, "fear": cmd.fear, "clean_fear": clean.fear})
                    if args.verbose and not ok:
                        print(f"{path.name} {place} {size} {colour}: occlusion {cmd.cues.occlusion:.2f}, fear {cmd.fear:.2f} "
                              f"(clean {clean.fear:.2f})")
    groups: dict[str, list[bool]] = defaultdict(list)
    for c in cases:
        for key in (f"{c['place']} {c['size']}", c["colour"], c["still"]):
            groups[key].append(c["passed"])
    passed = sum(c["passed"] for c in cases)
    print(f"occlusion ≥ 0.3 and fear ≥ clean + 0.2: {passed} of {len(cases)} cases ({100 * passed / len(cases):.0f} %; goal ≥ 90 %)")
    for key, ok in groups.items():
        print(f"  {key}: {sum(ok)}/{len(ok)} = {100 * sum(ok) / len(ok):.0f} %")
    if args.json:
        args.json.write_text(json.dumps({"cases": cases}, indent=1), encoding="utf-8")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
