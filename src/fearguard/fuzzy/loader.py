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
from collections.abc import Callable, Mapping
from dataclasses import asdict, fields
from itertools import pairwise
from pathlib import Path
from typing import Any

import numpy as np

from fearguard.cues import CUE_NAMES, CUE_SPECS
from fearguard.errors import FearguardError, RuleError
from fearguard.fear import LEVEL_NAMES, Cause, FearLevel
from fearguard.files.reader import ErrorKind, Table, TomlSource, number_list, read_toml, suggestion
from fearguard.fuzzy.membership import SHAPES, Shape, universe_grid
from fearguard.fuzzy.model import Group, Rule, Variable
from fearguard.fuzzy.rule_text import RuleSyntaxError, atoms, parse_rule
from fearguard.fuzzy.rulebase import RuleBase
from fearguard.policy.config import PolicyConfig
from fearguard.readings import finite_reading

MAX_UNIVERSE_POINTS = 100_001  # [-] a finer universe makes every evaluation slow for no accuracy
PEAK_MEMBERSHIP = 0.99  # [-] a term must reach this inside its universe to be usable
TOP_KEYS = {"name", "description", "variables", "fear", "groups", "policy"}


def bundled_rules_path(name: str = "default.toml") -> Path:
    """Path of a rule file shipped inside the package (works after a non-editable install)."""
    from importlib import resources  # tempfile, shutil, random…: not paid by ``import fearguard``

    return Path(str(resources.files("fearguard") / "rules" / name))


def load_rules(path: str | Path | None = None) -> RuleBase:
    """Load and compile a rule base; the bundled 1:10 model-car default when no path is given."""
    path = bundled_rules_path() if path is None else Path(path)
    data, src = read_toml(path, RuleError, "give the path of a rule file such as rules/default.toml")
    return _build(data, src)


def _build(data: Mapping[str, Any], src: TomlSource) -> RuleBase:
    top = Table(src, data, "", TOP_KEYS)
    name = top.string("name", Path(src.path).stem)
    variables_table = _table(data, "variables", src)
    variables: dict[str, Variable] = {}
    for var_name in variables_table:
        section = f"variables.{var_name}"
        if var_name not in CUE_NAMES:
            raise src.error(section, f"unknown variable {var_name!r}{suggestion(var_name, CUE_NAMES)}; the cues are {', '.join(CUE_NAMES)}")
        variables[var_name] = _variable(var_name, _table(variables_table, var_name, src, section), src, section)
    fear_var = _variable("fear", _table(data, "fear", src), src, "fear")
    if list(fear_var.terms) != list(LEVEL_NAMES):
        raise src.error("fear", f"the fear terms must be exactly {', '.join(LEVEL_NAMES)} in this order, got {', '.join(fear_var.terms)}")
    groups = _groups(_table(data, "groups", src), variables, src)
    policy = policy_from_table(src, data.get("policy", {}), "policy")
    return RuleBase(path=src.path, name=name, variables=variables, fear_variable=fear_var, groups=groups, policy=policy)


def _table(data: Mapping[str, Any], key: str, src: TomlSource, dotted: str | None = None) -> Mapping[str, Any]:
    dotted = dotted or key
    if key not in data:
        raise src.error(dotted, "missing table")
    value = data[key]
    if not isinstance(value, Mapping) or not value:
        raise src.error(dotted, "must be a non-empty table")
    return value


def _variable(name: str, table: Mapping[str, Any], src: TomlSource, section: str) -> Variable:
    def fail(key: str | None, problem: str) -> FearguardError:
        return src.error(f"{section}.{key}" if key else section, problem)

    grid = _universe(name, table.get("universe"), fail)
    start, stop = float(grid[0]), float(grid[-1])
    band = None
    if "normal_band" in table:
        b = number_list(table["normal_band"], 2)
        if b is None or not (start <= b[0] <= b[1] <= stop) or name != "brightness":
            raise fail("normal_band", "normal_band = [low, high] is for brightness only and must lie inside the universe")
        band = (b[0], b[1])
    elif name == "brightness":
        raise fail("normal_band", "brightness needs normal_band = [low, high]: fear must not fall moving away from it")
    term_tables = {k: v for k, v in table.items() if k not in ("universe", "normal_band")}
    if "terms" in term_tables and isinstance(term_tables["terms"], Mapping):
        term_tables = {**{k: v for k, v in term_tables.items() if k != "terms"}, **term_tables["terms"]}
    terms: dict[str, np.ndarray] = {}
    shapes: dict[str, tuple[str, tuple[float, ...]]] = {}
    for term, value in term_tables.items():
        shapes[term], terms[term] = _term(term, value, grid, fail)
    if not terms:
        raise fail(None, "has no terms")
    return Variable(name, grid, terms, shapes, band)


