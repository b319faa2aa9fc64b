"""Does the learnt floor rank the hazards a recording holds, on sources it was not tuned on? (docs/learning.md)

    python benchmarks/eval_floor.py [--corpus DIR] [--json OUT.json]

For every model-car source with labels (the three shared recordings and the development corpus's, ``eval_corpus.py``):
the floor model (``track/floor.py``) is learnt on the first half (every 2nd frame, as ``fearguard learn`` thins a long
recording), and the share of the usual floor hidden is measured at the labelled frames of the second half. Per source
and per setting of the grid (colours × match percentile × minimum radius × the texture test on or off): AUROC of the
raw share for *lost* against the rest and for *degraded or worse* against clean, and the share of clean frames the
floor alone would alarm (the share read as the occlusion cue, ``floor.as_occlusion``, at or past the start of the
bundled rules' *heavy* term). Then each source is left out in turn: among the settings that alarm at most
``CLEAN_ALARM_MAX`` of the clean frames on every other source, the one with the best worst-source AUROC over the other
sources is chosen (then the best mean), and the left-out source is scored with it — the table prints those left-out
numbers, the worst source and the setting each choice made. A supervisor that ranks well but stops the car on its own
clean track is not useful. The raw share, not the fear: ``eval_track.py`` scores the fear of a replay with the profile
(and the boxes of the floor's own colour the texture test is for: no labelled frame holds one).
"""

from __future__ import annotations

import argparse
import itertools
import json
import math
import sys
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent))
import eval_corpus as ec
import fearguard as fg
from fearguard.replay.recordings import open_recording
from fearguard.track.floor import (
    FLOOR_COLOURS,
    MATCH_PERCENTILE,
    MIN_RADIUS_LAB,
    TEXTURE_PERCENTILE,
    as_occlusion,
    floor_view,
    learn_floor,
)

GRID = tuple(itertools.product((6, 12, 20), (80.0, 90.0, 97.0), (1.0, 8.0, 12.0, 16.0, 24.0), (None, TEXTURE_PERCENTILE)))
#   colours × percentile × min radius × texture test (None: colour alone)
LEARN_EVERY = 2  # [frames] the first half, thinned
CLEAN_ALARM_MAX = 0.1  # [-] share of a source's clean frames the floor alone may alarm
_OCCLUSION = fg.load_rules(str(ec.ROOT / "rules" / "default.toml")).variables["occlusion"]
CALM_TOP = _OCCLUSION.calm_core_top(0.0)  # the reading maps a typical frame here (supervisor._occlusion_calm)
HEAVY_START = _OCCLUSION.shapes["heavy"][1][0]  # an occlusion from here on counts toward fear "high"

Scores = tuple[float, float, float]  # AUROC lost, AUROC degraded-or-worse, share of clean frames alarmed
Setting = tuple[int, float, float, float | None]  # colours, match percentile, minimum radius, texture percentile


def source_table(source: ec.Source) -> dict[Setting, Scores]:
    """AUROC (lost, degraded-or-worse) of the raw hidden share on one source and its clean frames alarmed, per setting."""
    rec = open_recording(source.path, source.fps)
    half = (rec.expected_frames or 0) // 2
    learnt = [floor_view(f.image_bgr) for f in rec.iter_frames(0, half, LEARN_EVERY)]
    risk = {ec.frame_of(source, label["key"]): int(label["risk"]) for label in source.labels}
    later = {f.index: floor_view(f.image_bgr) for f in open_recording(source.path, source.fps).iter_frames(half, None, 1)
             if f.index in risk}
    out = {}
    for k, pct, rmin, texture in GRID:
        model = learn_floor(learnt, colours=k, percentile=pct, min_radius_lab=rmin, texture_percentile=texture)
        if model is None:
            out[(k, pct, rmin, texture)] = (math.nan, math.nan, math.nan)
            continue
        share = {i: model.hidden_in(view) for i, view in later.items()}
        by = {r: [v for i, v in share.items() if risk[i] == r] for r in (0, 1, 2)}
        alarmed = [as_occlusion(v, model.hidden_usual, CALM_TOP) >= HEAVY_START for v in by[0]]
        out[(k, pct, rmin, texture)] = (ec.auroc(by[2], by[0] + by[1]), ec.auroc(by[1] + by[2], by[0]),
                               float(np.mean(alarmed)) if alarmed else math.nan)
    return out


