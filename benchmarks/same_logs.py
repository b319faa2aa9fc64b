"""Do the drivers still write the same logs, byte for byte? A fingerprint of every log a refactor must not change.

    python benchmarks/same_logs.py --write REF.json      # before a refactor
    python benchmarks/same_logs.py --check REF.json      # after: exit 1 and the differing runs if any log changed

The runs (issue 32's list): ``fearguard replay`` on the three shared videos (default options), ``fearguard run`` on
every bundled scenario (guarded, seed 1) and, where gym-duckietown is installed (``bash .ci/duckietown.sh``; run this
script with that environment's python), ``fearguard duckietown loop_empty`` for 30 s. Each log.jsonl is hashed
(SHA-256) together with its line count; nothing in a log reads the wall clock, so the same code gives the same bytes.
"""

from __future__ import annotations

import argparse
import hashlib
import importlib.util
import json
import sys
import tempfile
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
VIDEOS = ROOT.parent / "shared" / "data" / "road" / "video"
VIDEO_NAMES = ("solidWhiteRight.mp4", "solidYellowLeft.mp4", "project_video.mp4")


def _digest(log: Path) -> dict[str, object]:
    data = log.read_bytes()
    return {"sha256": hashlib.sha256(data).hexdigest(), "lines": data.count(b"\n")}


def fingerprints(only: str | None = None) -> dict[str, dict[str, object]]:
    """Every run's log fingerprint, by name ("replay:VIDEO", "run:SCENARIO", "duckietown:loop_empty")."""
    from fearguard.replay.run import ReplayOptions, replay
    from fearguard.sim.scenario import load_scenario
    from fearguard.sim.suite import run_to_folder, scenario_files

    out: dict[str, dict[str, object]] = {}
    with tempfile.TemporaryDirectory(prefix="fearguard-same-logs-") as tmp:
        work = Path(tmp)
        for name in VIDEO_NAMES:
            key = f"replay:{name}"
            if only and only not in key:
                continue
            replay(VIDEOS / name, work / key, ReplayOptions(plots=False, read_ahead=False))
            out[key] = _digest(work / key / "log.jsonl")
            print(key, out[key], file=sys.stderr, flush=True)
        for path in scenario_files():
            key = f"run:{path.stem}"
            if only and only not in key:
                continue
            run_to_folder(load_scenario(path), work / key, seed=1)
            out[key] = _digest(work / key / "log.jsonl")
            print(key, out[key], file=sys.stderr, flush=True)
        if importlib.util.find_spec("gym_duckietown") is not None and (not only or only in "duckietown:loop_empty"):
            from fearguard.worlds.duckietown.drive import DriveOptions, drive

            key = "duckietown:loop_empty"
            drive(DriveOptions("loop_empty", seconds=30.0, plots=False), work / key)
            out[key] = _digest(work / key / "log.jsonl")
            print(key, out[key], file=sys.stderr, flush=True)
    return out


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    group = parser.add_mutually_exclusive_group(required=True)
    group.add_argument("--write", type=Path, help="write the fingerprints here")
    group.add_argument("--check", type=Path, help="compare with fingerprints written before")
    parser.add_argument("--only", default=None, help="only the runs whose name contains this")
    args = parser.parse_args(argv)
    now = fingerprints(args.only)
    if args.write is not None:
        old = json.loads(args.write.read_text()) if args.write.is_file() else {}
        args.write.write_text(json.dumps({**old, **now}, indent=1, sort_keys=True) + "\n")
        print(f"{len(now)} logs fingerprinted into {args.write}")
        return 0
    reference = json.loads(args.check.read_text())
    changed = [k for k in now if k in reference and reference[k] != now[k]]
    missing = [k for k in now if k not in reference]
    for k in changed:
        print(f"CHANGED {k}: {reference[k]} -> {now[k]}")
    for k in missing:
        print(f"not in the reference: {k}")
    same = len(now) - len(changed) - len(missing)
    print(f"{same} of {len(now)} logs identical byte for byte" + ("" if not changed else f"; {len(changed)} changed"))
    return 1 if changed else 0


if __name__ == "__main__":
    sys.exit(main())
