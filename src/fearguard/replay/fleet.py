"""A fleet of recordings replayed as a plan: one row and one folder per recording, and the fleet's table.

``fearguard replay REC1 REC2 ...`` (a class of Donkey cars' tubs after a rules change, a week of drives) is a plan of
``"replay"`` rows (``drive/plan.py``), so it runs through ``run_plan`` like every suite: one after the other, or on Dask
(``--jobs``, ``--scheduler``), appended to runs.jsonl as each finishes and resumable. A row's options are the command's
replay options as JSON values (the vehicle and the steering function by name: a worker resolves them itself), with
absolute paths, so a worker on another machine finds the same files on the shared data path (docs/cluster.md).

``run_row`` replays one recording into its folder (``replay.run.replay``: log.jsonl, summary.json, timeline.png...) and
returns the summary's key numbers: frames, time in each mode, emergency episodes and the causes of their frames. A
recording that cannot be read is a row with its error (the rest of the fleet still runs). ``merge`` writes the table:
replays.md for a person, replays.json for a program.
"""

from __future__ import annotations

from collections import Counter
from collections.abc import Mapping, Sequence
from pathlib import Path
from typing import Any

from fearguard.drive.interrupt import StopSignal
from fearguard.drive.plan import RunSpec
from fearguard.errors import FearguardError
from fearguard.files.steer_import import resolve_steer
from fearguard.policy.config import MODE_ORDER
from fearguard.replay.bags import BagTopics
from fearguard.replay.run import ReplayOptions, replay
from fearguard.vehicle import resolve_vehicle

TOP_CAUSES = 3  # [-] causes named per recording in the table
PATH_OPTIONS = ("rules", "camera", "vehicle", "track")  # options that may name a file: made absolute for workers elsewhere
CONTROLLER = "guarded"  # a replay is the supervisor over a recording: no baseline


def plan(recordings: Sequence[str | Path], out_dir: str | Path, options: Mapping[str, Any]) -> list[RunSpec]:
    """One row per recording: its folder under ``out_dir`` (named after the recording; a second one of the same name gets
    ``-2``), the replay ``options`` (JSON values: ``replay_options`` turns them back into ReplayOptions)."""
    out = Path(out_dir).resolve()
    shared = {k: (str(Path(v).resolve()) if k in PATH_OPTIONS and v is not None and Path(v).exists() else v) for k, v in options.items()}
    specs, used = [], Counter[str]()
    for recording in recordings:
        stem = Path(str(recording).rstrip("/\\")).stem or "recording"
        used[stem] += 1
        folder = out / (stem if used[stem] == 1 else f"{stem}-{used[stem]}")
        specs.append(RunSpec("replay", str(recording), CONTROLLER, 0,
                             {**shared, "recording": str(Path(recording).resolve()), "folder": str(folder)}))
    return specs


def replay_options(options: Mapping[str, Any]) -> ReplayOptions:
    """The ReplayOptions a row names: its JSON values, with the vehicle (preset or file) and the steering function
    (``module:function``) resolved here, in the process that replays."""
    known = set(ReplayOptions.__dataclass_fields__) - {"vehicle", "steer", "topics"}
    values = {k: v for k, v in options.items() if k in known}
    steer, _ = resolve_steer(options.get("steer"))
    return ReplayOptions(**values, vehicle=resolve_vehicle(options.get("vehicle")), steer=steer,
                         topics=BagTopics(**dict(options.get("topics") or {})))


def run_row(spec: RunSpec, stop: StopSignal | None = None) -> dict[str, Any]:
    """Replay one recording into the row's folder: the summary's key numbers (``"error"``: it could not be replayed)."""
    o = spec.options
    try:
        result = replay(o["recording"], o["folder"], replay_options(o), stop=stop)
    except FearguardError as exc:  # this recording is unreadable (or its bag has no camera): the fleet goes on
        return {"recording": spec.name, "folder": o["folder"], "error": f"{type(exc).__name__}: {exc}"}
    if result.interrupted:
        return {"interrupted": True}
    return {"recording": spec.name, "folder": o["folder"], **key_numbers(result.summary, int(o.get("every") or 1))}