def _universe(name: str, value: object, fail: Callable[[str, str], FearguardError]) -> np.ndarray:
    """The sample points of ``universe = [start, stop, step]``, covering the cue's range (fear: exactly 0..1)."""
    u = number_list(value, 3)
    if u is None:
        raise fail("universe", "needs universe = [start, stop, step] with finite numbers")
    start, stop, step = u
    if not (stop > start and step > 0 and (stop - start) / step + 1 <= MAX_UNIVERSE_POINTS):
        raise fail("universe", f"universe {u} must have start < stop, step > 0 and at most {MAX_UNIVERSE_POINTS} points")
    if abs(round((stop - start) / step) * step - (stop - start)) > 1e-9 * max(1.0, abs(stop - start)):
        raise fail("universe", f"universe {u}: step must divide stop - start")
    if (stop - start) / step < 2:
        raise fail("universe", f"universe {u} needs at least 3 points")
    spec = next((s for s in CUE_SPECS if s.name == name), None)
    if spec is not None and (start > spec.low or (math.isfinite(spec.high) and stop < spec.high)):
        raise fail("universe", f"universe [{start}, {stop}] must cover the cue's range [{spec.low}, {spec.high}] "
                               "(values beyond a universe are clipped to its ends)")
    if name == "fear" and (start, stop) != (0.0, 1.0):
        raise fail("universe", f"the fear universe must be [0.0, 1.0, step] (fear is 0..1 and the policy's thresholds "
                               f"are on that scale), got [{start}, {stop}, {step}]")
    return universe_grid(start, stop, step)


def _term(term: str, value: object, grid: np.ndarray, fail: Callable[[str, str], FearguardError]
          ) -> tuple[tuple[str, tuple[float, ...]], np.ndarray]:
    """A term written ``{ shape = [params] }``: its shape and parameters, and its membership sampled on the grid."""
    if not (isinstance(value, Mapping) and len(value) == 1):
        raise fail(term, f"term {term!r} must be written like {{ trimf = [a, b, c] }}; shapes: {', '.join(SHAPES)}")
    (shape_name, params), = value.items()
    shape = SHAPES.get(shape_name)
    if shape is None:
        raise fail(term, f"unknown membership shape {shape_name!r}{suggestion(shape_name, SHAPES)}; known: {', '.join(SHAPES)}")
    p = number_list(params, shape.n_params)
    if p is None or not shape.valid(p):
        raise fail(term, f"{shape_name} takes {shape.n_params} finite numbers with {shape.requirement}, got {params!r}")
    mf = _sampled(shape, grid, p)
    if mf is None:
        raise fail(term, f"{shape_name} {p} cannot be sampled on the universe (scikit-fuzzy rejects it); {shape.requirement}")
    if not mf.max() >= PEAK_MEMBERSHIP:
        raise fail(term, f"term {term!r} ({shape_name} {p}) never reaches membership {PEAK_MEMBERSHIP} inside the universe "
                         f"[{grid[0]}, {grid[-1]}]: the universe does not contain the term")
    return (shape_name, tuple(p)), mf


def _sampled(shape: Shape, grid: np.ndarray, params: list[float]) -> np.ndarray | None:
    """The term sampled on the grid, or None when scikit-fuzzy refuses the parameters or gives non-finite values."""
    try:
        with np.errstate(all="ignore"):
            mf = np.asarray(shape.sample(grid, params), dtype=float)
    except (AssertionError, ArithmeticError, ValueError):  # scikit-fuzzy asserts on some parameter orders
        return None
    return mf if mf.shape == grid.shape and np.isfinite(mf).all() else None


def _groups(table: Mapping[str, Any], variables: dict[str, Variable], src: TomlSource) -> tuple[Group, ...]:
    groups = []
    causes = [c.value for c in Cause]
    for gname, gtable in table.items():
        t = Table(src, gtable, f"groups.{gname}", ("cause", "rules", "description"))
        cause = Cause(t.string("cause", choices=causes))
        texts = t.data.get("rules")
        if not isinstance(texts, list) or not texts or not all(isinstance(x, str) for x in texts):
            raise t.fail("rules", "rules must be a non-empty list of rule strings")
        rules = tuple(_rule(text, i, gname, variables, src) for i, text in enumerate(texts))
        used = {a.variable for r in rules for a in atoms(r.antecedent)}
        groups.append(Group(gname, cause, rules, tuple(n for n in CUE_NAMES if n in used)))
    return tuple(groups)


def _rule(text: str, i: int, group: str, variables: dict[str, Variable], src: TomlSource) -> Rule:
    line = src.line_containing(text)
    section = f"groups.{group}"
    key = f"rules[{i}]"

    def fail(problem: str) -> FearguardError:
        return src.error(f"{section}.{key}", f"rule {text!r}: {problem}", line or src.line_of(f"{section}.rules"))

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


# -- the [policy] table: policy holds the numbers, the loader reads them -------------------------------
_WHOLE_KEYS = ("enter_frames", "watchdog_frames", "recovery_max_creeps", "oscillation_flips")
_POSITIVE_KEYS = ("watchdog_age_s", "recovery_creep_m", "recovery_creep_s", "recovery_max_total_m", "oscillation_deg",
                  "lane_check_lookahead_s", "recovery_blind_m", "recovery_creep_max_deg")


