"""Prove a rule base complete and monotone by sweeping a dense grid, group by group, and its policy
thresholds reachable.

Fear is the max over groups, and max keeps both properties: if every group fires some rule
everywhere and never lowers its fear when one of its cues worsens, neither does fear. So each
group is swept over the full grid of its own cues (dense: up to ~250 000 points per group),
including ``inf`` for the open-ended cues; other cues do not affect it.

Reachable: with every cue at its worst (unknown), each cause the rule base grades must reach the
policy's ``emergency_enter_fear`` (else EMERGENCY can never be entered for it), and calm cues (lane
seen, brightness mid-band, nothing hidden, nothing in range, just localised) must stay below
``caution_fear`` (else the car can never drive freely). Monotone fear between the two then covers
every case in between. And each hazard alone must reach the response the design promises for it
(``fuzzy/promises.py``): a lost lane, EMERGENCY; darkness, at least CAUTION; … — monotone and complete do not
catch an inverted consequent.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from fearguard.cues import CUE_NAMES, CUE_SPECS, Worsens, calm_values
from fearguard.fear import Cause
from fearguard.fuzzy.model import Group
from fearguard.fuzzy.promises import Reach, check_promises
from fearguard.fuzzy.rulebase import RuleBase

GRID_BUDGET = 250_000  # [points] per group
MONOTONE_TOL = 1e-9  # [-] fear may not fall by more than rounding


@dataclass(frozen=True)
class GroupCheck:
    group: str
    inputs: tuple[str, ...]
    points_per_axis: tuple[int, ...]
    uncovered: tuple[str, ...]  # examples of grid points where no rule fires
    violations: tuple[str, ...]  # examples of a fear drop when a cue worsens

    @property
    def ok(self) -> bool:
        return not self.uncovered and not self.violations


@dataclass(frozen=True)
class ThresholdCheck:
    """Fear of calm cues against ``caution_fear``; each cause's fear at the worst cues against ``emergency_enter_fear``."""

    calm_cues: tuple[float, ...]
    calm_fear: float
    caution_fear: float
    enter_fear: float
    worst_fears: dict[Cause, float]  # per cause the rule base grades

    @property
    def unreachable(self) -> tuple[Cause, ...]:
        return tuple(c for c, f in self.worst_fears.items() if not f >= self.enter_fear)

    @property
    def calm_ok(self) -> bool:
        return self.calm_fear < self.caution_fear

    @property
    def ok(self) -> bool:
        return self.calm_ok and not self.unreachable

    def lines(self) -> list[str]:
        worst = ", ".join(f"{c.value} {f:.3f}" for c, f in self.worst_fears.items())
        calm = ", ".join(f"{n}={v:g}" for n, v in zip(CUE_NAMES, self.calm_cues, strict=True))
        out = [f"  thresholds     calm cues → fear {self.calm_fear:.3f} (caution_fear {self.caution_fear:g}); "
               f"every cue at its worst → {worst} (emergency_enter_fear {self.enter_fear:g})"]
        if not self.calm_ok:
            out.append(f"      calm cues ({calm}) give fear {self.calm_fear:.3f}, not below caution_fear {self.caution_fear:g}: "
                       "the car could never drive at full speed")
        out.extend(f"      UNREACHABLE: {c.value} reaches only fear {self.worst_fears[c]:.3f} with every cue at its worst, "
                   f"below emergency_enter_fear {self.enter_fear:g}: EMERGENCY can never be entered for it" for c in self.unreachable)
        return out


def check_thresholds(rb: RuleBase) -> ThresholdCheck:
    """Calm cues must stay below caution; every cue at its worst must bring each graded cause to emergency."""
    calm = calm_values(rb.brightness_band)
    worst = rb.evaluate([math.nan] * len(CUE_NAMES))  # unknown = worst, both brightness extremes tried
    causes = dict.fromkeys(g.cause for g in rb.groups)
    return ThresholdCheck(calm, rb.evaluate(calm).fear, rb.policy.caution_fear, rb.policy.emergency_enter_fear,
                          {c: float(worst.cause_fears[c]) for c in causes})


@dataclass(frozen=True)
class CheckReport:
    rules: RuleBase
    groups: tuple[GroupCheck, ...]
    thresholds: ThresholdCheck
    promises: tuple[Reach, ...] = ()  # each hazard alone against the response it must reach (fuzzy/promises.py)

    @property
    def ok(self) -> bool:
        return all(g.ok for g in self.groups) and self.thresholds.ok and all(r.ok for r in self.promises)

    def lines(self) -> list[str]:
        rb = self.rules
        out = [f"{rb.path}: {rb.name!r}: {len(rb.groups)} groups, {len(rb.rules)} rules; fear = max over groups"]
        for g in self.groups:
            grid = "×".join(str(n) for n in g.points_per_axis)
            complete = "complete" if not g.uncovered else f"INCOMPLETE ({len(g.uncovered)} examples)"
            monotone = "monotone" if not g.violations else f"NOT MONOTONE ({len(g.violations)} examples)"
            out.append(f"  {g.group:<14} {' × '.join(g.inputs):<36} {grid:>11} points  {complete}, {monotone}")
            out.extend(f"      no rule fires at {u}" for u in g.uncovered)
            out.extend(f"      {v}" for v in g.violations)
        out.extend(self.thresholds.lines())
        kept = sum(r.ok for r in self.promises)
        out.append(f"  promises       each hazard alone (the others calm) reaches its response: {kept} of {len(self.promises)}")
        out.extend(r.line() for r in self.promises if not r.ok)
        out.append("OK: every group is complete and monotone, so fear is too; the policy thresholds are reachable and "
                   "each hazard alone reaches its response." if self.ok else "FAILED: see above.")
        return out


