"""Read a rule-base TOML file (tomllib) into a RuleBase, or fail naming the file, line and key.

File layout (see docs/rules.md)::

    name = "..."
    [variables.<cue>]   universe = [start, stop, step]; <term> = { trapmf = [...] }; normal_band (brightness)
    [fear]              universe and exactly the terms very_low, low, medium, high, very_high
    [groups.<name>]     cause = "collision" | "road" | "localisation"; rules = ["IF ... THEN fear IS ..."]
    [policy]            speed fractions, emergency thresholds, enter_frames, hold_s, ...
"""

from __future__ import annotations

import math
import re
import tomllib
from collections.abc import Mapping
from pathlib import Path
from typing import Any

import numpy as np

from fearguard.cues import CUE_NAMES, CUE_SPECS
from fearguard.errors import RuleError
from fearguard.fear import LEVEL_NAMES, Cause, FearLevel
from fearguard.fuzzy.membership import SHAPES, universe_grid
from fearguard.fuzzy.model import Group, Rule, Variable
from fearguard.fuzzy.rule_text import RuleSyntaxError, atoms, parse_rule
from fearguard.fuzzy.rulebase import RuleBase
from fearguard.policy import PolicyConfig

MAX_UNIVERSE_POINTS = 100_001  # [-] a finer universe makes every evaluation slow for no accuracy
PEAK_MEMBERSHIP = 0.99  # [-] a term must reach this inside its universe to be usable
TOP_KEYS = {"name", "description", "variables", "fear", "groups", "policy"}


class _Source:
    """The file's text, to find the line a key or a rule stands on (tomllib gives values only)."""

    def __init__(self, path: str, text: str) -> None:
        self.path = path
        self.lines = text.splitlines()

    def line_of(self, section: str, key: str | None = None) -> int | None:
        """1-based line of ``key`` inside ``[section]`` (or of the section header itself)."""
        start = None
        header = re.compile(r"^\s*\[\s*" + re.escape(section) + r"\s*\]\s*(#.*)?$")
        for n, line in enumerate(self.lines):
            if header.match(line):
                start = n
                break
        if start is None:
            return None
        if key is None:
            return start + 1
        pattern = re.compile(r"^\s*(?:[A-Za-z_]+\.)?" + re.escape(key) + r"\s*=")
        for n in range(start + 1, len(self.lines)):
            if self.lines[n].lstrip().startswith("["):
                break
            if pattern.match(self.lines[n]):
                return n + 1
        return start + 1

    def line_containing(self, needle: str) -> int | None:
        for n, line in enumerate(self.lines):
            if needle in line:
                return n + 1
        return None

    def error(self, problem: str, section: str, key: str | None = None, line: int | None = None) -> RuleError:
        line = line or self.line_of(section, key)
        dotted = f"{section}.{key}" if key else section
        where = f"line {line}, key {dotted}" if line else f"key {dotted}"
        return RuleError(self.path, where, problem)


def bundled_rules_path(name: str = "default.toml") -> Path:
    """Path of a rule file shipped inside the package (works after a non-editable install)."""
    from importlib import resources  # tempfile, shutil, random…: not paid by ``import fearguard``

    return Path(str(resources.files("fearguard") / "rules" / name))


def load_rules(path: str | Path | None = None) -> RuleBase:
    """Load and compile a rule base; the bundled 1:10 model-car default when no path is given."""
    path = bundled_rules_path() if path is None else Path(path)
    try:
        text = path.read_text(encoding="utf-8")
    except FileNotFoundError:
        raise RuleError(path, "file", "no such file; give the path of a rule file such as rules/default.toml") from None
    except (OSError, UnicodeDecodeError) as exc:
        raise RuleError(path, "file", f"cannot be read as UTF-8 text ({exc})") from None
    src = _Source(str(path), text)
    try:
        data = tomllib.loads(text)
    except tomllib.TOMLDecodeError as exc:
        raise RuleError(path, "TOML syntax", str(exc)) from None
    return _build(data, src)


