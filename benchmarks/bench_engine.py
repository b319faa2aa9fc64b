"""Speed of the fuzzy engine against scikit-fuzzy's ControlSystemSimulation, measured in the same run.

    python benchmarks/bench_engine.py [RULES.toml]

Prints medians and the ratios the issue asks for (evaluate ≥ 300× faster than the reference per call,
evaluate_batch ≥ 100 000 cue vectors/s). Machines here are noisy: read the ratios, not the absolute times.
"""

from __future__ import annotations

import statistics
import sys
import time

import numpy as np

import fearguard as fg

SEED = 2026
ROUNDS = 9  # reference and engine are timed alternately, round by round, so both see the same machine
REFERENCE_CALLS = 8  # per round
EVALUATE_CALLS = 2_000  # per round
BATCH_ROWS = 200_000
STEP_CALLS = 5_000


def random_cues(n: int, rng: np.random.Generator) -> np.ndarray:
    return np.column_stack([rng.uniform(0, 1, n), rng.uniform(0, 255, n), rng.uniform(0, 1, n),
                            rng.uniform(0, 5, n), rng.uniform(0, 40, n)])


def per_call_s(fn, rows: np.ndarray) -> float:
    start = time.perf_counter()
    for row in rows:
        fn(row)
    return (time.perf_counter() - start) / len(rows)


def main() -> None:
    rules = fg.load_rules(sys.argv[1] if len(sys.argv) > 1 else None)
    rng = np.random.default_rng(SEED)
    rules.reference_fear(random_cues(1, rng)[0])  # build scikit-fuzzy's systems outside the timing
    ref, ev, ratios = [], [], []
    for _ in range(ROUNDS):
        ref.append(per_call_s(rules.reference_fear, random_cues(REFERENCE_CALLS, rng)))
        ev.append(per_call_s(rules.evaluate, random_cues(EVALUATE_CALLS, rng)))
        ratios.append(ref[-1] / ev[-1])
    ref_s, eval_s, ratio = statistics.median(ref), statistics.median(ev), statistics.median(ratios)
    x = random_cues(BATCH_ROWS, rng)
    batch = []
    for _ in range(5):
        start = time.perf_counter()
        rules.evaluate_batch(x)
        batch.append(time.perf_counter() - start)
    batch_rate = BATCH_ROWS / statistics.median(batch)
    guard = fg.FearGuard(lambda frame: 0.0, rules=rules)
    cues = [fg.Cues(*row) for row in random_cues(STEP_CALLS, rng)]
    start = time.perf_counter()
    for k, c in enumerate(cues):
        guard.step(fg.Observation(t_s=k * 0.05, speed_mps=1.0, cues=c))
    step_s = (time.perf_counter() - start) / STEP_CALLS

    print(f"rule base: {rules.path} ({len(rules.groups)} groups, {len(rules.rules)} rules)")
    print(f"scikit-fuzzy ControlSystemSimulation : {ref_s * 1e3:9.2f} ms per call")
    print(f"fearguard evaluate                   : {eval_s * 1e6:9.1f} µs per call  -> {ratio:6.0f}× faster (goal ≥ 300×; "
          f"median of {ROUNDS} interleaved rounds, range {min(ratios):.0f}–{max(ratios):.0f}×)")
    print(f"fearguard evaluate_batch             : {batch_rate:9.0f} cue vectors/s -> "
          f"{batch_rate * ref_s:6.0f}× the reference's rate (goal ≥ 100 000/s)")
    print(f"FearGuard.step (cue level)           : {step_s * 1e6:9.1f} µs per frame -> "
          f"{ref_s / step_s:6.0f}× faster than one reference call")


if __name__ == "__main__":
    main()
