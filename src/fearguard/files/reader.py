"""One strict, bounded reader for every file fearguard reads (rules, scenarios, camera.toml, JSON records).

Bounded: a file is at most ``MAX_TEXT_BYTES``, nested at most ``MAX_NESTING`` levels of ``[ ]``/``{ }``
(checked on the text before tomllib or json recurse into it, so depth can never become a
RecursionError) and of tables in all (dotted keys nest without a bracket: checked on the parsed document by an
iterative walk), and holds no integer outside 64 bits (TOML's own rule; a bigger one cannot become a
float). Strict: ``Table`` reads one TOML table and rejects unknown keys first, with "did you mean" (a
typo must never be ignored), then hands out typed values with their defaults. Every failure is the
caller's ``FileError`` kind (errors.py) naming the file, the line and the key path.

tomllib gives values without positions, so ``TomlSource.line_of`` finds a key path such as
``vehicles[1].braking[0].decel_mps2`` in the text by walking headers (``[[vehicles]]`` counted in order)
and ``key =`` lines; nested arrays of inline tables resolve to the first match after their parent
(approximate, as the file format docs say). Hand-written because tomllib keeps no positions.
"""

from __future__ import annotations

import difflib
import json
import re
import tomllib
from collections.abc import Callable, Iterable, Iterator, Mapping, Sequence
from pathlib import Path
from typing import Any

from fearguard.errors import FearguardError, FileError
from fearguard.readings import finite_reading, whole_number

MAX_TEXT_BYTES = 4_000_000  # [bytes] far above any rule, scenario or camera file, or one JSON record
MAX_NESTING = 64  # [levels] of [ ] / { }: the deepest shipped file uses 3
INT_RANGE = (-(2**63), 2**63 - 1)  # TOML integers are 64-bit; JSON ones are held to the same bound

ErrorKind = Callable[[str | Path, str, str], FearguardError]  # (path, where, problem) → the error to raise

_TOKEN = re.compile(r"([A-Za-z_][A-Za-z0-9_]*)(?:\[(\d+)\])?")
_ANY_HEADER = re.compile(r"^\s*\[\[?\s*[A-Za-z_][\w.]*\s*\]\]?\s*(#.*)?$")
_OPENERS, _CLOSERS = "[{", "]}"


# -- bounds ------------------------------------------------------------------------------------
def too_deep_line(text: str, toml: bool) -> int | None:
    """1-based line where ``[ ]``/``{ }`` nesting first exceeds MAX_NESTING outside strings, else None.

    A lexical scan (strings, escapes, TOML's literal and multi-line strings and comments) so that the
    parsers, which recurse once per level, never see a text deeper than the bound.
    """
    if text.count("[") + text.count("{") <= MAX_NESTING:  # cannot be too deep: no scan needed
        return None
    depth, line, i, n = 0, 1, 0, len(text)
    while i < n:
        c = text[i]
        if c == "\n":
            line += 1
        elif c in _OPENERS:
            depth += 1
            if depth > MAX_NESTING:
                return line
        elif c in _CLOSERS:
            depth = max(0, depth - 1)
        elif c == '"' or (toml and c == "'"):
            i, line = _skip_string(text, i, line, toml)
            continue
        elif toml and c == "#":
            end = text.find("\n", i)
            i = n if end < 0 else end
            continue
        i += 1
    return None


def _skip_string(text: str, i: int, line: int, toml: bool) -> tuple[int, int]:
    """Index just after the string starting at ``i`` and the line it ends on (an unclosed one ends the text)."""
    quote = text[i] * 3 if toml and text.startswith(text[i] * 3, i) else text[i]
    escapes = quote[0] == '"'
    j = i + len(quote)
    while j < len(text):
        c = text[j]
        if escapes and c == "\\":
            line += text[j + 1 : j + 2] == "\n"
            j += 2
            continue
        if text.startswith(quote, j):
            return j + len(quote), line
        if c == "\n":
            line += 1
            if len(quote) == 1:  # a one-line string cannot span lines: the scan resumes after it
                return j + 1, line
        j += 1
    return j, line


