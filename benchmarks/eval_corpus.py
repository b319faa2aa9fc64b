"""Does fear rank real footage the way a person does, on sources it was not tuned on? A per-source table.

    python benchmarks/eval_corpus.py [--corpus DIR] [--no-shared] [--only SOURCE,...] [--json OUT.json] [--keep DIR]

Every source is replayed exactly as a user runs ``fearguard replay`` (``replay.run.replay``: HoughLaneSteering, the
vehicle preset and the bundled rule file of its kind — road: ``road_car`` + ``rules/road_car.toml``; model car:
``donkey`` + the default rules; robot mat: ``duckiebot`` + ``rules/duckiebot.toml``), and the command at every frame
labelled by eye is read back from ``log.jsonl``. The labels use one scale (docs/perception.md, "The development
corpus"): 0 clean, 1 degraded, 2 lost. Per source:

- AUROC of fear for *lost* against the rest, and for *degraded or worse* against clean (n/a when a class is absent);
- clean frames calm: fear below the rule file's ``caution_fear`` and not in EMERGENCY;
- degraded frames in EMERGENCY; lost frames alerted (CAUTION or EMERGENCY).

The table ends with the worst source for each column — the number that counts (issue 33): an average hides the
track where the car never moves. Sources: every folder of ``--corpus`` with a ``meta.json`` (its labels in
``labels.csv`` there; the corpus is gathered outside the repository, docs/perception.md lists where each comes from
and its licence) and, unless ``--no-shared``, the three labelled model-car recordings of ``../shared/data/modelcar``.
A source left out of every tuning decision is judged out of sample; ``--only`` runs a subset.
"""

from __future__ import annotations

import argparse
import csv
import json
import math
import sys
import tempfile
from collections import defaultdict
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

import fearguard as fg
from fearguard.replay.run import ReplayOptions, replay
from fearguard.replay.sources import natural_key

ROOT = Path(__file__).resolve().parents[1]
SHARED = ROOT.parent / "shared" / "data" / "modelcar"
DEFAULT_CORPUS = Path("/work/devdata")  # frames live outside the repository (their licences: data/corpus/SOURCES.md)
CORPUS_LABELS = ROOT / "benchmarks" / "data" / "corpus"  # the labels and each source's meta.json, kept in the repository
KINDS = {  # kind → (vehicle preset, rule file)
    "road": ("road_car", "road_car.toml"),
    "modelcar": ("donkey", "default.toml"),
    "robot_mat": ("duckiebot", "duckiebot.toml"),
}
SHARED_SOURCES = {  # the shared model-car recordings: (path under modelcar/, fps, how a label's key maps to a frame)
    "robocar-ucsd-window": ("robocar-ucsd-window/images", 20.0, "image_number"),
    "donkey-carpet-dark": ("donkey-carpet-dark", 20.0, "tub_index"),
    "deeppicar-tape": ("deeppicar-tape/video01.avi", 20.0, "frame"),
}


@dataclass(frozen=True)
class Source:
    name: str
    path: Path
    kind: str
    fps: float | None
    key_is: str  # "frame" (the replay's frame index), "tub_index" (a tub's _index: the replay's too), "image_number"
    labels: tuple[dict[str, str], ...]


@dataclass(frozen=True)
class Scored:
    risk: int
    fear: float
    mode: str
    key: str


def auroc(positive: list[float], negative: list[float]) -> float:
    """P(a positive scores above a negative), ties half (Mann-Whitney U / n·m); NaN when a class is empty."""
    if not positive or not negative:
        return math.nan
    p, n = np.asarray(positive)[:, None], np.asarray(negative)[None, :]
    return float(((p > n).sum() + 0.5 * (p == n).sum()) / (p.size * n.size))


def corpus_sources(corpus: Path) -> list[Source]:
    labels: dict[str, list[dict[str, str]]] = defaultdict(list)
    if (corpus / "labels.csv").is_file():
        with (corpus / "labels.csv").open(newline="") as f:
            for row in csv.DictReader(f):
                labels[row["source"]].append(row)
    out = []
    for meta_path in sorted(corpus.glob("*/meta.json")):
        meta = json.loads(meta_path.read_text())
        name = meta["source_id"]
        if name in labels and meta.get("kind") in KINDS:
            out.append(Source(name, meta_path.parent / "frames", meta["kind"], meta.get("fps"), "frame", tuple(labels[name])))
    return out


def shared_sources() -> list[Source]:
    if not (SHARED / "labels.csv").is_file():
        return []
    with (SHARED / "labels.csv").open(newline="") as f:
        rows = list(csv.DictReader(f))
    return [Source(name, SHARED / rel, "modelcar", fps, key_is, tuple(r for r in rows if r["source"] == name))
            for name, (rel, fps, key_is) in SHARED_SOURCES.items()]


def frame_of(source: Source, key: str) -> int:
    """The replay's frame index of a label's key."""
    if source.key_is == "image_number":
        files = sorted((p for p in source.path.iterdir() if p.suffix.lower() in (".jpg", ".jpeg", ".png")),
                       key=lambda p: (natural_key(p.name), p.name))
        names = {p.name.split("_")[0]: i for i, p in enumerate(files)}
        return names[key]
    return int(key)