def _axis(rb: RuleBase, name: str, n: int) -> np.ndarray:
    u = rb.variables[name].universe
    if n >= 2 * len(u) - 1:  # every sample point and every midpoint: nothing between is unseen
        pts = np.sort(np.concatenate([u, 0.5 * (u[:-1] + u[1:])]))
    else:
        pts = np.linspace(u[0], u[-1], n)
    spec = CUE_SPECS[CUE_NAMES.index(name)]
    if spec.worsens is Worsens.AWAY_FROM_BAND:  # the band's edges must be grid points
        pts = np.union1d(pts, rb.brightness_band)
    if math.isinf(spec.high):
        pts = np.append(pts, np.inf)
    return pts


def _describe(names: tuple[str, ...], axes: list[np.ndarray], idx: tuple[int, ...]) -> str:
    return ", ".join(f"{n}={axes[k][i]:.4g}" for k, (n, i) in enumerate(zip(names, idx, strict=True)))


def check_group(rb: RuleBase, gi: int, group: Group, examples: int = 3) -> GroupCheck:
    d = len(group.inputs)
    n = max(11, int(GRID_BUDGET ** (1.0 / d)))
    axes = [_axis(rb, name, n) for name in group.inputs]
    mesh = np.meshgrid(*axes, indexing="ij")
    x = np.zeros((mesh[0].size, len(CUE_NAMES)))
    x[:, CUE_NAMES.index("brightness")] = sum(rb.brightness_band) / 2.0
    x[:, CUE_NAMES.index("obstacle_range_m")] = np.inf
    for name, m in zip(group.inputs, mesh, strict=True):
        x[:, CUE_NAMES.index(name)] = m.ravel()
    engine = rb.engine
    shape = mesh[0].shape
    strength = engine.alpha_batch(x, gi)[0].max(axis=0).reshape(shape)
    uncovered = tuple(_describe(group.inputs, axes, tuple(int(i) for i in idx)) for idx in np.argwhere(strength <= 0.0)[:examples])
    fear = engine.group_fears_batch(x, gi)[:, 0].reshape(shape)
    violations: list[str] = []
    for k, name in enumerate(group.inputs):
        spec = CUE_SPECS[CUE_NAMES.index(name)]
        step = np.diff(fear, axis=k)  # fear(next point) − fear(point) along this cue
        left = axes[k][:-1]
        if spec.worsens is Worsens.WHEN_HIGHER:
            drop = -step
        elif spec.worsens is Worsens.WHEN_LOWER:
            drop = step
        else:  # away from the band: below it fear must not rise with brightness, above it not fall
            lo, hi = rb.brightness_band
            below = np.broadcast_to((left < lo).reshape([-1 if j == k else 1 for j in range(d)]), step.shape)
            drop = np.where(below, step, -step)
            above = (left >= hi).reshape([-1 if j == k else 1 for j in range(d)])
            drop = np.where(below | np.broadcast_to(above, step.shape), drop, 0.0)
        for idx in np.argwhere(drop > MONOTONE_TOL)[:examples]:
            i = tuple(int(v) for v in idx)
            nxt = (*i[:k], i[k] + 1, *i[k + 1 :])
            lower_is_worse = spec.worsens is Worsens.WHEN_LOWER or (
                spec.worsens is Worsens.AWAY_FROM_BAND and axes[k][i[k]] < rb.brightness_band[0]
            )
            better, worse = (nxt, i) if lower_is_worse else (i, nxt)
            violations.append(
                f"fear falls {fear[better]:.4f} → {fear[worse]:.4f} when {name} worsens "
                f"{axes[k][better[k]]:.4g} → {axes[k][worse[k]]:.4g} at {_describe(group.inputs, axes, i)}"
            )
    return GroupCheck(group.name, group.inputs, tuple(len(a) for a in axes), uncovered, tuple(violations))


def check_rules(rb: RuleBase) -> CheckReport:
    """Sweep every group and test the thresholds; the report says where completeness, monotonicity or reach fails."""
    return CheckReport(rb, tuple(check_group(rb, gi, g) for gi, g in enumerate(rb.groups)), check_thresholds(rb),
                       check_promises(rb))
