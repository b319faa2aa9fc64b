"""Histories: what a supervisor was fed, frame by frame, and the JSON Lines file that replays them.

A ``Step`` is one ``Observation`` plus what the wrapped steering function answers (``steer_output``,
used when no real steering function is under test) and, instead of pixels, a ``FrameSpec`` that
rebuilds the frame exactly (``frames.py``). A ``Case`` is one or more named runs of steps: most
invariants need one drive, a comparison (monotone, unknown = worst) needs two.

File format (``save_case`` / ``load_case``), one JSON object per line:

    {"fearguard": "counterexample", "version": 1, "invariant": "...", "message": "...", "rules": ..., "vehicle": {...}}
    {"run": "drive", "frame": 0, "t_s": 0.0, "speed_mps": 1.0, "lane_confidence": 0.9, ..., "steer_output": 0.0,
     "fear": 0.08, "fear_level": "VERY_LOW", "mode": "NORMAL", "strategy": "PASS_THROUGH", ...}

Every step line holds ``log.jsonl``'s names (docs/architecture.md: ``frame``, ``t_s``, the five cues, ``fear``,
``fear_level``, ``mode``, ``strategy``, ``speed_limit_mps``, ``steering_deg``, ``reasons``) and the
observation's fields (``speed_mps``, ``ultrasonic_range_m``, ``ultrasonic_echo_s``, ``odometer_m``, ``range_rate_mps``,
``qr_payload``, ``lead_bearing_deg``/``lead_range_m`` or ``lead_box_px``, ``frame_spec``). The cue fields
are the cues *given* to the supervisor (absent: perception measured them). As in ``log.jsonl``, a NaN cue
is ``null`` and ±infinity is ``"inf"``/``"-inf"``; values a JSON number cannot carry (a string where a
number belongs, bytes, ``Decimal``, a 0-d array, ``None`` as a cue) are tagged objects ``{"$": kind, "v": ...}``.
"""

from __future__ import annotations

import json
import math
from collections.abc import Iterable, Mapping
from dataclasses import dataclass, field, fields
from decimal import Decimal
from pathlib import Path
from typing import Any

import numpy as np

import fearguard as fg
from fearguard.cues import CUE_NAMES
from fearguard.errors import HistoryError  # defined in errors.py, importable here
from fearguard.files.reader import loads_json

FORMAT_VERSION = 1
OBSERVATION_NUMBERS = ("t_s", "speed_mps", "ultrasonic_range_m", "ultrasonic_echo_s", "odometer_m", "range_rate_mps")
COMMAND_FIELDS = ("fear", "fear_level", "mode", "strategy", "speed_limit_mps", "steering_deg", "reasons")


@dataclass(frozen=True)
class SteerRaises:
    """A scripted steering function that raises this exception type instead of answering."""

    exception: str = "RuntimeError"


@dataclass(frozen=True)
class FrameSpec:
    """How to rebuild one frame: ``kind`` render | synthetic | garbage, and its parameters (``frames.py``).

    ``reuse_buffer``: write the pixels into the previous step's array (same object, new content), as a
    camera driver that refills one buffer does.
    """

    kind: str
    source: str = ""  # render: scenario name; garbage: what is wrong with it
    index: int = 0  # render: frame of that scenario's pool; synthetic: random seed
    effect: str = ""  # render/synthetic: "" | dark | glare | noise | black | half_black
    offset_px: float = 0.0  # synthetic: lane centre offset
    reuse_buffer: bool = False

    def to_json(self) -> dict[str, Any]:
        return {f.name: getattr(self, f.name) for f in fields(self) if getattr(self, f.name) != f.default}

    @classmethod
    def from_json(cls, data: Mapping[str, Any]) -> FrameSpec:
        known = {f.name for f in fields(cls)}
        unknown = set(data) - known
        if unknown or "kind" not in data:
            raise ValueError(f"frame_spec needs 'kind' and only {sorted(known)}, got {sorted(data)}")
        return cls(**dict(data))


@dataclass(frozen=True)
class Step:
    """One frame of a history: the observation's fields and the scripted steering output."""

    t_s: Any
    speed_mps: Any = 0.0
    cues: fg.Cues | None = None  # given: perception is skipped
    frame: FrameSpec | None = None
    ultrasonic_range_m: Any = None
    ultrasonic_echo_s: Any = None
    range_rate_mps: Any = None  # the obstacle range's rate (m/s, − = approaching) when the caller knows it (radar)
    odometer_m: Any = None
    qr_payload: Any = None
    lead: Any = None  # fg.Lead, fg.LeadBox or None
    steer_output: Any = 0.0  # what a scripted steering function returns (a SteerRaises: it raises)