def mean_auroc(tables: dict[str, dict], setting: Setting, leave_out: str | None) -> float:
    values = [v for name, t in tables.items() if name != leave_out for v in t[setting][:2] if not math.isnan(v)]
    return float(np.mean(values)) if values else math.nan


def worst_auroc(tables: dict[str, dict], setting: Setting, leave_out: str | None) -> float:
    values = [v for name, t in tables.items() if name != leave_out for v in t[setting][:2] if not math.isnan(v)]
    return min(values, default=math.nan)


def worst_alarm(tables: dict[str, dict], setting: Setting, leave_out: str | None) -> float:
    values = [t[setting][2] for name, t in tables.items() if name != leave_out and not math.isnan(t[setting][2])]
    return max(values, default=0.0)


def choose(tables: dict[str, dict], leave_out: str | None) -> Setting:
    """Among the settings calm enough on the clean frames of the sources not left out, the one whose worst AUROC on
    those sources is best (then the best mean): the worst track is the one that counts."""
    calm = [g for g in GRID if worst_alarm(tables, g, leave_out) <= CLEAN_ALARM_MAX]
    if not calm:
        return min(GRID, key=lambda g: worst_alarm(tables, g, leave_out))
    return max(calm, key=lambda g: (worst_auroc(tables, g, leave_out), mean_auroc(tables, g, leave_out)))


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--corpus", type=Path, default=ec.DEFAULT_CORPUS, help="the development corpus (eval_corpus.py)")
    parser.add_argument("--json", type=Path, default=None, help="write every number here")
    args = parser.parse_args(argv)
    sources = [s for s in ec.shared_sources() + (ec.corpus_sources(args.corpus) if args.corpus.is_dir() else [])
               if s.kind == "modelcar"]
    tables = {s.name: source_table(s) for s in sources}
    current = (FLOOR_COLOURS, MATCH_PERCENTILE, MIN_RADIUS_LAB, TEXTURE_PERCENTILE)
    print("| source (left out) | setting chosen on the others | AUROC lost | AUROC deg+ | clean frames alarmed % | "
          "with the bundled setting |")
    print("|---|---|---|---|---|---|")
    left_out = {}
    for name, table in tables.items():
        best = choose(tables, name)
        left_out[name] = table[best]
        lost, deg, alarm = table[best]
        now = table[current]
        print(f"| {name} | {best} | {ec.fmt(lost)} | {ec.fmt(deg)} | {ec.fmt(100 * alarm, True)} | {ec.fmt(now[0])} / "
              f"{ec.fmt(now[1])} / {ec.fmt(100 * now[2], True)} % |")
    for i, what in enumerate(("AUROC lost", "AUROC deg+", "clean frames alarmed")):
        vals = {n: v[i] for n, v in left_out.items() if not math.isnan(v[i])}
        if vals:
            worst = (max if i == 2 else min)(vals, key=vals.get)
            print(f"left out, {what}: median {np.median(list(vals.values())):.2f}, worst {vals[worst]:.2f} ({worst})")
    overall = choose(tables, None)
    for what, g in (("chosen on all sources", overall), ("bundled", current)):
        print(f"{what}: {g}: worst AUROC {worst_auroc(tables, g, None):.2f}, mean {mean_auroc(tables, g, None):.3f}, clean "
              f"frames alarmed at most {100 * worst_alarm(tables, g, None):.0f} %")
    if args.json:
        args.json.write_text(json.dumps({n: {str(k): v for k, v in t.items()} for n, t in tables.items()}, indent=1))
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