def _fractions(t: Table, key: str) -> tuple[float, ...]:
    value = t.data[key]
    if not isinstance(value, Mapping):
        raise t.fail(key, "must be a table like { very_low = 1.0, low = 0.8, ... }")
    missing = [n for n in LEVEL_NAMES if n not in value]
    extra = [k for k in value if k not in LEVEL_NAMES]
    if missing or extra:
        raise t.fail(key, f"needs exactly the levels {', '.join(LEVEL_NAMES)}; missing {missing}, unknown {extra}")
    seq = [finite_reading(value[n]) for n in LEVEL_NAMES]
    if not all(v is not None and 0.0 <= v <= 1.0 for v in seq):
        raise t.fail(key, f"each fraction must be a number in [0, 1], got {[value[n] for n in LEVEL_NAMES]}")
    fractions = tuple(float(v) for v in seq if v is not None)
    if any(b > a for a, b in pairwise(fractions)):
        raise t.fail(key, f"fractions must not increase with fear (monotone policy), got {list(fractions)}")
    return fractions


def policy_from_table(src: TomlSource, data: object, key_path: str = "policy") -> PolicyConfig:
    """Validate a ``[policy]`` table with the strict reader; errors name the file, the line and the key."""
    t = Table(src, data, key_path, [f.name for f in fields(PolicyConfig)])
    values: dict[str, Any] = {}
    for key in t.data:
        if key == "speed_fraction":
            values[key] = _fractions(t, key)
        elif key in _WHOLE_KEYS:
            values[key] = t.integer(key, low=0 if key == "recovery_max_creeps" else 1)
        else:
            values[key] = t.number(key)
    cfg = PolicyConfig(**values)
    for key, ok, problem in (
        ("emergency_enter_fear", 0.0 < cfg.emergency_enter_fear <= 1.0, "must be in (0, 1]"),
        ("emergency_exit_fear", 0.0 <= cfg.emergency_exit_fear < cfg.emergency_enter_fear,
         "must be >= 0 and below emergency_enter_fear (hysteresis)"),
        ("caution_fear", 0.0 < cfg.caution_fear <= cfg.emergency_enter_fear,
         "must be in (0, emergency_enter_fear]"),
        ("hold_s", cfg.hold_s >= 0.0, "must be >= 0"),
        ("comfort_accel_mps2", cfg.comfort_accel_mps2 > 0.0, "must be > 0"),
        ("crawl_fraction", 0.0 <= cfg.crawl_fraction <= 1.0, "must be in [0, 1]"),
        ("follow_time_gap_s", cfg.follow_time_gap_s > 0.0, "must be > 0"),
        ("follow_decel_mps2", cfg.follow_decel_mps2 > 0.0, "must be > 0"),
        ("follow_gain", cfg.follow_gain >= 0.0, "must be >= 0"),
        *((k, getattr(cfg, k) > 0.0, "must be > 0") for k in _POSITIVE_KEYS),
        ("recovery_dwell_s", cfg.recovery_dwell_s >= 0.0, "must be >= 0"),
        ("standstill_mps", cfg.standstill_mps >= 0.0, "must be >= 0"),
        ("moving_object_min_mps", cfg.moving_object_min_mps >= 0.0, "must be >= 0"),
        ("lane_check_min_deg", cfg.lane_check_min_deg >= 0.0, "must be >= 0"),
        ("lane_check_fraction", 0.0 <= cfg.lane_check_fraction <= 1.0, "must be in [0, 1]"),
        ("recovery_min_confidence", 0.0 <= cfg.recovery_min_confidence <= 1.0, "must be in [0, 1]"),
        ("recovery_min_guide", 0.0 <= cfg.recovery_min_guide <= 1.0, "must be in [0, 1]"),
        ("road_enter_s", cfg.road_enter_s >= 0.0, "must be >= 0"),
        ("stop_line_wait_s", cfg.stop_line_wait_s >= 0.0, "must be >= 0 (0: stop lines are not stopped for)"),
        ("stop_line_cross_m", cfg.stop_line_cross_m > 0.0, "must be > 0"),
        ("route_blind_m", cfg.route_blind_m >= 0.0, "must be >= 0 (0: a route is not followed)"),
        ("road_doubt_fraction", 0.0 <= cfg.road_doubt_fraction <= 1.0, "must be in [0, 1]"),
    ):
        if not ok:
            raise t.fail(key, f"{problem}, got {getattr(cfg, key)}")
    return cfg


def policy_with(policy: PolicyConfig, changes: Mapping[str, Any], source: str, error: ErrorKind = RuleError) -> PolicyConfig:
    """``policy`` with some of its numbers changed (a sweep's ``--set policy.hold_s=3``), validated as a rule file's
    ``[policy]`` table is: an unknown key, a wrong type or a broken threshold order is ``error`` naming ``source``."""
    table = {**asdict(policy), "speed_fraction": dict(zip(LEVEL_NAMES, policy.speed_fraction, strict=True)), **changes}
    return policy_from_table(TomlSource(source, "", error), table, "policy")
