"""The same rule base through scikit-fuzzy's own ControlSystemSimulation: the reference the engine is
checked against (tests, benchmark). One ControlSystem per group; fear = max over groups, as in the engine.
"""

from __future__ import annotations

from functools import reduce
from typing import Any

import numpy as np
from skfuzzy import control as ctrl

from fearguard.cues import BRIGHTNESS, CUE_NAMES, unknown_mask, with_worst
from fearguard.fear import LEVEL_NAMES
from fearguard.fuzzy.model import Group, RuleSet
from fearguard.fuzzy.rule_text import And, Is, Node, Not


def _antecedent(node: Node, antecedents: dict[str, Any]) -> Any:
    if isinstance(node, Is):
        return antecedents[node.variable][node.term]
    if isinstance(node, Not):
        return ~_antecedent(node.operand, antecedents)
    parts = [_antecedent(op, antecedents) for op in node.operands]
    return reduce((lambda a, b: a & b) if isinstance(node, And) else (lambda a, b: a | b), parts)


def build_system(rb: RuleSet, group: Group) -> ctrl.ControlSystem:
    """A scikit-fuzzy ControlSystem for one group, from the very same sampled terms."""
    antecedents: dict[str, Any] = {}
    for name in group.inputs:
        var = rb.variables[name]
        antecedents[name] = ctrl.Antecedent(var.universe, name)
        for term, mf in var.terms.items():
            antecedents[name][term] = mf
    fear = ctrl.Consequent(rb.fear_variable.universe, "fear", defuzzify_method="centroid")
    for term, mf in rb.fear_variable.terms.items():
        fear[term] = mf
    rules = [
        ctrl.Rule(_antecedent(r.antecedent, antecedents), fear[LEVEL_NAMES[r.level]] % float(r.weight), label=f"r{i}")
        for i, r in enumerate(group.rules)
    ]
    return ctrl.ControlSystem(rules)


def _group_fear(sim: ctrl.ControlSystemSimulation, inputs: tuple[str, ...], x: np.ndarray) -> float:
    for name in inputs:
        sim.input[name] = float(x[CUE_NAMES.index(name)])
    sim.compute()
    return float(sim.output.get("fear", 1.0))  # no rule fired: fear 1, as in the engine


class Reference:
    """One reusable scikit-fuzzy simulation per group of a rule set; fear = max over groups."""

    def __init__(self, rules: RuleSet) -> None:
        self.groups = rules.groups
        self.simulations = [ctrl.ControlSystemSimulation(build_system(rules, g), cache=False) for g in rules.groups]

    def fear(self, x_raw: np.ndarray) -> float:
        """Fear computed by scikit-fuzzy; unknown cues replaced by their worst value first."""
        candidates = [with_worst(x_raw, 0.0)]
        if unknown_mask(x_raw)[BRIGHTNESS]:
            candidates.append(with_worst(x_raw, 255.0))
        return max(
            _group_fear(sim, group.inputs, x)
            for x in candidates
            for sim, group in zip(self.simulations, self.groups, strict=True)
        )
