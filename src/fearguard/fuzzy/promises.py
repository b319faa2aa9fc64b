"""What each hazard, alone, must reach: the design's promises as values a rule file can be checked against.

Monotone and complete is not enough: a rule base whose "lane lost" rule says ``THEN fear IS low`` is both, and
drives blind at full speed. So every cue, alone at its worst (the others calm), must reach the response the design
promises (docs/architecture.md, invariant 11):

| cue | at its worst, and at the edge of its worst term's core | half-way into its worst term |
|---|---|---|
| ``lane_confidence``, ``occlusion`` | EMERGENCY, road cause (STOP, or FOLLOW_LEAD with a lead) | at least CAUTION |
| ``brightness`` (0 and 255) | at least CAUTION (darkness or glare: slow down) | at least CAUTION |
| ``obstacle_range_m`` | EMERGENCY STOP, collision cause (also the cores of terms named ``imminent``/``near``) | at least CAUTION |
| ``qr_staleness_s`` | EMERGENCY CRAWL, localisation cause | at least CAUTION |
| ``familiarity`` (with a track profile) | at least CAUTION (unlike the recordings: slow down) | at least CAUTION |

*Worst term*: the term with the highest membership at the cue's worst value. The *edge of its core* is its least bad
value with membership 1; *half-way* is where its membership has fallen to 0.5 toward calm (the crossover with the
next term). Terms are read from the rule file, so the points move with its numbers but not with its consequents:
an inverted consequent cannot hide. ``fearguard rules check`` tests the fears against the policy thresholds;
``fearguard.testing`` and ``fearguard verify`` drive a supervisor into each and check its mode and strategy.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from enum import Enum

import numpy as np

from fearguard.cues import CUE_NAMES, CUE_SPECS, Cues, calm_values
from fearguard.fear import Cause
from fearguard.fuzzy.model import Variable
from fearguard.fuzzy.rulebase import RuleBase

NAMED_COLLISION_TERMS = ("imminent", "near")  # obstacle_range_m terms the design calls a collision risk: STOP in their core
CORE = 1.0 - 1e-9  # [-] membership that counts as the core of a term
HALF = 0.5  # [-] membership at the crossover: half-way into the worst term

CUE_CAUSE = {  # the hazard each cue grades: it picks the strategy
    "lane_confidence": Cause.ROAD, "brightness": Cause.ROAD, "occlusion": Cause.ROAD,
    "obstacle_range_m": Cause.COLLISION, "qr_staleness_s": Cause.LOCALISATION, "familiarity": Cause.ROAD,
}


class Response(Enum):
    """What the supervisor must answer; ``needs_emergency`` says which fear threshold the rules must reach."""

    ROAD_EMERGENCY = "EMERGENCY STOP or FOLLOW_LEAD (the road picture is lost)"
    COLLISION_STOP = "EMERGENCY STOP (collision risk)"
    LOCALISATION_CRAWL = "EMERGENCY CRAWL (localisation stale)"
    CAUTION = "at least CAUTION"

    @property
    def needs_emergency(self) -> bool:
        return self is not Response.CAUTION


WORST_RESPONSE = {
    "lane_confidence": Response.ROAD_EMERGENCY, "occlusion": Response.ROAD_EMERGENCY, "brightness": Response.CAUTION,
    "obstacle_range_m": Response.COLLISION_STOP, "qr_staleness_s": Response.LOCALISATION_CRAWL,
    "familiarity": Response.CAUTION,  # unlike anything learnt: slow down (the rules may ask more; the design promises this)
}


@dataclass(frozen=True)
class Promise:
    """One cue at one value, the others calm, and what the supervisor must answer."""

    cue: str
    value: float
    where: str  # which point this is: "its worst value", "the core of 'low'", "half-way into 'low'"
    term: str | None  # the rule file's term it stands in (None: the worst value outside every term's core)
    response: Response

    def cues(self, rules: RuleBase) -> Cues:
        """The calm picture with this cue at the promise's value."""
        values = dict(zip(CUE_NAMES, calm_values(rules.brightness_band), strict=True))
        values[self.cue] = self.value
        return Cues(**values)

    def text(self) -> str:
        return f"{self.cue} {self.value:g} alone ({self.where}, the other cues calm)"


def worst_values(name: str) -> tuple[float, ...]:
    """The value(s) an unknown cue counts as: brightness has two extremes (darkness, glare)."""
    spec = CUE_SPECS[CUE_NAMES.index(name)]
    return (0.0, 255.0) if spec.worst is None else (spec.worst,)