def nesting_depth(value: object) -> int:
    """Levels of tables and arrays in a parsed document (iterative: a document of dotted keys such as
    ``a.a.a…= 1`` nests without a bracket, so the text scan cannot bound it and a recursive walk would overflow)."""
    deepest, stack = 0, [(value, 0)]
    while stack:
        item, depth = stack.pop()
        if isinstance(item, Mapping):
            children: Iterable[object] = item.values()
        elif isinstance(item, list):
            children = item
        else:
            continue
        deepest = max(deepest, depth + 1)
        stack.extend((child, depth + 1) for child in children)
    return deepest


def _big_integers(value: object, path: str = "") -> Iterator[str]:
    """Key paths of integers outside INT_RANGE (iterative; callers check ``nesting_depth`` first)."""
    stack: list[tuple[object, str]] = [(value, path)]
    while stack:
        item, where = stack.pop()
        if isinstance(item, Mapping):
            stack.extend((v, f"{where}.{k}" if where else str(k)) for k, v in reversed(list(item.items())))
        elif isinstance(item, list):
            stack.extend((v, f"{where}[{i}]") for i, v in reversed(list(enumerate(item))))
        elif isinstance(item, int) and not isinstance(item, bool) and not INT_RANGE[0] <= item <= INT_RANGE[1]:
            yield where


def loads_json(text: str) -> Any:
    """``json.loads`` within the bounds; any failure is a ValueError saying what is wrong (callers name the line)."""
    if len(text) > MAX_TEXT_BYTES:
        raise ValueError(f"{len(text)} characters, more than the {MAX_TEXT_BYTES} a record may have")
    if too_deep_line(text, toml=False) is not None:
        raise ValueError(f"nested deeper than {MAX_NESTING} levels of [ ] / {{ }}")
    try:
        value = json.loads(text)
    except RecursionError:  # unreachable after the depth scan; kept so no recursion can escape as a traceback
        raise ValueError(f"nested deeper than {MAX_NESTING} levels") from None
    depth = nesting_depth(value)
    if depth > MAX_NESTING:
        raise ValueError(f"nested {depth} levels deep, more than {MAX_NESTING}")
    for key in _big_integers(value):
        raise ValueError(f"integer at {key or 'top level'} outside the 64-bit range")
    return value


def read_text(path: str | Path, error: ErrorKind, missing_hint: str) -> str:
    """A UTF-8 text file within MAX_TEXT_BYTES, or ``error`` saying why not."""
    path = Path(path)
    try:
        size = path.stat().st_size
        if size > MAX_TEXT_BYTES:
            raise error(path, "file", f"{size} bytes, more than the {MAX_TEXT_BYTES} such a file may have")
        return path.read_text(encoding="utf-8")
    except FileNotFoundError:
        raise error(path, "file", f"no such file; {missing_hint}") from None
    except (OSError, UnicodeDecodeError) as exc:
        raise error(path, "file", f"cannot be read as UTF-8 text ({exc})") from None


def parse_toml(path: str | Path, text: str, error: ErrorKind) -> tuple[dict[str, Any], TomlSource]:
    """The parsed document and its source (for lines), within the bounds; ``error`` names line and key."""
    src = TomlSource(path, text, error)
    line = too_deep_line(text, toml=True)
    if line is not None:
        raise error(path, f"line {line}", f"nested deeper than {MAX_NESTING} levels of [ ] / {{ }}")
    try:
        data = tomllib.loads(text)
    except tomllib.TOMLDecodeError as exc:
        raise error(path, "TOML syntax", f"{exc}; fix the syntax at that line") from None
    except (ValueError, RecursionError) as exc:  # e.g. an integer of more than 4300 digits
        raise error(path, "TOML syntax", f"cannot be read ({exc})") from None
    depth = nesting_depth(data)
    if depth > MAX_NESTING:  # dotted keys (a.b.c = 1, [a.b.c]) nest without brackets
        raise error(path, "structure", f"tables nested {depth} levels deep (dotted keys or headers), more than the "
                                       f"{MAX_NESTING} a file may have; the deepest shipped file uses 3")
    for key in _big_integers(data):
        raise src.error(key, "integer outside the 64-bit range TOML allows; write a smaller number")
    return data, src


