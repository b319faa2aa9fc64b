"""An optional sensor log recorded beside the camera, aligned to frames by time.

A log is CSV with a header row, or JSON Lines (one object per line); ``t_s`` is required, the other
known columns are optional and an empty value means "no reading in this row". A log row describes the
world at its time, so a frame at ``t_s`` sees the latest row at or before it, if that row is not older
than ``max_age_s`` (``SensorLog.at``, a binary search). Malformed lines are reported as ``LogIssue``
(1-based line numbers) and skipped, or raise ``SensorLogError`` with ``strict=True``. Rows out of time
order are reported and then sorted into place (kept: a log written by several threads is often slightly
out of order, and every row still says what was measured when).
"""

from __future__ import annotations

import csv
import json
import math
import warnings
from bisect import bisect_right
from collections.abc import Callable
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, Protocol

from fearguard.errors import SensorLogError, SensorLogWarning
from fearguard.files.reader import loads_json
from fearguard.readings import reading

MAX_AGE_S = 0.25  # [s] default: a reading older than this is not used for a frame (5 frames at 20 Hz)
NUMBER_COLUMNS = (
    "t_s", "ultrasonic_range_m", "echo_s", "speed_mps", "odometer_m", "lead_x", "lead_y", "lead_w", "lead_h",
)  # lead_*: lead vehicle's box in pixels (left, top, width, height)
TEXT_COLUMNS = ("qr_payload",)
KNOWN_COLUMNS = (*NUMBER_COLUMNS, *TEXT_COLUMNS)
CSV_SUFFIXES = (".csv",)
JSONL_SUFFIXES = (".jsonl", ".json", ".ndjson")


@dataclass(frozen=True)
class LogIssue:
    """A problem on one line of a log file (1-based); the row is skipped unless the problem says it was kept."""

    line: int
    problem: str


@dataclass(frozen=True)
class SensorSample:
    """The readings of one log row; None where the row has no value (or, for ``t_s``, when there is no row)."""

    t_s: float | None = None  # [s] time of the row these readings come from
    ultrasonic_range_m: float | None = None
    echo_s: float | None = None  # [s] ultrasonic echo time (HC-SR04: range = 171.5 m/s × echo_s)
    speed_mps: float | None = None
    odometer_m: float | None = None
    qr_payload: str | None = None
    lead_x: float | None = None  # [px] left edge of the lead vehicle's box
    lead_y: float | None = None  # [px] top edge
    lead_w: float | None = None  # [px] width
    lead_h: float | None = None  # [px] height

    def lead_box_px(self) -> tuple[float, float, float, float] | None:
        """The lead box (left, top, width, height) when all four values are present."""
        box = (self.lead_x, self.lead_y, self.lead_w, self.lead_h)
        return None if any(v is None for v in box) else box  # type: ignore[return-value]


NO_READING = SensorSample()  # what ``at`` returns when no row is recent enough


class Readings(Protocol):
    """Sensor readings aligned to frames by time: a SensorLog file, or the sensor topics of a ROS bag (replay/bags.py)."""

    columns: tuple[str, ...]  # the readings present (a column present = the car has that sensor)
    issues: tuple[LogIssue, ...]

    def at(self, t_s: float, max_age_s: float = MAX_AGE_S) -> SensorSample:
        """The readings valid at t_s (NO_READING when none is recent enough); never raises."""
        ...


