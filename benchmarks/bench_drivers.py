"""Closed-loop driver speed with its recorder: ``run_scenario`` writing log.jsonl, frames/s, this tree vs a reference.

    python benchmarks/bench_drivers.py --reference /path/to/other/checkout/src [--rounds 3]

Each round runs every scenario once with this tree's ``src`` and once with the reference's, alternating
(one process each, imports excluded from the timing), so both see the same machine load. Prints frames/s
per run and the ratio new/reference of the median frames/s per scenario; the goal is ≥ 0.95 (the
recorder, the typed metrics and the signal check cost nothing measurable per frame).
"""

from __future__ import annotations

import argparse
import json
import os
import statistics
import subprocess
import sys
import tempfile
from pathlib import Path

SRC = Path(__file__).resolve().parents[1] / "src"
SCENARIOS = ("clear_straight", "night", "occluding_traffic_follow_lead")
WORKER = """
import inspect, json, sys, time
from pathlib import Path
from fearguard.sim.loop import run_scenario
from fearguard.sim.scenario import load_scenario
scenario = load_scenario(sys.argv[1]); out = Path(sys.argv[2])
params = inspect.signature(run_scenario).parameters
kwargs = {"out_dir": out} if "out_dir" in params else {"log_path": out / "log.jsonl"}
out.mkdir(parents=True, exist_ok=True)
t0 = time.perf_counter()
result = run_scenario(scenario, scenario.seed, "guarded", **kwargs)
elapsed = time.perf_counter() - t0
print(json.dumps({"frames": result.frames, "fps": result.frames / elapsed}))
"""


def one(src: Path, scenario: Path, out: Path) -> float:
    done = subprocess.run([sys.executable, "-c", WORKER, str(scenario), str(out)], capture_output=True, text=True, check=True,
                          env={**os.environ, "PYTHONPATH": str(src)})
    return float(json.loads(done.stdout.strip().splitlines()[-1])["fps"])


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--reference", required=True, help="the src folder of the checkout to compare with")
    parser.add_argument("--rounds", type=int, default=3)
    args = parser.parse_args()
    reference = Path(args.reference)
    bundled = SRC / "fearguard" / "scenarios"
    fps: dict[tuple[str, str], list[float]] = {}
    with tempfile.TemporaryDirectory() as tmp:
        for r in range(args.rounds):
            for name in SCENARIOS:
                for label, src in (("new", SRC), ("reference", reference)) if r % 2 == 0 else (("reference", reference), ("new", SRC)):
                    value = one(src, bundled / f"{name}.toml", Path(tmp) / f"{label}-{name}-{r}")
                    fps.setdefault((name, label), []).append(value)
                    print(f"round {r} {name:32s} {label:9s} {value:7.1f} frames/s", flush=True)
    ratios = []
    print("\n| scenario | new frames/s | reference frames/s | new/reference |\n|---|---|---|---|")
    for name in SCENARIOS:
        new, ref = statistics.median(fps[(name, "new")]), statistics.median(fps[(name, "reference")])
        ratios.append(new / ref)
        print(f"| {name} | {new:.1f} | {ref:.1f} | {new / ref:.3f} |")
    print(f"\ngeometric mean new/reference: {statistics.geometric_mean(ratios):.3f} (goal ≥ 0.95)")
    return 0


if __name__ == "__main__":
    sys.exit(main())