def promises(rules: RuleBase, cues: tuple[str, ...] = CUE_NAMES) -> tuple[Promise, ...]:
    """Every promise of ``cues`` that this rule file grades (a cue without a variable has none)."""
    out: list[Promise] = []
    for name in cues:
        var = rules.variables.get(name)
        if var is None:
            continue
        for worst in worst_values(name):
            out.extend(_cue_promises(name, worst, var))
        if name == "obstacle_range_m":
            out.extend(Promise(name, _core_edge(var, term, toward_calm=+1), f"the core of {term!r}", term, Response.COLLISION_STOP)
                       for term in NAMED_COLLISION_TERMS if term in var.terms)
    return tuple(dict.fromkeys(out))  # a point named twice is checked once


def _cue_promises(name: str, worst: float, var: Variable) -> list[Promise]:
    """The worst value, the edge of the worst term's core, and half-way into the worst term."""
    response = WORST_RESPONSE[name]
    toward_calm = -1 if worst > var.universe[0] else +1  # worst at the top of the universe: calm lies below
    inside = float(np.clip(worst, var.universe[0], var.universe[-1]))
    term = max(var.terms, key=lambda t: float(np.interp(inside, var.universe, var.terms[t])))
    out = [Promise(name, worst, "its worst value", None, response)]
    core = _core_edge(var, term, toward_calm)
    if math.isfinite(core):
        out.append(Promise(name, core, f"the core of {term!r}", term, response))
    half = _half_way(var, term, core, toward_calm)
    if math.isfinite(half):
        out.append(Promise(name, half, f"half-way into {term!r}", term, Response.CAUTION))
    return out


def _core_edge(var: Variable, term: str, toward_calm: int) -> float:
    """The core point of ``term`` nearest to calm (membership 1); NaN if the term never reaches 1."""
    core = var.universe[var.terms[term] >= CORE]
    if not core.size:
        return math.nan
    return float(core.max() if toward_calm > 0 else core.min())


def _half_way(var: Variable, term: str, core: float, toward_calm: int) -> float:
    """From the core edge toward calm, the first universe point where ``term``'s membership is at most HALF."""
    if not math.isfinite(core):
        return math.nan
    u, m = var.universe, var.terms[term]
    side = (u > core) if toward_calm > 0 else (u < core)
    idx = np.flatnonzero(side & (m <= HALF))
    if not idx.size:
        return math.nan
    return float(u[idx.min()] if toward_calm > 0 else u[idx.max()])


def cue_cause(name: str) -> Cause:
    return CUE_CAUSE[name]


@dataclass(frozen=True)
class Reach:
    """A promise checked on the rules alone: the fear of its cause against the policy threshold it needs."""

    promise: Promise
    fear: float  # the fear of the promise's cause (the group fears of that cause, maxed)
    threshold: float
    rule: str  # the rule reading this cue's term (the one that should fire), or ""

    @property
    def ok(self) -> bool:
        return self.fear >= self.threshold

    def line(self) -> str:
        p = self.promise
        mark = "ok " if self.ok else "UNREACHED"
        tail = "" if self.ok else f"; the rule that should drive it: {self.rule!r}" if self.rule else ""
        return (f"      {mark} {p.text()}: {cue_cause(p.cue).value} fear {self.fear:.3f}, needs {self.threshold:g} "
                f"for {p.response.value}{tail}")


def check_promises(rules: RuleBase) -> tuple[Reach, ...]:
    """Each promise on the rules alone: the cause's fear must reach emergency_enter_fear (EMERGENCY) or caution_fear."""
    cfg = rules.policy
    out = []
    for p in promises(rules):
        result = rules.evaluate(p.cues(rules))
        cause = cue_cause(p.cue)
        fear = result.cause_fears.get(cause, 0.0) if p.response.needs_emergency else result.fear
        threshold = cfg.emergency_enter_fear if p.response.needs_emergency else cfg.caution_fear
        out.append(Reach(p, fear, threshold, rule_for(rules, p)))
    return tuple(out)


def rule_for(rules: RuleBase, promise: Promise) -> str:
    """The rule whose antecedent names this cue's term (``cue IS term``, not ``IS NOT``): the one that should fire."""
    term = promise.term
    if term is None:
        var = rules.variables.get(promise.cue)
        if var is None:
            return ""
        inside = float(np.clip(promise.value, var.universe[0], var.universe[-1]))
        term = max(var.terms, key=lambda t: float(np.interp(inside, var.universe, var.terms[t])))
    needle = f"{promise.cue} IS {term}"
    hits = [r.text for r in rules.rules if needle in r.text and f"{promise.cue} IS NOT {term}" not in r.text]
    return min(hits, key=len) if hits else ""