@dataclass(frozen=True)
class SensorLog:
    """Rows of a sensor log sorted by t_s (stable: equal times keep file order), and what was wrong with the file."""

    path: Path
    samples: tuple[SensorSample, ...]
    issues: tuple[LogIssue, ...] = ()
    columns: tuple[str, ...] = ()  # known columns present in the file (a column present = the car has that sensor)
    unknown_columns: tuple[str, ...] = ()
    _times_s: tuple[float, ...] = field(init=False, repr=False, compare=False)

    def __post_init__(self) -> None:
        if any(s.t_s is None or not math.isfinite(s.t_s) for s in self.samples):
            raise ValueError("every SensorSample in a SensorLog needs a finite t_s")
        ordered = tuple(sorted(self.samples, key=lambda s: s.t_s))  # type: ignore[arg-type, return-value]
        object.__setattr__(self, "samples", ordered)
        object.__setattr__(self, "_times_s", tuple(s.t_s for s in ordered))

    def __len__(self) -> int:
        return len(self.samples)

    def at(self, t_s: float, max_age_s: float = MAX_AGE_S) -> SensorSample:
        """The latest row with row.t_s ≤ t_s and t_s − row.t_s ≤ max_age_s, else NO_READING; never raises."""
        try:
            t, age = float(t_s), float(max_age_s)
        except (TypeError, ValueError):
            return NO_READING
        if not math.isfinite(t) or not age >= 0.0:  # `not >=` also rejects NaN
            return NO_READING
        i = bisect_right(self._times_s, t) - 1
        if i < 0 or t - self._times_s[i] > age:
            return NO_READING
        return self.samples[i]


def load_sensor_log(path: str | Path, strict: bool = False) -> SensorLog:
    """Read a CSV or JSON Lines sensor log; malformed lines become ``issues`` (or raise with ``strict``)."""
    path = Path(path)
    try:
        data = path.read_bytes()
    except OSError as exc:
        raise SensorLogError(path, None, f"cannot read it ({exc.strerror}); give the sensor log file (.csv or .jsonl)") from exc
    lines = _decode_lines(data.removeprefix(b"\xef\xbb\xbf"))
    issues: list[LogIssue] = []

    def report(line: int, problem: str) -> None:
        if strict:
            raise SensorLogError(path, line, problem)
        issues.append(LogIssue(line, problem))

    for number, (_, ok) in enumerate(lines, start=1):
        if not ok:
            report(number, "not valid UTF-8 text")
    if _format(path, lines) == "csv":
        rows, present = _csv_rows(path, lines, report)
    else:
        rows, present = _jsonl_rows(path, lines, report)
    unknown = tuple(c for c in present if c not in KNOWN_COLUMNS)
    if unknown:
        warnings.warn(
            f"{path}: unknown columns ignored: {', '.join(unknown)} (known: {', '.join(KNOWN_COLUMNS)})", SensorLogWarning, stacklevel=2,
        )
    samples: list[SensorSample] = []
    latest: tuple[float, int] | None = None  # (t_s, line) of the latest row so far
    for number, values in rows:
        parsed = _sample(values, number, report)
        if parsed is None:
            continue
        t_s, sample = parsed
        if latest is not None and t_s < latest[0]:
            report(number, f"t_s {t_s:g} is earlier than {latest[0]:g} on line {latest[1]}; kept, sorted into place")
        else:
            latest = (t_s, number)
        samples.append(sample)
    issues.sort(key=lambda issue: issue.line)
    columns = tuple(c for c in KNOWN_COLUMNS if c in present)
    return SensorLog(path, tuple(samples), tuple(issues), columns, unknown)


Report = Callable[[int, str], None]


def _decode_lines(data: bytes) -> list[tuple[str, bool]]:
    """Lines with their endings, each decoded on its own so one bad byte costs one line, not the file."""
    out: list[tuple[str, bool]] = []
    for raw in data.splitlines(keepends=True):
        try:
            out.append((raw.decode("utf-8"), True))
        except UnicodeDecodeError:
            out.append((raw.decode("utf-8", errors="replace"), False))
    return out


def _format(path: Path, lines: list[tuple[str, bool]]) -> str:
    """"csv" or "jsonl", from the extension, else from the first non-blank character."""
    first = next((text.strip() for text, _ in lines if text.strip()), "")
    if not first:
        raise SensorLogError(path, None, "the file is empty; expected a CSV header row naming t_s, or JSON Lines objects with t_s")
    suffix = path.suffix.lower()
    kind = "csv" if suffix in CSV_SUFFIXES else "jsonl" if suffix in JSONL_SUFFIXES else ("jsonl" if first[0] in "{[" else "csv")
    if kind == "jsonl" and first.startswith("["):
        raise SensorLogError(path, 1, "a JSON array is not supported; write one JSON object per line (JSON Lines)")
    return kind


