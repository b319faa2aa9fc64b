"""A loaded rule base: linguistic variables, rule groups, policy numbers, and how to evaluate them.

Fear is a small hierarchy: each *group* is a Mamdani rule base (min/max, centroid) over a few cues,
and fear = max over groups (fuzzy OR of the hazards). Max of monotone groups is monotone, which a
single large Mamdani base with centroid is not in general (docs/architecture.md, invariant 3); each group's
own monotonicity is proved by ``fearguard rules check``.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass, field
from functools import cached_property

import numpy as np

from fearguard.cues import BRIGHTNESS, CUE_NAMES, Cues, unknown_mask, with_worst
from fearguard.fear import Cause, FearLevel, FearResult
from fearguard.fuzzy.rule_text import Node
from fearguard.policy import PolicyConfig


@dataclass(frozen=True, eq=False)
class Variable:
    """A linguistic variable: sample points of its universe and each term's sampled membership."""

    name: str
    universe: np.ndarray
    terms: dict[str, np.ndarray]
    shapes: dict[str, tuple[str, tuple[float, ...]]]
    normal_band: tuple[float, float] | None = None


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


@dataclass(eq=False)
class RuleBase:
    """The fear rule base of one TOML file, compiled for fast inference."""

    path: str
    name: str
    variables: dict[str, Variable]
    fear_variable: Variable
    groups: tuple[Group, ...]
    policy: PolicyConfig
    _engine: object = field(init=False, repr=False)

    def __post_init__(self) -> None:
        from fearguard.fuzzy.engine import Engine

        self._engine = Engine(self)

    @property
    def rules(self) -> tuple[Rule, ...]:
        return tuple(r for g in self.groups for r in g.rules)

    @cached_property
    def level_anchors(self) -> np.ndarray:
        """Fear the engine gives when only that level fires fully: the centroid of each level's term."""
        from fearguard.fuzzy.engine import centroid_weights

        area_w, moment_w = centroid_weights(self.fear_variable.universe)
        return np.array([float(mf @ moment_w) / float(mf @ area_w) for mf in self.fear_variable.terms.values()])

    @property
    def brightness_band(self) -> tuple[float, float]:
        var = self.variables.get("brightness")
        if var is None or var.normal_band is None:
            return (0.0, 255.0)
        return var.normal_band

    def level_of(self, fear: float) -> FearLevel:
        """The level whose fear term has the highest membership at this fear (ties: the higher)."""
        return self._engine.level_of(fear)  # type: ignore[attr-defined]

    def evaluate(self, cues: Cues | Sequence[float] | np.ndarray) -> FearResult:
        """Fear of one cue vector, with the rules that fired; unknown cues count as their worst."""
        x = cues.values() if isinstance(cues, Cues) else np.asarray(cues, dtype=float).reshape(5).tolist()
        return self._engine.evaluate(x)  # type: ignore[attr-defined]

    def evaluate_batch(self, x: np.ndarray) -> np.ndarray:
        """Fear of N cue vectors, x: (N, 5) in CUE_NAMES order → (N,)."""
        return self.group_fears_batch(x).max(axis=1)

    def group_fears_batch(self, x: np.ndarray) -> np.ndarray:
        """Each group's fear for N cue vectors: (N, 5) → (N, n_groups); unknown = worst."""
        x = np.asarray(x, dtype=float)
        if x.ndim != 2 or x.shape[1] != len(CUE_NAMES):
            raise ValueError(f"evaluate_batch needs an array of shape (N, 5) in the order {CUE_NAMES}, got {x.shape}")
        dark = self._engine.group_fears_batch(with_worst(x, 0.0))  # type: ignore[attr-defined]
        unknown_b = unknown_mask(x)[:, BRIGHTNESS]
        if unknown_b.any():
            glare = self._engine.group_fears_batch(with_worst(x[unknown_b], 255.0))  # type: ignore[attr-defined]
            rows = np.flatnonzero(unknown_b)
            pick = glare.max(axis=1) > dark[rows].max(axis=1)
            dark[rows[pick]] = glare[pick]
        return dark

    def reference_fear(self, cues: Cues | Sequence[float] | np.ndarray) -> float:
        """The same rule base computed through scikit-fuzzy's ControlSystemSimulation (slow, exact)."""
        from fearguard.fuzzy.reference import reference_fear

        x = cues.as_array() if isinstance(cues, Cues) else np.asarray(cues, dtype=float).reshape(5)
        return reference_fear(self, x)
