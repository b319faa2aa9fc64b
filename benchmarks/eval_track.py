"""Does a learnt track profile help on the car's own track, and catch what is unlike it? (issue 34, docs/learning.md)

    python benchmarks/eval_track.py [--corpus DIR] [--no-shared] [--only SOURCE,...] [--json OUT.json]

For every labelled source (the three shared model-car recordings and, with ``--corpus``, the development corpus):

1. **Own track, second half:** ``fearguard learn`` on the first half (by frame index), ``fearguard replay --track`` on
   the second half exactly as a user runs it (the source's vehicle preset and rule file, as ``eval_corpus.py``), scored at
   the second half's labelled frames: AUROC of fear for lost and degraded-or-worse, clean frames NORMAL, degraded
   frames in EMERGENCY, and over every frame of the second half the share in EMERGENCY.
2. **Across tracks:** each profile replayed on every other source's second half: frames with fear ≥ MEDIUM.
3. **The same recording, changed:** the second half darkened ×0.3, and with a box over half the lane (the middle half
   of the lower half of the picture, in one of five colours): frames with fear ≥ MEDIUM.

Sources shorter than ``MIN_FRAMES`` frames are too short to learn from and are listed as such.
"""

from __future__ import annotations

import argparse
import json
import math
import sys
import tempfile
from pathlib import Path
from typing import Any

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent))
import eval_corpus as ec
import fearguard as fg
from fearguard.replay.recordings import open_recording
from fearguard.replay.run import ReplayOptions, replay
from fearguard.track.learn import LearnOptions, learn_track
from fearguard.track.profile import save_track

MIN_FRAMES = 100  # [frames] a source shorter than this is too short to learn on half of it
BOX_COLOURS_BGR = ((40, 160, 220), (30, 30, 200), (200, 90, 30), (20, 20, 20), (235, 235, 235))
CHANGED_EVERY = 5  # [frames] the changed recordings use every 5th frame of the second half (the same frames for each change)
MEDIUM = int(fg.FearLevel.MEDIUM)


def second_half_folder(source: ec.Source, work: Path, half: int, change: str) -> Path:
    """The second half written as an image folder, changed: "dark" (×0.3) or "box<i>" (colour i over half the lane)."""
    import cv2

    folder = work / f"{source.name}-{change}"
    folder.mkdir(parents=True, exist_ok=True)
    for frame in open_recording(source.path, source.fps).iter_frames(half, None, CHANGED_EVERY):
        img = frame.image_bgr.copy()
        h, w = img.shape[:2]
        if change == "dark":
            img = (img.astype(np.float32) * 0.3).astype(np.uint8)
        else:
            img[h // 2:, w // 4: 3 * w // 4] = BOX_COLOURS_BGR[int(change[3:])]
        cv2.imwrite(str(folder / f"{frame.index:06d}.png"), img)
    return folder


def replay_rows(path: Path, options: ReplayOptions, out: Path) -> list[dict[str, Any]]:
    replay(path, out, options)
    with (out / "log.jsonl").open() as f:
        return [json.loads(line) for line in f]


def options_for(source: ec.Source, track: Path, start: int | None, fps: float | None) -> ReplayOptions:
    preset, rules = ec.KINDS[source.kind]
    return ReplayOptions(rules=str(ec.ROOT / "rules" / rules), vehicle=fg.VehicleLimits.preset(preset), fps=fps, plots=False,
                         read_ahead=False, track=str(track), start=f"{start}f" if start is not None else None)


def share_medium(rows: list[dict[str, Any]]) -> float:
    levels = [fg.FearLevel[r["fear_level"]] for r in rows if r.get("fear_level")]
    return 100.0 * sum(lv >= MEDIUM for lv in levels) / len(levels) if levels else math.nan


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--corpus", type=Path, default=None, help="also the development corpus in this folder (eval_corpus.py)")
    parser.add_argument("--no-shared", action="store_true", help="leave out ../shared/data/modelcar")
    parser.add_argument("--only", default=None, help="comma-separated source names")
    parser.add_argument("--json", type=Path, default=None, help="write every number here")
    args = parser.parse_args(argv)
    sources = ([] if args.no_shared else ec.shared_sources()) + (ec.corpus_sources(args.corpus) if args.corpus else [])
    if args.only:
        sources = [s for s in sources if s.name in set(args.only.split(","))]
    results: dict[str, dict[str, Any]] = {}
    with tempfile.TemporaryDirectory() as tmp:
        work = Path(tmp)
        tracks: dict[str, tuple[Path, int, ec.Source]] = {}
        for s in sources:
            n = open_recording(s.path, s.fps).expected_frames or 0
            if n < MIN_FRAMES:
                print(f"{s.name}: {n} frames, too short to learn on half of it", file=sys.stderr)
                continue
            half = n // 2
            learnt = learn_track([s.path], LearnOptions(fps=s.fps, stop=f"{half}f"))
            tracks[s.name] = (save_track(learnt.profile, work / f"{s.name}.npz"), half, s)
        for name, (track, half, s) in tracks.items():
            rows = replay_rows(s.path, options_for(s, track, half, s.fps), work / f"own-{name}")
            by_frame = {r["frame"]: r for r in rows}
            scored = []
            for label in s.labels:
                r = by_frame.get(ec.frame_of(s, label["key"]))
                if r is not None and r.get("fear") is not None:
                    scored.append(ec.Scored(int(label["risk"]), float(r["fear"]), str(r["mode"]), label["key"]))
            m = ec.metrics(scored, fg.load_rules(str(ec.ROOT / "rules" / ec.KINDS[s.kind][1])).policy.caution_fear)
            m["emergency_all_pct"] = 100.0 * sum(r["mode"] == "EMERGENCY" for r in rows) / max(len(rows), 1)
            changed = {}
            for change in ["dark", *(f"box{i}" for i in range(len(BOX_COLOURS_BGR)))]:
                folder = second_half_folder(s, work, half, change)
                fps = (s.fps or 20.0) / CHANGED_EVERY
                changed[change] = share_medium(replay_rows(folder, options_for(s, track, None, fps), work / f"{change}-{name}"))
            across = {}
            for other, (_, other_half, o) in tracks.items():
                if other != name:
                    opts = options_for(o, track, other_half, o.fps)
                    across[other] = share_medium(replay_rows(o.path, opts, work / f"across-{name}-{other}"))
            results[name] = {"kind": s.kind, "metrics": m, "changed_medium_pct": changed, "across_medium_pct": across}
            box = [v for k, v in changed.items() if k.startswith("box")]
            print(f"{name}: {m['n_clean']}/{m['n_degraded']}/{m['n_lost']} labelled in the 2nd half; AUROC lost "
                  f"{ec.fmt(m['auroc_lost'])} deg+ {ec.fmt(m['auroc_degraded'])}; clean NORMAL {ec.fmt(m['clean_normal_pct'], True)} %;"
                  f" degraded EMERGENCY {ec.fmt(m['degraded_emergency_pct'], True)} %; EMERGENCY on {m['emergency_all_pct']:.0f} % "
                  f"of all 2nd-half frames; ≥ MEDIUM darkened {changed['dark']:.0f} %, boxed {min(box):.0f}–{max(box):.0f} %; "
                  f"profile on other tracks ≥ MEDIUM " + ", ".join(f"{k} {v:.0f} %" for k, v in across.items()), flush=True)
    print()
    print(ec.table(results))
    if args.json:
        args.json.write_text(json.dumps(results, indent=1, default=float))
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