def score_source(source: Source, work: Path) -> list[Scored]:
    """Replay the source as a user would; the command at each labelled frame."""
    preset, rules = KINDS[source.kind]
    options = ReplayOptions(rules=str(ROOT / "rules" / rules), vehicle=fg.VehicleLimits.preset(preset), fps=source.fps,
                            plots=False, read_ahead=False)
    out = work / source.name
    replay(source.path, out, options)
    by_frame = {}
    with (out / "log.jsonl").open() as f:
        for line in f:
            row = json.loads(line)
            by_frame[row["frame"]] = row
    scored = []
    for label in source.labels:
        row = by_frame.get(frame_of(source, label["key"]))
        if row is None or row.get("fear") is None:
            continue
        scored.append(Scored(int(label["risk"]), float(row["fear"]), str(row["mode"]), label["key"]))
    return scored


def metrics(scored: list[Scored], caution_fear: float) -> dict[str, float | int]:
    clean = [s for s in scored if s.risk == 0]
    degraded = [s for s in scored if s.risk == 1]
    lost = [s for s in scored if s.risk == 2]

    def share(xs: list[Scored], pred: Any) -> float:
        return 100.0 * sum(map(pred, xs)) / len(xs) if xs else math.nan

    return {
        "n_clean": len(clean), "n_degraded": len(degraded), "n_lost": len(lost),
        "auroc_lost": auroc([s.fear for s in lost], [s.fear for s in clean + degraded]),
        "auroc_degraded": auroc([s.fear for s in degraded + lost], [s.fear for s in clean]),
        "clean_calm_pct": share(clean, lambda s: s.fear < caution_fear and s.mode != "EMERGENCY"),
        "clean_normal_pct": share(clean, lambda s: s.mode == "NORMAL"),
        "degraded_emergency_pct": share(degraded, lambda s: s.mode == "EMERGENCY"),
        "lost_alerted_pct": share(lost, lambda s: s.mode != "NORMAL"),
    }


COLUMNS = (  # (key, header, better: +1 higher, -1 lower, goal)
    ("auroc_lost", "AUROC lost", +1, 0.9), ("auroc_degraded", "AUROC deg+", +1, 0.8), ("clean_calm_pct", "clean calm %", +1, 90.0),
    ("degraded_emergency_pct", "deg EMERG %", -1, 20.0), ("lost_alerted_pct", "lost alerted %", +1, 90.0),
)


def fmt(v: float | int, percent: bool = False) -> str:
    if isinstance(v, float) and math.isnan(v):
        return "n/a"
    return f"{v:.0f}" if percent or isinstance(v, int) else f"{v:.2f}"


def table(results: dict[str, dict[str, Any]]) -> str:
    head = f"| source | kind | clean/deg/lost | {' | '.join(c[1] for c in COLUMNS)} |"
    lines = [head, "|" + "---|" * (3 + len(COLUMNS))]
    for name, r in results.items():
        m = r["metrics"]
        lines.append(f"| {name} | {r['kind']} | {m['n_clean']}/{m['n_degraded']}/{m['n_lost']} | "
                     + " | ".join(fmt(m[k], k.endswith("pct")) for k, *_ in COLUMNS) + " |")
    worst = []
    for key, header, better, goal in COLUMNS:
        vals = [(r["metrics"][key], n) for n, r in results.items() if not math.isnan(r["metrics"][key])]
        if not vals:
            continue
        v, n = (min if better > 0 else max)(vals)
        ok = (v >= goal) if better > 0 else (v <= goal)
        sign = "≥" if better > 0 else "≤"
        worst.append(f"{header} {fmt(v, key.endswith('pct'))} ({n}; goal {sign} {goal:g}: {'met' if ok else 'NOT met'})")
    lines.append("")
    lines.append("worst source: " + "; ".join(worst))
    return "\n".join(lines)


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--corpus", type=Path, default=DEFAULT_CORPUS, help="development corpus folder (meta.json per source, labels.csv)")
    parser.add_argument("--no-shared", action="store_true", help="leave out ../shared/data/modelcar")
    parser.add_argument("--only", default=None, help="comma-separated source names")
    parser.add_argument("--json", type=Path, default=None, help="write the per-source metrics and every scored frame here")
    parser.add_argument("--keep", type=Path, default=None, help="keep the replays' outputs here")
    args = parser.parse_args(argv)
    sources = corpus_sources(args.corpus) + ([] if args.no_shared else shared_sources())
    if args.only:
        wanted = set(args.only.split(","))
        sources = [s for s in sources if s.name in wanted]
    if not sources:
        print(f"no labelled sources found in {args.corpus}" + ("" if args.no_shared else f" or {SHARED}"), file=sys.stderr)
        return 2
    results: dict[str, dict[str, Any]] = {}
    with tempfile.TemporaryDirectory(prefix="fearguard-corpus-") as tmp:
        work = args.keep if args.keep is not None else Path(tmp)
        for source in sources:
            caution = fg.load_rules(ROOT / "rules" / KINDS[source.kind][1]).policy.caution_fear
            scored = score_source(source, work)
            results[source.name] = {"kind": source.kind, "metrics": metrics(scored, caution),
                                    "frames": [s.__dict__ for s in scored]}
            print(f"{source.name}: {len(scored)} labelled frames scored", file=sys.stderr, flush=True)
    print(table(results))
    if args.json is not None:
        args.json.write_text(json.dumps(results, indent=1, default=lambda v: None if isinstance(v, float) and math.isnan(v) else v))
    return 0


if __name__ == "__main__":
    sys.exit(main())