History = tuple[Step, ...]


@dataclass(frozen=True)
class Case:
    """What one example of an invariant feeds the supervisor: named runs of steps, and what they probe."""

    runs: tuple[tuple[str, History], ...]
    note: str = ""  # e.g. "occlusion worsens by 0.3 on the last frame"
    params: Mapping[str, Any] = field(default_factory=dict)  # JSON-able details the checker reads

    @classmethod
    def drive(cls, history: Iterable[Step], note: str = "", **params: Any) -> Case:
        return cls((("drive", tuple(history)),), note, params)

    def run(self, name: str) -> History:
        return dict(self.runs)[name]

    @property
    def steps(self) -> int:
        return sum(len(h) for _, h in self.runs)


# -- values JSON cannot hold ---------------------------------------------------------------------
def encode(value: Any, *, text: bool = False, nan_as_null: bool = False) -> Any:
    """A JSON value for an observation field; ``text``: a plain string is the field's natural type."""
    if value is None:
        return {"$": "none"} if nan_as_null else None
    if isinstance(value, bool):
        return value
    if isinstance(value, float):
        if math.isnan(value):
            return None if nan_as_null else "nan"
        return ("inf" if value > 0 else "-inf") if math.isinf(value) else value
    if isinstance(value, int):
        return value
    if isinstance(value, str):
        return value if text else {"$": "str", "v": value}
    if isinstance(value, bytes):
        return {"$": "bytes", "v": value.hex()}
    if isinstance(value, Decimal):
        return {"$": "decimal", "v": str(value)}
    if isinstance(value, np.ndarray) and value.ndim == 0:
        return {"$": "array0", "v": encode(value.item()), "dtype": str(value.dtype)}
    if isinstance(value, np.generic):
        return {"$": "numpy", "v": encode(value.item()), "dtype": str(value.dtype)}
    if isinstance(value, SteerRaises):
        return {"$": "raise", "v": value.exception}
    if isinstance(value, list | tuple):
        return {"$": "list", "v": [encode(v) for v in value]}
    raise TypeError(f"cannot write {type(value).__name__} {value!r} into a history")


def decode(value: Any, *, text: bool = False, nan_as_null: bool = False) -> Any:
    """The inverse of ``encode``."""
    if value is None:
        return math.nan if nan_as_null else None
    if isinstance(value, str):
        return float(value) if value in ("inf", "-inf", "nan") and not text else value
    if isinstance(value, list):
        raise ValueError("a plain list is not a value; lists are tagged {\"$\": \"list\"}")
    if not isinstance(value, dict):
        return value
    kind, v = value.get("$"), value.get("v")
    if kind == "none":
        return None
    if kind == "str":
        return str(v)
    if kind == "bytes":
        return bytes.fromhex(v)
    if kind == "decimal":
        return Decimal(v)
    if kind in ("array0", "numpy"):
        arr = np.array(decode(v), dtype=value["dtype"])
        return arr if kind == "array0" else arr[()]
    if kind == "raise":
        return SteerRaises(str(v))
    if kind == "list":
        return [decode(x) for x in v]
    raise ValueError(f"unknown tagged value {value!r}")


def step_record(run: str, index: int, step: Step, cmd: Any = None) -> dict[str, Any]:
    """One line of a history file (the command's fields added when it is known)."""
    rec: dict[str, Any] = {"run": run, "frame": index}
    for name in OBSERVATION_NUMBERS:
        value = getattr(step, name)
        if value is not None or name in ("t_s", "speed_mps"):
            rec[name] = encode(value)
    if step.cues is not None:
        rec.update({n: encode(getattr(step.cues, n), nan_as_null=True) for n in CUE_NAMES})
    if step.qr_payload is not None:
        rec["qr_payload"] = encode(step.qr_payload, text=True)
    if isinstance(step.lead, fg.Lead):
        rec["lead_bearing_deg"], rec["lead_range_m"] = encode(step.lead.bearing_deg), encode(step.lead.range_m)
    elif isinstance(step.lead, fg.LeadBox):
        rec["lead_box_px"] = [encode(v) for v in (step.lead.x_px, step.lead.y_px, step.lead.w_px, step.lead.h_px)]
    if step.frame is not None:
        rec["frame_spec"] = step.frame.to_json()
    rec["steer_output"] = encode(step.steer_output)
    if cmd is not None:
        rec.update(
            fear=encode(float(cmd.fear)), fear_level=cmd.fear_level.name, mode=cmd.mode.name, strategy=cmd.strategy.name,
            speed_limit_mps=encode(float(cmd.speed_limit_mps)), steering_deg=encode(float(cmd.steering_deg)),
            reasons=list(cmd.reasons),
        )
    return rec


