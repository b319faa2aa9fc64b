"""The per-frame JSON Lines log: one line per frame from a Command, written flushed, read back line by line.

Used through ``recorder.Recorder`` by every driver (``fearguard run``, ``fearguard replay``, Duckietown). The
log uses the contract's names (docs/architecture.md): frame, t_s, the five cues, fear, fear_level, mode, strategy, speed_limit_mps,
steering_deg, reasons (plus extra fields a caller adds). Every line is flushed as it is written, so an
interrupted run keeps every frame it processed. JSON has no NaN or infinity: NaN (unknown) is written
as null, ±infinity as the strings "inf" / "-inf".
"""

from __future__ import annotations

import json
import math
from collections.abc import Mapping
from pathlib import Path
from typing import Any, TextIO

from fearguard.cues import CUE_NAMES
from fearguard.files.reader import loads_json
from fearguard.supervisor import Command


def json_value(value: Any) -> Any:
    """A value JSON can hold: NaN → None, ±inf → "inf"/"-inf", tuples → lists, enums → names."""
    if isinstance(value, float):
        if math.isnan(value):
            return None
        if math.isinf(value):
            return "inf" if value > 0 else "-inf"
        return value
    if isinstance(value, Mapping):
        return {str(k): json_value(v) for k, v in value.items()}
    if isinstance(value, list | tuple):
        return [json_value(v) for v in value]
    if hasattr(value, "name") and hasattr(value, "value"):
        return value.name
    return value


def command_record(frame: int, t_s: float, cmd: Command | None, **extra: Any) -> dict[str, Any]:
    """One log line: the contract's fields (docs/architecture.md) from a Command (None: unsupervised run), plus extras."""
    record: dict[str, Any] = {"frame": frame, "t_s": t_s}
    if cmd is not None:
        record.update(zip(CUE_NAMES, cmd.cues.values(), strict=True))
        record.update(
            fear=cmd.fear, fear_level=cmd.fear_level.name, mode=cmd.mode.name, strategy=cmd.strategy.name,
            speed_limit_mps=cmd.speed_limit_mps, steering_deg=cmd.steering_deg, reasons=list(cmd.reasons),
            cause=cmd.cause.value if cmd.cause is not None else "fault",
        )
    record.update(extra)
    return {k: json_value(v) for k, v in record.items()}


class JsonlLog:
    """Append-only JSON Lines file, one flushed line per frame (a crash keeps every line written)."""

    def __init__(self, path: str | Path) -> None:
        self.path = Path(path)
        self.path.parent.mkdir(parents=True, exist_ok=True)
        self._file: TextIO = self.path.open("w", encoding="utf-8")
        self.lines = 0

    def write(self, record: Mapping[str, Any]) -> None:
        self._file.write(json.dumps(record, allow_nan=False, separators=(",", ":")) + "\n")
        self._file.flush()
        self.lines += 1

    def close(self) -> None:
        self._file.close()

    def __enter__(self) -> JsonlLog:
        return self

    def __exit__(self, *exc: object) -> None:
        self.close()


def read_jsonl(path: str | Path) -> list[dict[str, Any]]:
    """Every complete line of a JSON Lines log (a torn last line from a killed writer is left out)."""
    records = []
    for line in Path(path).read_text(encoding="utf-8").splitlines():
        if line.strip():
            try:
                records.append(loads_json(line))
            except ValueError:  # JSONDecodeError, or beyond the reader's bounds
                break
    return records
