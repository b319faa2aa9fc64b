"""The plain values of a rule base: linguistic variables with their sampled terms, rules and groups.

These sit at the bottom of ``fuzzy/``: the loader builds them, the compiled engine and the
scikit-fuzzy reference both read them, and nothing here imports either (no cycle).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from fearguard.fear import Cause, FearLevel
from fearguard.fuzzy.rule_text import Node


@dataclass(frozen=True, eq=False)
class Variable:
    """A linguistic variable: sample points of its universe and each term's sampled membership."""

    name: str
    universe: np.ndarray
    terms: dict[str, np.ndarray]
    shapes: dict[str, tuple[str, tuple[float, ...]]]
    normal_band: tuple[float, float] | None = None

    def calm_core_top(self, calm: float) -> float:
        """How far from ``calm`` (the cue's calmest value, at the bottom of the universe) the term that holds it stays
        fully true: the top of that term's core (0 when no term is fully true there)."""
        inside = float(np.clip(calm, self.universe[0], self.universe[-1]))
        best = max(self.terms.values(), key=lambda m: float(np.interp(inside, self.universe, m)))
        core = self.universe[(best >= 1.0 - 1e-9) & (self.universe >= inside)]
        return float(core.max()) if core.size and float(np.interp(inside, self.universe, best)) >= 1.0 - 1e-9 else inside


@dataclass(frozen=True)
class Rule:
    text: str
    group: str
    antecedent: Node
    level: FearLevel
    weight: float
    line: int | None


@dataclass(frozen=True)
class Group:
    """One small Mamdani rule base grading one cause."""

    name: str
    cause: Cause
    rules: tuple[Rule, ...]
    inputs: tuple[str, ...]  # cue names its rules read, in CUE_NAMES order


@dataclass(frozen=True, eq=False)
class RuleSet:
    """What the engine and the reference compute from: input variables, the fear variable, the groups."""

    variables: dict[str, Variable]
    fear_variable: Variable
    groups: tuple[Group, ...]

    @property
    def brightness_band(self) -> tuple[float, float]:
        """The normal brightness band (fear must not fall moving away from it); the full range if none."""
        var = self.variables.get("brightness")
        if var is None or var.normal_band is None:
            return (0.0, 255.0)
        return var.normal_band
