"""A loaded rule base: where it came from, its plain values, its policy numbers, and its compiled engine.

Fear is a small hierarchy: each *group* is a Mamdani rule base (min/max, centroid) over a few cues,
and fear = max over groups (fuzzy OR of the hazards). Max of monotone groups is monotone, which a
single large Mamdani base with centroid is not in general (docs/architecture.md, invariant 3); each group's
own monotonicity is proved by ``fearguard rules check``.

Layering (no import cycle): ``model`` (plain values) ← ``engine`` and ``reference`` ← ``rulebase``.
The scikit-fuzzy reference is imported only when first asked for (it is slow and only for checking).
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass, field
from typing import TYPE_CHECKING

import numpy as np

from fearguard.cues import BRIGHTNESS, CUE_NAMES, CUE_SPECS, MEASURED_CUES, Cues, unknown_mask, with_worst
from fearguard.fear import FearLevel, FearResult
from fearguard.fuzzy.engine import Engine
from fearguard.fuzzy.model import Group, Rule, RuleSet, Variable
from fearguard.policy import PolicyConfig

if TYPE_CHECKING:
    from fearguard.fuzzy.reference import Reference

__all__ = ["Group", "Rule", "RuleBase", "Variable"]  # the values are re-exported for existing imports


@dataclass(eq=False)
class RuleBase:
    """The fear rule base of one TOML file, compiled for fast inference."""

    path: str
    name: str
    variables: dict[str, Variable]
    fear_variable: Variable
    groups: tuple[Group, ...]
    policy: PolicyConfig
    _engine: Engine = field(init=False, repr=False)
    _reference: Reference | None = field(init=False, repr=False, default=None)

    def __post_init__(self) -> None:
        self._engine = Engine(self.model)

    @property
    def model(self) -> RuleSet:
        """The plain values the engine and the reference compute from."""
        return RuleSet(self.variables, self.fear_variable, self.groups)

    @property
    def engine(self) -> Engine:
        """The compiled engine (per-group batch fears and activations, used by ``rules check``)."""
        return self._engine

    @property
    def rules(self) -> tuple[Rule, ...]:
        return tuple(r for g in self.groups for r in g.rules)

    @property
    def level_anchors(self) -> np.ndarray:
        """Fear the engine gives when only that level fires fully: the centroid of each level's term."""
        return self._engine.level_anchors

    @property
    def brightness_band(self) -> tuple[float, float]:
        return self.model.brightness_band

    def level_of(self, fear: float) -> FearLevel:
        """The level whose fear term has the highest membership at this fear (ties: the higher)."""
        return self._engine.level_of(fear)

    def evaluate(self, cues: Cues | Sequence[float] | np.ndarray) -> FearResult:
        """Fear of one cue vector, with the rules that fired; unknown cues count as their worst."""
        x = cues.values() if isinstance(cues, Cues) else full_width(np.asarray(cues, dtype=float).reshape(1, -1))[0].tolist()
        return self._engine.evaluate(x)

    def evaluate_batch(self, x: np.ndarray) -> np.ndarray:
        """Fear of N cue vectors, x: (N, 5) or (N, 6) in CUE_NAMES order → (N,). Five columns: a car without a track
        profile (familiarity does not apply)."""
        return self.group_fears_batch(x).max(axis=1)

    def group_fears_batch(self, x: np.ndarray) -> np.ndarray:
        """Each group's fear for N cue vectors: (N, 5 or 6) → (N, n_groups); unknown = worst."""
        x = full_width(np.asarray(x, dtype=float))
        dark = self._engine.group_fears_batch(with_worst(x, 0.0))
        unknown_b = unknown_mask(x)[:, BRIGHTNESS]
        if unknown_b.any():
            glare = self._engine.group_fears_batch(with_worst(x[unknown_b], 255.0))
            rows = np.flatnonzero(unknown_b)
            pick = glare.max(axis=1) > dark[rows].max(axis=1)
            dark[rows[pick]] = glare[pick]
        return dark

    def reference_fear(self, cues: Cues | Sequence[float] | np.ndarray) -> float:
        """The same rule base computed through scikit-fuzzy's ControlSystemSimulation (slow, exact)."""
        from fearguard.fuzzy.reference import Reference  # scikit-fuzzy's control system: loaded on first use

        if self._reference is None:
            self._reference = Reference(self.model)
        x = cues.as_array() if isinstance(cues, Cues) else full_width(np.asarray(cues, dtype=float).reshape(1, -1))[0]
        return self._reference.fear(x)


def full_width(x: np.ndarray) -> np.ndarray:
    """Cue vectors (N, 5) or (N, 6) → (N, 6): five columns are a car without a track profile, whose familiarity is
    calm (the cue does not apply). Any other shape is a ValueError naming the order."""
    if x.ndim != 2 or x.shape[1] not in (MEASURED_CUES, len(CUE_NAMES)):
        raise ValueError(f"evaluate_batch needs an array of shape (N, {MEASURED_CUES}) or (N, {len(CUE_NAMES)}) in the "
                         f"order {CUE_NAMES}, got {x.shape}")
    if x.shape[1] == len(CUE_NAMES):
        return x
    calm = np.array([s.calm for s in CUE_SPECS[MEASURED_CUES:]], dtype=float)
    return np.hstack([x, np.broadcast_to(calm, (x.shape[0], calm.size))])