def read_toml(path: str | Path, error: ErrorKind, missing_hint: str) -> tuple[dict[str, Any], TomlSource]:
    """Read and parse a TOML file within the bounds (``read_text`` then ``parse_toml``)."""
    return parse_toml(path, read_text(path, error, missing_hint), error)


# -- positions -----------------------------------------------------------------------------------
class TomlSource:
    """The file's text, to point an error at the line a key path stands on."""

    def __init__(self, path: str | Path, text: str, error: ErrorKind = FileError) -> None:
        self.path = str(path)
        self.lines = text.splitlines()
        self.kind = error

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

    def line_containing(self, needle: str) -> int | None:
        """1-based line of the first occurrence of ``needle`` (e.g. a rule's text), None if absent."""
        return next((n + 1 for n, line in enumerate(self.lines) if needle in line), None)

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

    def error(self, key_path: str, problem: str, line: int | None = None) -> FearguardError:
        """The source's error kind at ``key_path`` (with its line when known or found)."""
        line = line or (self.line_of(key_path) if key_path else None)
        where = f"line {line}, key {key_path}" if line else (f"key {key_path}" if key_path else "file")
        return self.kind(self.path, where, problem)


# -- strict tables -------------------------------------------------------------------------------
class Table:
    """One TOML table at ``key_path``; unknown keys are rejected on construction."""

    def __init__(self, src: TomlSource, data: object, key_path: str, known: Iterable[str]) -> None:
        self.src, self.key_path, self.known = src, key_path, tuple(known)
        if not isinstance(data, Mapping):
            raise src.error(key_path, f"must be a table, got {type(data).__name__} {data!r}")
        self.data: Mapping[str, Any] = data
        for key in data:
            if key not in self.known:
                raise self.fail(key, f"unknown key {key!r}{suggestion(key, self.known)}; known keys: {', '.join(self.known)}")

    def path_of(self, key: str) -> str:
        return f"{self.key_path}.{key}" if self.key_path else key

    def fail(self, key: str, problem: str) -> FearguardError:
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
        x = finite_reading(value)
        if x is None:
            raise self.fail(key, f"must be a finite number{_unit(unit)}, got {value!r}")
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
        value = whole_number(self.data[key])
        if value is None:
            raise self.fail(key, f"must be a whole number, got {self.data[key]!r}")
        if (low is not None and value < low) or (high is not None and value > high):
            bounds = f"in [{low}, {high}]" if high is not None else f">= {low}"
            raise self.fail(key, f"must be a whole number {bounds}, got {value}")
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
            raise self.fail(key, f"must be one of {', '.join(repr(c) for c in choices)}, got {value!r}{suggestion(value, choices)}")
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
            ends = number_list(pair, 2)
            if ends is None or ends[0] >= ends[1]:
                raise self.src.error(f"{self.path_of(key)}[{i}]", f"must be [start, end] with start < end [{unit}], got {pair!r}")
            out.append((ends[0], ends[1]))
        return tuple(out)


def number_list(value: object, n: int | None = None) -> list[float] | None:
    """A list of ``n`` (any if None) finite numbers as floats, else None."""
    if not isinstance(value, list) or (n is not None and len(value) != n):
        return None
    out: list[float] = []
    for v in value:
        x = finite_reading(v)
        if x is None:
            return None
        out.append(x)
    return out


def _unit(unit: str) -> str:
    return f" [{unit}]" if unit else ""


def suggestion(word: str, choices: Iterable[str]) -> str:
    """`` (did you mean 'x'?)`` for the closest choice, or nothing."""
    close = difflib.get_close_matches(word, list(choices), n=1)
    return f" (did you mean {close[0]!r}?)" if close else ""

