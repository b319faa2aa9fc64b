"""Typed, strict reading of a scenario TOML document: every error names the file, the line and the key path.

tomllib gives values without positions, so ``TomlSource.line_of`` finds a key path such as
``vehicles[1].braking[0].decel_mps2`` in the text by walking headers (``[[vehicles]]`` counted in order)
and ``key =`` lines; nested arrays of inline tables resolve to the first match after their parent
(approximate, as the file format docs say). ``Table`` reads one TOML table: it rejects unknown keys
first (a typo must never be ignored), then hands out typed values with their defaults.
"""

from __future__ import annotations

import difflib
import math
import re
from collections.abc import Iterable, Mapping, Sequence
from pathlib import Path
from typing import Any

from fearguard.errors import FearguardError

_TOKEN = re.compile(r"([A-Za-z_][A-Za-z0-9_]*)(?:\[(\d+)\])?")
_ANY_HEADER = re.compile(r"^\s*\[\[?\s*[A-Za-z_][\w.]*\s*\]\]?\s*(#.*)?$")


class ScenarioError(FearguardError):
    """A scenario file (TOML) is missing, malformed, or describes an impossible world."""

    def __init__(self, path: str | Path, where: str, problem: str) -> None:
        self.path, self.where, self.problem = str(path), where, problem
        super().__init__(f"{self.path}, {where}: {problem}")


class TomlSource:
    """The file's text, to point an error at the line a key path stands on."""

    def __init__(self, path: str | Path, text: str) -> None:
        self.path = str(path)
        self.lines = text.splitlines()

    def line_of(self, key_path: str) -> int | None:
        """1-based line of ``a[1].b.c`` (approximate inside inline tables); None if not found at all."""
        tokens = [(m.group(1), None if m.group(2) is None else int(m.group(2))) for m in _TOKEN.finditer(key_path)]
        cursor, prefix, found = 0, "", None
        for name, index in tokens:
            dotted = f"{prefix}.{name}" if prefix else name
            headers = self._headers(dotted, cursor)
            if headers:
                pick = headers[min(index or 0, len(headers) - 1)]
                cursor, prefix, found = pick, dotted, pick + 1
                continue
            if self._sub_headers(dotted, cursor):  # only deeper tables, e.g. [[road.segments]] without [road]
                prefix = dotted
                continue
            line = self._assignment(name, cursor)
            if line is None:
                return found
            cursor, prefix, found = line, dotted, line + 1
        return found

    def _headers(self, dotted: str, start: int) -> list[int]:
        pattern = re.compile(r"^\s*\[\[?\s*" + re.escape(dotted) + r"\s*\]\]?\s*(#.*)?$")
        return [n for n in range(start, len(self.lines)) if pattern.match(self.lines[n])]

    def _sub_headers(self, dotted: str, start: int) -> bool:
        pattern = re.compile(r"^\s*\[\[?\s*" + re.escape(dotted) + r"\.")
        return any(pattern.match(self.lines[n]) for n in range(start, len(self.lines)))

    def _assignment(self, name: str, start: int) -> int | None:
        """Line of ``name =`` inside the table that starts at ``start`` (stops at the next table header)."""
        pattern = re.compile(r"(^|[\s{,.])" + re.escape(name) + r"\s*=")
        for n in range(start, len(self.lines)):
            if n > start and _ANY_HEADER.match(self.lines[n]):
                return None
            if pattern.search(self.lines[n].split("#", 1)[0]):
                return n
        return None

    def error(self, key_path: str, problem: str) -> ScenarioError:
        """A ScenarioError at ``key_path`` (with its line when it can be found)."""
        line = self.line_of(key_path) if key_path else None
        where = f"line {line}, key {key_path}" if line else (f"key {key_path}" if key_path else "file")
        return ScenarioError(self.path, where, problem)


def is_number(value: object) -> bool:
    """An int or float (bool is not a number here)."""
    return isinstance(value, int | float) and not isinstance(value, bool)