def _build(data: Mapping[str, Any], src: _Source) -> RuleBase:
    for key in data:
        if key not in TOP_KEYS:
            raise src.error(f"unknown top-level key; expected one of {', '.join(sorted(TOP_KEYS))}", key)
    name = data.get("name", Path(src.path).stem)
    variables_table = _table(data, "variables", src)
    variables: dict[str, Variable] = {}
    for var_name in variables_table:
        section = f"variables.{var_name}"
        if var_name not in CUE_NAMES:
            raise src.error(f"unknown variable {var_name!r}; the cues are {', '.join(CUE_NAMES)}", section)
        variables[var_name] = _variable(var_name, _table(variables_table, var_name, src, section), src, section)
    fear_var = _variable("fear", _table(data, "fear", src), src, "fear")
    if list(fear_var.terms) != list(LEVEL_NAMES):
        raise src.error(f"the fear terms must be exactly {', '.join(LEVEL_NAMES)} in this order, got {', '.join(fear_var.terms)}", "fear")
    groups = _groups(_table(data, "groups", src), variables, src)
    policy_table = data.get("policy", {})
    if not isinstance(policy_table, Mapping):
        raise src.error("must be a table", "policy")
    policy = PolicyConfig.from_table(policy_table, src.path, lambda key: src.line_of("policy", key))
    return RuleBase(path=src.path, name=str(name), variables=variables, fear_variable=fear_var, groups=groups, policy=policy)


def _table(data: Mapping[str, Any], key: str, src: _Source, dotted: str | None = None) -> Mapping[str, Any]:
    dotted = dotted or key
    if key not in data:
        raise src.error("missing table", dotted)
    value = data[key]
    if not isinstance(value, Mapping) or not value:
        raise src.error("must be a non-empty table", dotted)
    return value


def _number_list(value: Any, n: int | None) -> list[float] | None:
    if not isinstance(value, list) or (n is not None and len(value) != n):
        return None
    if not all(isinstance(v, int | float) and not isinstance(v, bool) and math.isfinite(v) for v in value):
        return None
    return [float(v) for v in value]


def _variable(name: str, table: Mapping[str, Any], src: _Source, section: str) -> Variable:
    u = _number_list(table.get("universe"), 3)
    if u is None:
        raise src.error("needs universe = [start, stop, step] with finite numbers", section, "universe")
    start, stop, step = u
    if not (stop > start and step > 0 and (stop - start) / step + 1 <= MAX_UNIVERSE_POINTS):
        raise src.error(f"universe {u} must have start < stop, step > 0 and at most {MAX_UNIVERSE_POINTS} points", section, "universe")
    if abs(round((stop - start) / step) * step - (stop - start)) > 1e-9 * max(1.0, abs(stop - start)):
        raise src.error(f"universe {u}: step must divide stop - start", section, "universe")
    if (stop - start) / step < 2:
        raise src.error(f"universe {u} needs at least 3 points", section, "universe")
    grid = universe_grid(start, stop, step)
    spec = next((s for s in CUE_SPECS if s.name == name), None)
    if spec is not None and (start > spec.low or (math.isfinite(spec.high) and stop < spec.high)):
        raise src.error(
            f"universe [{start}, {stop}] must cover the cue's range [{spec.low}, {spec.high}] "
            "(values beyond a universe are clipped to its ends)", section, "universe")
    band = None
    if "normal_band" in table:
        b = _number_list(table["normal_band"], 2)
        if b is None or not (start <= b[0] <= b[1] <= stop) or name != "brightness":
            raise src.error("normal_band = [low, high] is for brightness only and must lie inside the universe", section, "normal_band")
        band = (b[0], b[1])
    elif name == "brightness":
        raise src.error("brightness needs normal_band = [low, high]: fear must not fall moving away from it", section, "normal_band")
    terms: dict[str, np.ndarray] = {}
    shapes: dict[str, tuple[str, tuple[float, ...]]] = {}
    term_tables = {k: v for k, v in table.items() if k not in ("universe", "normal_band")}
    if "terms" in term_tables and isinstance(term_tables["terms"], Mapping):
        term_tables = {**{k: v for k, v in term_tables.items() if k != "terms"}, **term_tables["terms"]}
    for term, value in term_tables.items():
        if not (isinstance(value, Mapping) and len(value) == 1):
            raise src.error(f"term {term!r} must be written like {{ trimf = [a, b, c] }}; shapes: {', '.join(SHAPES)}", section, term)
        (shape_name, params), = value.items()
        shape = SHAPES.get(shape_name)
        if shape is None:
            raise src.error(f"unknown membership shape {shape_name!r}; known: {', '.join(SHAPES)}", section, term)
        p = _number_list(params, shape.n_params)
        if p is None or not shape.valid(p):
            raise src.error(f"{shape_name} takes {shape.n_params} finite numbers with {shape.requirement}, got {params!r}", section, term)
        mf = np.asarray(shape.sample(grid, p), dtype=float)
        if not mf.max() >= PEAK_MEMBERSHIP:
            raise src.error(
                f"term {term!r} ({shape_name} {p}) never reaches membership {PEAK_MEMBERSHIP} inside the universe "
                f"[{start}, {stop}]: the universe does not contain the term", section, term)
        terms[term] = mf
        shapes[term] = (shape_name, tuple(p))
    if not terms:
        raise src.error("has no terms", section)
    return Variable(name, grid, terms, shapes, band)