def key_numbers(summary: Mapping[str, Any], every: int = 1) -> dict[str, Any]:
    """A replay summary's numbers for the fleet table: frames, seconds replayed and in each mode, emergency episodes,
    the causes of the EMERGENCY frames and of the frames with fear ≥ MEDIUM (seconds each), fear mean and max, the share
    of frames the lane was seen on and the replay's advice when it was hardly seen (replay/eyes.py)."""
    eyes = summary.get("eyes_check") or {}
    frames = int(summary.get("processed_frames") or 0)
    frame_s = every / float(summary["fps"]) if summary.get("fps") else 0.0
    modes = summary.get("mode_share", {})
    episodes = summary.get("emergency_episodes", [])
    return {
        "frames": frames, "duration_s": frames * frame_s, "mode_s": {m: float(modes.get(m, 0.0)) * frames * frame_s for m in MODE_ORDER},
        "emergency_episodes": len(episodes),
        "emergency_causes": _causes_s([e["causes"] for e in episodes], frame_s),
        "elevated_causes": _causes_s([s["causes"] for s in summary.get("elevated_fear", [])], frame_s),
        "fear_mean": summary.get("fear_mean"), "fear_max": summary.get("fear_max"),
        "lane_seen_share": eyes.get("lane_seen_share"), "eyes_advice": eyes.get("advice"),
        "processing_fps": summary.get("processing_fps"),  # timing: the machine's, not the recording's
    }


def _causes_s(counts: Sequence[Mapping[str, int]], frame_s: float) -> dict[str, float]:
    """Frames per cause summed over stretches, as seconds, most first."""
    total: Counter[str] = Counter()
    for c in counts:
        total.update(c)
    return {cause: n * frame_s for cause, n in total.most_common()}


def top_causes(row: Mapping[str, Any]) -> list[tuple[str, float]]:
    """The causes of a recording's EMERGENCY frames (else of its fear ≥ MEDIUM frames), most seconds first."""
    causes = row.get("emergency_causes") or row.get("elevated_causes") or {}
    return list(causes.items())[:TOP_CAUSES]


def merge(rows: Sequence[Mapping[str, Any]]) -> tuple[dict[str, Any], str]:
    """The fleet's JSON (rows without their specs, and totals) and markdown table, in plan order."""
    clean = [{k: v for k, v in r.items() if k != "spec"} for r in rows]
    good = [r for r in clean if "error" not in r]
    totals = {"recordings": len(clean), "failed": len(clean) - len(good), "frames": sum(r["frames"] for r in good),
              "duration_s": sum(r["duration_s"] for r in good), "emergency_episodes": sum(r["emergency_episodes"] for r in good),
              "mode_s": {m: sum(r["mode_s"][m] for r in good) for m in MODE_ORDER}}
    read = [(r["lane_seen_share"], r["frames"]) for r in good if r.get("lane_seen_share") is not None]
    read_frames = sum(n for _, n in read)
    totals["lane_seen_share"] = sum(x * n for x, n in read) / read_frames if read_frames else None
    lines = ["| recording | frames | replayed s | " + " | ".join(f"{m} s" for m in MODE_ORDER)
             + " | emergency episodes | top causes | lane seen % |", "|---|---|---|" + "---|" * len(MODE_ORDER) + "---|---|---|"]
    for r in clean:
        if "error" in r:
            lines.append(f"| {r['recording']} | – | – | " + "– | " * len(MODE_ORDER) + f"– | **{r['error']}** | – |")
            continue
        causes = ", ".join(f"{c} {s:.1f} s" for c, s in top_causes(r)) or "–"
        seen = r.get("lane_seen_share")
        lines.append(f"| {r['recording']} | {r['frames']} | {r['duration_s']:.1f} | "
                     + " | ".join(f"{r['mode_s'][m]:.1f}" for m in MODE_ORDER) + f" | {r['emergency_episodes']} | {causes} | "
                     + (f"{100 * seen:.0f} |" if seen is not None else "– |"))
    lines.append(f"| **{totals['recordings']} recordings** | {totals['frames']} | {totals['duration_s']:.1f} | "
                 + " | ".join(f"{totals['mode_s'][m]:.1f}" for m in MODE_ORDER) + f" | {totals['emergency_episodes']} | "
                 + (f"{totals['failed']} could not be replayed |" if totals["failed"] else "– |")
                 + (f" {100 * totals['lane_seen_share']:.0f} |" if totals["lane_seen_share"] is not None else " – |"))
    hardly = [r for r in good if r.get("eyes_advice")]
    if hardly:  # the camera hardly saw the lane: what would help, once for the fleet (each summary.json has its own)
        others = f" (also {', '.join(r['recording'] for r in hardly[1:])})" if len(hardly) > 1 else ""
        lines += ["", f"note: {hardly[0]['recording']}{others}: {hardly[0]['eyes_advice']}"]
    return {"recordings": clean, "totals": totals}, "\n".join(lines) + "\n"