class Table:
    """One TOML table at ``key_path``; unknown keys are rejected on construction."""

    def __init__(self, src: TomlSource, data: object, key_path: str, known: Iterable[str]) -> None:
        self.src, self.key_path, self.known = src, key_path, tuple(known)
        if not isinstance(data, Mapping):
            raise src.error(key_path, f"must be a table, got {type(data).__name__} {data!r}")
        self.data: Mapping[str, Any] = data
        for key in data:
            if key not in self.known:
                raise self.fail(key, f"unknown key {key!r}{_suggestion(key, self.known)}; known keys: {', '.join(self.known)}")

    def path_of(self, key: str) -> str:
        return f"{self.key_path}.{key}" if self.key_path else key

    def fail(self, key: str, problem: str) -> ScenarioError:
        return self.src.error(self.path_of(key), problem)

    def has(self, key: str) -> bool:
        return key in self.data

    def number(self, key: str, default: float | None = None, *, low: float | None = None, high: float | None = None,
               strict_low: bool = False, unit: str = "") -> float:
        """A finite number in [low, high] (``strict_low``: > low); ``default`` when absent (None = required)."""
        if key not in self.data:
            if default is None:
                raise self.fail(key, f"missing; give a number{_unit(unit)}")
            return float(default)
        return self.check_number(key, self.data[key], low=low, high=high, strict_low=strict_low, unit=unit)

    def optional_number(self, key: str, **bounds: Any) -> float | None:
        return self.number(key, **bounds) if key in self.data else None

    def check_number(self, key: str, value: object, *, low: float | None = None, high: float | None = None,
                     strict_low: bool = False, unit: str = "") -> float:
        if not is_number(value) or not math.isfinite(float(value)):  # type: ignore[arg-type]
            raise self.fail(key, f"must be a finite number{_unit(unit)}, got {value!r}")
        x = float(value)  # type: ignore[arg-type]
        if low is not None and (x <= low if strict_low else x < low):
            raise self.fail(key, f"must be {'>' if strict_low else '>='} {low:g}{_unit(unit)}, got {x:g}")
        if high is not None and x > high:
            raise self.fail(key, f"must be <= {high:g}{_unit(unit)}, got {x:g}")
        return x

    def integer(self, key: str, default: int | None = None, *, low: int | None = None, high: int | None = None) -> int:
        if key not in self.data:
            if default is None:
                raise self.fail(key, "missing; give a whole number")
            return default
        value = self.data[key]
        if not isinstance(value, int) or isinstance(value, bool):
            raise self.fail(key, f"must be a whole number, got {value!r}")
        if (low is not None and value < low) or (high is not None and value > high):
            bounds = f"in [{low}, {high}]" if high is not None else f">= {low}"
            raise self.fail(key, f"must be {bounds}, got {value}")
        return value

    def boolean(self, key: str, default: bool | None = None) -> bool:
        if key not in self.data:
            if default is None:
                raise self.fail(key, "missing; give true or false")
            return default
        value = self.data[key]
        if not isinstance(value, bool):
            raise self.fail(key, f"must be true or false, got {value!r}")
        return value

    def optional_bool(self, key: str) -> bool | None:
        return self.boolean(key) if key in self.data else None

    def string(self, key: str, default: str | None = None, *, choices: Sequence[str] | None = None) -> str:
        if key not in self.data:
            if default is None:
                hint = f"; one of {', '.join(repr(c) for c in choices)}" if choices else ""
                raise self.fail(key, f"missing{hint}")
            return default
        value = self.data[key]
        if not isinstance(value, str):
            raise self.fail(key, f"must be a string, got {value!r}")
        if choices is not None and value not in choices:
            raise self.fail(key, f"must be one of {', '.join(repr(c) for c in choices)}, got {value!r}{_suggestion(value, choices)}")
        return value

    def table(self, key: str, known: Iterable[str]) -> Table:
        """A sub-table (an empty one when absent)."""
        return Table(self.src, self.data.get(key, {}), self.path_of(key), known)

    def tables(self, key: str, known: Iterable[str]) -> list[Table]:
        """An array of tables (``[[key]]`` or ``key = [{...}, ...]``); empty when absent."""
        if key not in self.data:
            return []
        value = self.data[key]
        if not isinstance(value, list):
            raise self.fail(key, f"must be an array of tables ([[{self.path_of(key)}]]), got {value!r}")
        return [Table(self.src, item, f"{self.path_of(key)}[{i}]", known) for i, item in enumerate(value)]

    def intervals(self, key: str, unit: str = "s") -> tuple[tuple[float, float], ...]:
        """A list of [start, end] pairs with start < end (e.g. time intervals)."""
        value = self.data.get(key, [])
        if not isinstance(value, list):
            raise self.fail(key, f"must be a list of [start, end] pairs, got {value!r}")
        out = []
        for i, pair in enumerate(value):
            ok = isinstance(pair, list) and len(pair) == 2 and all(is_number(x) and math.isfinite(x) for x in pair)
            if not ok or pair[0] >= pair[1]:
                raise self.src.error(f"{self.path_of(key)}[{i}]", f"must be [start, end] with start < end [{unit}], got {pair!r}")
            out.append((float(pair[0]), float(pair[1])))
        return tuple(out)


def _unit(unit: str) -> str:
    return f" [{unit}]" if unit else ""


def _suggestion(word: str, choices: Iterable[str]) -> str:
    close = difflib.get_close_matches(word, list(choices), n=1)
    return f" (did you mean {close[0]!r}?)" if close else ""