def step_from_record(rec: Mapping[str, Any]) -> Step:
    """The Step a history line describes (the command fields are ignored: replay recomputes them)."""
    numbers = {name: decode(rec.get(name)) for name in OBSERVATION_NUMBERS}
    if "speed_mps" not in rec:
        numbers["speed_mps"] = 0.0  # a hand-written history may leave the car standing
    cues = None
    if any(n in rec for n in CUE_NAMES):
        missing = [n for n in CUE_NAMES if n not in rec]
        if missing:
            raise ValueError(f"a step with cues needs all five cue fields, missing {missing}")
        cues = fg.Cues(**{n: decode(rec[n], nan_as_null=True) for n in CUE_NAMES})
    lead: Any = None
    if "lead_bearing_deg" in rec:
        lead = fg.Lead(decode(rec["lead_bearing_deg"]), decode(rec.get("lead_range_m")))
    elif "lead_box_px" in rec:
        lead = fg.LeadBox(*(decode(v) for v in rec["lead_box_px"]))
    frame = FrameSpec.from_json(rec["frame_spec"]) if rec.get("frame_spec") is not None else None
    qr = rec.get("qr_payload")
    return Step(
        t_s=numbers["t_s"], speed_mps=numbers["speed_mps"], cues=cues, frame=frame,
        ultrasonic_range_m=numbers["ultrasonic_range_m"], ultrasonic_echo_s=numbers["ultrasonic_echo_s"],
        range_rate_mps=numbers["range_rate_mps"],
        odometer_m=numbers["odometer_m"], qr_payload=decode(qr, text=True), lead=lead, steer_output=decode(rec.get("steer_output", 0.0)),
    )


def save_case(path: str | Path, case: Case, header: Mapping[str, Any], commands: Mapping[str, list[Any]] | None = None) -> Path:
    """Write a case as JSON Lines: the header, then every step of every run (with its command, if given)."""
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    head = {"fearguard": "counterexample", "version": FORMAT_VERSION, **header, "note": case.note, "params": dict(case.params)}
    lines = [json.dumps(head, allow_nan=False)]
    for name, history in case.runs:
        cmds = (commands or {}).get(name) or []
        for i, step in enumerate(history):
            lines.append(json.dumps(step_record(name, i, step, cmds[i] if i < len(cmds) else None), allow_nan=False))
    path.write_text("\n".join(lines) + "\n", encoding="utf-8")
    return path


def load_case(path: str | Path) -> tuple[dict[str, Any], Case]:
    """Read a history file back: (header, case). A file without a header is one run named "drive"."""
    path = Path(path)
    try:
        text = path.read_text(encoding="utf-8")
    except FileNotFoundError:
        raise HistoryError(path, None, "no such file; give a history written by `fearguard verify`") from None
    except (OSError, UnicodeDecodeError) as exc:
        raise HistoryError(path, None, f"cannot be read as UTF-8 text ({exc})") from None
    header: dict[str, Any] = {}
    runs: dict[str, list[Step]] = {}
    for n, line in enumerate(text.splitlines(), start=1):
        if not line.strip():
            continue
        try:
            rec = loads_json(line)
        except json.JSONDecodeError as exc:
            raise HistoryError(path, n, f"not JSON ({exc.msg})") from None
        except ValueError as exc:  # beyond the reader's bounds: too long, too deep, a too-big integer
            raise HistoryError(path, n, str(exc)) from None
        if not isinstance(rec, dict):
            raise HistoryError(path, n, "each line must be a JSON object")
        if rec.get("fearguard") == "counterexample":
            header = rec
            continue
        if "t_s" not in rec:
            raise HistoryError(path, n, "a step needs a t_s field")
        try:
            step = step_from_record(rec)
        except (ValueError, TypeError, KeyError) as exc:
            raise HistoryError(path, n, str(exc)) from None
        runs.setdefault(str(rec.get("run", "drive")), []).append(step)
    if not runs:
        raise HistoryError(path, None, "holds no steps")
    case = Case(tuple((k, tuple(v)) for k, v in runs.items()), str(header.get("note", "")), dict(header.get("params", {})))
    return header, case