def _groups(table: Mapping[str, Any], variables: dict[str, Variable], src: _Source) -> tuple[Group, ...]:
    groups = []
    causes = ", ".join(c.value for c in Cause)
    for gname, gtable in table.items():
        section = f"groups.{gname}"
        if not isinstance(gtable, Mapping):
            raise src.error("must be a table with cause and rules", section)
        unknown = set(gtable) - {"cause", "rules", "description"}
        if unknown:
            raise src.error(f"unknown keys {sorted(unknown)}; a group has cause, rules, description", section)
        try:
            cause = Cause(gtable.get("cause"))
        except ValueError:
            raise src.error(f"cause must be one of {causes}, got {gtable.get('cause')!r}", section, "cause") from None
        texts = gtable.get("rules")
        if not isinstance(texts, list) or not texts or not all(isinstance(t, str) for t in texts):
            raise src.error("rules must be a non-empty list of rule strings", section, "rules")
        rules = tuple(_rule(text, i, gname, variables, src) for i, text in enumerate(texts))
        used = {a.variable for r in rules for a in atoms(r.antecedent)}
        groups.append(Group(gname, cause, rules, tuple(n for n in CUE_NAMES if n in used)))
    return tuple(groups)


def _rule(text: str, i: int, group: str, variables: dict[str, Variable], src: _Source) -> Rule:
    line = src.line_containing(text)
    section = f"groups.{group}"
    key = f"rules[{i}]"

    def fail(problem: str) -> RuleError:
        return src.error(f"rule {text!r}: {problem}", section, key, line or src.line_of(section, "rules"))

    try:
        parsed = parse_rule(text)
    except RuleSyntaxError as exc:
        raise fail(f"malformed rule: {exc}") from None
    for atom in atoms(parsed.antecedent):
        var = variables.get(atom.variable)
        if var is None:
            known = ", ".join(variables) or "none"
            raise fail(f"unknown variable {atom.variable!r} (defined: {known})")
        if atom.term not in var.terms:
            raise fail(f"unknown term {atom.term!r} of {atom.variable} (its terms: {', '.join(var.terms)})")
    if parsed.level not in LEVEL_NAMES:
        raise fail(f"unknown fear level {parsed.level!r} (levels: {', '.join(LEVEL_NAMES)})")
    return Rule(text, group, parsed.antecedent, FearLevel(LEVEL_NAMES.index(parsed.level)), parsed.weight, line)
