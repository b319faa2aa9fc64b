"""Start-up cost on the car: ``import fearguard`` (and what the car uses) after numpy and cv2, vs importing numpy and cv2.

Each of 10 fresh interpreters measures, in order: ``import numpy, cv2`` (the reference), then
``import fearguard``, then ``from fearguard import FearGuard, Observation`` (what a car's loop touches),
then building ``FearGuard(steer)`` with the bundled rule file. Medians are printed as ratios to the
reference, with which heavy packages each stage loaded (scikit-fuzzy, scipy.stats, matplotlib, rich).
Usage: python benchmarks/bench_import.py [--runs N]
"""

from __future__ import annotations

import argparse
import json
import statistics
import subprocess
import sys

PROBE = r"""
import json, sys, time
heavy = ("skfuzzy", "scipy.stats", "matplotlib", "rich", "filterpy")
loaded = lambda: [m for m in heavy if m in sys.modules]
t0 = time.perf_counter(); import numpy, cv2; t1 = time.perf_counter()
import fearguard; t2 = time.perf_counter(); after_import = loaded()
from fearguard import FearGuard, Observation; t3 = time.perf_counter(); after_names = loaded()
guard = FearGuard(lambda frame: 0.0); t4 = time.perf_counter(); after_build = loaded()
print(json.dumps({"ref": t1 - t0, "import": t2 - t1, "names": t3 - t1, "build": t4 - t1,
                  "loaded": {"import": after_import, "names": after_names, "build": after_build}}))
"""


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--runs", type=int, default=10)
    args = parser.parse_args()
    runs = [json.loads(subprocess.run([sys.executable, "-c", PROBE], check=True, capture_output=True, text=True).stdout)
            for _ in range(args.runs)]
    ref = statistics.median(r["ref"] for r in runs)
    print(f"import numpy, cv2 (reference): median {1e3 * ref:.0f} ms over {args.runs} fresh interpreters")
    for key, what in (("import", "import fearguard"), ("names", "+ from fearguard import FearGuard, Observation"),
                      ("build", "+ FearGuard(steer) with the bundled rules")):
        t = statistics.median(r[key] for r in runs)
        print(f"{what:50s} {1e3 * t:7.0f} ms = {t / ref:5.2f} × reference; loaded: {', '.join(runs[-1]['loaded'][key]) or 'none of them'}")


if __name__ == "__main__":
    main()