def _csv_rows(path: Path, lines: list[tuple[str, bool]], report: Report) -> tuple[list[tuple[int, dict[str, Any]]], tuple[str, ...]]:
    """(first line number, {column: text}) per data row of a CSV file with a header row."""
    bad = {number for number, (_, ok) in enumerate(lines, start=1) if not ok}
    reader = csv.reader(text for text, _ in lines)
    header: list[str] | None = None
    header_line = 0
    rows: list[tuple[int, dict[str, Any]]] = []
    while True:
        first = reader.line_num + 1
        try:
            row = next(reader)
        except StopIteration:
            break
        except csv.Error as exc:
            report(first, f"not a valid CSV row ({exc})")
            continue
        if not any(cell.strip() for cell in row):
            continue
        if header is None:
            header, header_line = [cell.strip() for cell in row], first
            _check_header(path, header, header_line)
            continue
        if bad.intersection(range(first, reader.line_num + 1)):
            continue  # already reported as not UTF-8
        if len(row) != len(header):
            report(first, f"row has {len(row)} fields but the header (line {header_line}) has {len(header)}")
            continue
        rows.append((first, dict(zip(header, row, strict=True))))
    return rows, tuple(header or ())


def _check_header(path: Path, header: list[str], line: int) -> None:
    for i, name in enumerate(header, start=1):
        if not name:
            raise SensorLogError(path, line, f"header column {i} has no name")
        if header.count(name) > 1:
            raise SensorLogError(path, line, f"header names column {name!r} twice")
    if "t_s" not in header:
        raise SensorLogError(
            path, line, f"no 't_s' column (time in seconds) in the header {header}; the first row must name the columns, "
            f"e.g. t_s,{','.join(KNOWN_COLUMNS[1:4])}",
        )


def _jsonl_rows(path: Path, lines: list[tuple[str, bool]], report: Report) -> tuple[list[tuple[int, dict[str, Any]]], tuple[str, ...]]:
    """(line number, object) per JSON Lines row, and every key seen (first appearance order)."""
    rows: list[tuple[int, dict[str, Any]]] = []
    seen: dict[str, None] = {}
    for number, (text, ok) in enumerate(lines, start=1):
        if not ok or not text.strip():
            continue
        try:
            value = loads_json(text)
        except ValueError as exc:
            report(number, f"not valid JSON ({exc})")
            continue
        if not isinstance(value, dict):
            report(number, f"expected a JSON object {{\"t_s\": ...}}, got {type(value).__name__}")
            continue
        seen.update(dict.fromkeys(value))
        rows.append((number, value))
    return rows, tuple(seen)


def _sample(values: dict[str, Any], line: int, report: Report) -> tuple[float, SensorSample] | None:
    """(t_s, SensorSample) from one row's raw values, or None (reported) if a value is malformed or t_s is missing."""
    parsed: dict[str, Any] = {}
    for name in KNOWN_COLUMNS:
        raw = values.get(name)
        if isinstance(raw, str) and not raw.strip():
            raw = None
        if raw is None:
            parsed[name] = None
        elif name in TEXT_COLUMNS:
            if isinstance(raw, dict | list):
                report(line, f"column {name!r} must be text, got {json.dumps(raw)[:40]}")
                return None
            parsed[name] = raw if isinstance(raw, str) else json.dumps(raw)
        else:
            number = _number(raw)
            if number is None:
                report(line, f"column {name!r} has {raw!r} where a number is expected")
                return None
            parsed[name] = number
    t_s = parsed["t_s"]
    if t_s is None or not math.isfinite(t_s):
        report(line, "t_s is missing" if t_s is None else f"t_s must be a finite number of seconds, got {t_s}")
        return None
    return t_s, SensorSample(**parsed)


def _number(raw: object) -> float | None:
    """A float from a JSON number or numeric text ("1.5", "inf", "nan"); None for anything else (booleans too)."""
    if isinstance(raw, str):
        try:
            return float(raw.strip())
        except ValueError:
            return None
    return reading(raw)

