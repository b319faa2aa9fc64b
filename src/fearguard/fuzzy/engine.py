"""Compiled Mamdani inference (min/max, centroid) in numpy, equal to scikit-fuzzy's to ~1e-6.

Hand-written because scikit-fuzzy's ControlSystemSimulation costs ~20 ms per call, far too slow per
frame. It computes the same thing: memberships by linear interpolation of the terms that
scikit-fuzzy sampled on each universe, AND = min, OR = max, NOT = 1 − μ, weight × firing, max
accumulation per fear level, each level's term clipped at its activation, max aggregation, and
the exact centroid of the piecewise-linear result on the fear universe. One scalar path (Python
floats, ~30 µs) for ``evaluate`` and one vectorised path for ``evaluate_batch``.
"""

from __future__ import annotations

from bisect import bisect_left
from collections.abc import Callable
from typing import Any

import numpy as np

from fearguard.cues import BRIGHTNESS, CUE_NAMES, worst_filled
from fearguard.fear import Cause, FearLevel, FearResult
from fearguard.fuzzy.model import Rule, RuleSet
from fearguard.fuzzy.rule_text import And, Is, Node, Not

CHUNK_ROWS = 256  # rows per block in evaluate_batch: keeps the (groups, rows, fear points) block in cache

Memberships = list[Any]  # per cue index: memberships of its terms (floats or (N,) arrays), None if unused


class _Straight:
    """Straight-line Python source of rules' firing strengths over ``m`` (memberships per cue, per term).

    One assignment per AND/OR/NOT step instead of one nested expression per rule: the source has no
    nesting at all, so a rule of any width (hundreds of operands, chains of NOTs) compiles — a nested
    expression stops at the Python parser's limit of 200 levels.
    """

    def __init__(self, index: dict[tuple[str, str], tuple[int, int]], vector: bool) -> None:
        self.index, self.vector = index, vector
        self.lines: list[str] = []

    def _temp(self, expr: str) -> str:
        name = f"t{len(self.lines)}"
        self.lines.append(f"    {name} = {expr}")
        return name

    def value(self, node: Node) -> str:
        """A name (or a membership lookup) holding the node's strength, after the lines it needs."""
        if isinstance(node, Is):
            v, t = self.index[(node.variable, node.term)]
            return f"m[{v}][{t}]"
        if isinstance(node, Not):
            return self._temp(f"1.0 - {self.value(node.operand)}")
        name = ("fmin" if self.vector else "min") if isinstance(node, And) else ("fmax" if self.vector else "max")
        acc = self.value(node.operands[0])
        for op in node.operands[1:]:
            acc = self._temp(f"{name}({acc}, {self.value(op)})")
        return acc

    def compile(self, rules: list[Rule]) -> Callable[[Memberships], Any]:
        """One function returning every rule's firing strength (weighted): one call per frame, not one per
        tree node. Generated from our own parsed trees (only indices, min/max, 1 − x and weights)."""
        outs = []
        for r in rules:
            out = self.value(r.antecedent)
            outs.append(out if r.weight == 1.0 else self._temp(f"{out} * {r.weight!r}"))
        ret = f"({', '.join(outs)},)" if not self.vector else f"[{', '.join(outs)}]"
        source = "def strengths(m):\n" + "\n".join([*self.lines, f"    return {ret}"]) + "\n"
        scope: dict[str, Any] = {"fmin": np.fmin, "fmax": np.fmax, "min": min, "max": max, "__builtins__": {}}
        exec(compile(source, "<fearguard rules>", "exec"), scope)
        return scope["strengths"]


def centroid_weights(y: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Weights a, m with area = a·μ and moment = m·μ exactly for μ linear between samples y."""
    h = np.diff(y)
    area = np.zeros_like(y)
    area[:-1] += h / 2.0
    area[1:] += h / 2.0
    moment = np.zeros_like(y)
    moment[:-1] += h / 6.0 * (2.0 * y[:-1] + y[1:])
    moment[1:] += h / 6.0 * (y[:-1] + 2.0 * y[1:])
    return area, moment


class _ClipSum:
    """S(β) = Σ_i w_i·min(β, g_i) for the area and moment weights: one bisect into the sorted g.

    When at most two fear terms overlap anywhere, max(a, b) = a + b − min(a, b) turns the aggregated
    set's area and moment into sums of such S over the active levels and their overlapping pairs, so
    the scalar path needs no array work at all (exactly the dense result, up to rounding).
    """

    def __init__(self, g: np.ndarray, weights: np.ndarray) -> None:
        order = np.argsort(g, kind="stable")
        self.g = g[order].tolist()
        w = weights[order]  # (points, [area, moment])
        cum_wg = np.vstack([np.zeros((1, 2)), np.cumsum(w * g[order][:, None], axis=0)])
        cum_w = np.vstack([np.zeros((1, 2)), np.cumsum(w, axis=0)])
        total_a, total_m = cum_w[-1]
        self.rows = [
            (a_g, m_g, total_a - a, total_m - m) for (a_g, m_g), (a, m) in zip(cum_wg.tolist(), cum_w.tolist(), strict=True)
        ]

    def __call__(self, beta: float) -> tuple[float, float]:
        a_g, m_g, a_rest, m_rest = self.rows[bisect_left(self.g, beta)]
        return a_g + beta * a_rest, m_g + beta * m_rest


class _Sampled:
    """One variable's sampled terms, ready for linear interpolation at a crisp value."""

    def __init__(self, universe: np.ndarray, terms: list[np.ndarray]) -> None:
        self.lo = float(universe[0])
        self.step = float(universe[1] - universe[0])
        self.n = len(universe)
        self.matrix = np.vstack(terms)  # (n_terms, n_points)
        self.rows = self.matrix.T.tolist()  # per point: every term's membership (fast scalar lookup)
        self.last = float(self.n - 1)

    def grades(self, value: float) -> list[float]:
        """Membership of a crisp value in every term (clipped to the universe, as scikit-fuzzy does)."""
        pos = (value - self.lo) / self.step
        if pos <= 0.0:
            return self.rows[0]
        if pos >= self.last:
            return self.rows[-1]
        k = int(pos)
        w = pos - k
        return [a + w * (b - a) for a, b in zip(self.rows[k], self.rows[k + 1], strict=True)]

    def grades_batch(self, values: np.ndarray) -> np.ndarray:
        """(N,) crisp values → (n_terms, N) memberships."""
        pos = np.clip((values - self.lo) / self.step, 0.0, self.n - 1.0)
        k = np.minimum(pos.astype(np.intp), self.n - 2)
        w = pos - k
        m = self.matrix
        return m[:, k] + w * (m[:, k + 1] - m[:, k])


class Engine:
    """The rule base compiled into index tables and closures."""

    def __init__(self, rb: RuleSet) -> None:
        self.rules = rb
        self.inputs: list[tuple[int, _Sampled]] = []
        index: dict[tuple[str, str], tuple[int, int]] = {}
        for i, name in enumerate(CUE_NAMES):
            var = rb.variables.get(name)
            if var is not None:
                self.inputs.append((i, _Sampled(var.universe, list(var.terms.values()))))
                index.update({(name, term): (i, t) for t, term in enumerate(var.terms)})
        self.group_names = [g.name for g in rb.groups]
        self.causes = [g.cause for g in rb.groups]
        rules = [(gi, r) for gi, g in enumerate(rb.groups) for r in g.rules]
        self.rule_texts = [r.text for _, r in rules]
        self.rule_slots = [(gi, int(r.level)) for gi, r in rules]  # where each strength accumulates

        self.strengths = _Straight(index, vector=False).compile([r for _, r in rules])
        self.strengths_batch = _Straight(index, vector=True).compile([r for _, r in rules])
        self.fear = _Sampled(rb.fear_variable.universe, list(rb.fear_variable.terms.values()))
        self.out_mf = self.fear.matrix
        # each level's support as a slice: the batch path only touches the points a level can raise
        self.supports = [slice(int(np.flatnonzero(mf > 0)[0]), int(np.flatnonzero(mf > 0)[-1]) + 1) for mf in self.out_mf]
        self.centroid_w = np.column_stack(centroid_weights(rb.fear_variable.universe))  # (points, [area, moment])
        area_w, moment_w = centroid_weights(rb.fear_variable.universe)  # contiguous: the same sums as ever, bit for bit
        # fear when only that level fires fully: the centroid of each level's term
        self.level_anchors = np.array([float(mf @ moment_w) / float(mf @ area_w) for mf in rb.fear_variable.terms.values()])
        mf = self.out_mf
        self.closed_form = int((mf > 0).sum(axis=0).max()) <= 2  # at most two fear terms overlap anywhere
        self.level_sums = [_ClipSum(g, self.centroid_w) for g in mf]
        self.pair_table = [
            [_ClipSum(np.minimum(mf[a], mf[b]), self.centroid_w) if a < b and np.any((mf[a] > 0) & (mf[b] > 0)) else None
             for b in range(len(mf))]
            for a in range(len(mf))
        ]
        self.group_rules = [[(r.text, int(r.level)) for r in g.rules] for g in rb.groups]

    def level_of(self, fear: float) -> FearLevel:
        """The level whose fear term has the highest membership at this fear (ties: the higher)."""
        grades = self.fear.grades(fear)
        best = 0
        for i, g in enumerate(grades):
            if g >= grades[best]:
                best = i
        return FearLevel(best)

    def _defuzz(self, mu: np.ndarray) -> np.ndarray:
        """Centroid of each aggregated set (last axis); a set with no area (no rule fired) gives 1."""
        sums = mu @ self.centroid_w
        area, moment = sums[..., 0], sums[..., 1]
        out = np.ones_like(area)
        np.divide(moment, area, out=out, where=area > 0.0)
        return out

    # -- scalar path -------------------------------------------------------------------------
    def _infer(self, x: list[float]) -> tuple[list[float], dict[str, float]]:
        mem: Memberships = [None] * len(CUE_NAMES)
        for i, sampled in self.inputs:
            mem[i] = sampled.grades(x[i])
        strengths = self.strengths(mem)
        n_levels = len(self.out_mf)
        alpha = [[0.0] * n_levels for _ in self.group_names]
        for (gi, level), s in zip(self.rule_slots, strengths, strict=True):
            row = alpha[gi]
            if s > row[level]:
                row[level] = s
        activations = dict(zip(self.rule_texts, strengths, strict=True))
        if self.closed_form:
            return [self._centroid(row) for row in alpha], activations
        fears = [1.0] * len(self.group_names)  # fear terms overlapping three or more deep (e.g. Gaussian): dense
        keys = [(gi, k) for gi, row in enumerate(alpha) for k in range(n_levels) if row[k] > 0.0]
        if keys:
            clipped = np.minimum(self.out_mf[[k for _, k in keys]], np.array([alpha[g][k] for g, k in keys])[:, None])
            starts = [n for n, key in enumerate(keys) if n == 0 or key[0] != keys[n - 1][0]]
            sums = (np.maximum.reduceat(clipped, starts, axis=0) @ self.centroid_w).tolist()
            for n, (area, moment) in zip(starts, sums, strict=True):
                fears[keys[n][0]] = moment / area if area > 0.0 else 1.0
        return fears, activations

    def _centroid(self, alpha: list[float]) -> float:
        """Closed-form centroid of one group's aggregated set; 1 when no rule fired."""
        area = moment = 0.0
        active: list[int] = []
        for level, a in enumerate(alpha):
            if a > 0.0:
                da, dm = self.level_sums[level](a)
                area += da
                moment += dm
                for other in active:  # overlapping pairs were counted twice: take their min back out
                    pair = self.pair_table[other][level]
                    if pair is not None:
                        b = alpha[other]
                        da, dm = pair(a if a < b else b)
                        area -= da
                        moment -= dm
                active.append(level)
        return moment / area if active else 1.0

    def evaluate(self, raw: list[float]) -> FearResult:
        x, unknown = worst_filled(raw, 0.0)
        groups, acts = self._infer(x)
        if unknown[BRIGHTNESS]:
            x[BRIGHTNESS] = 255.0
            glare, glare_acts = self._infer(x)
            if max(glare) > max(groups):
                groups, acts = glare, glare_acts
        fear = max(groups)
        cause_fears = dict.fromkeys(Cause, 0.0)
        for cause, f in zip(self.causes, groups, strict=True):
            if f > cause_fears[cause]:
                cause_fears[cause] = f
        return FearResult(
            fear=fear,
            level=self.level_of(fear),
            activations=acts,
            group_fears=dict(zip(self.group_names, groups, strict=True)),
            cause_fears=cause_fears,
            candidate_drivers=self.group_rules[groups.index(fear)],
        )

    # -- vector path -------------------------------------------------------------------------
    def group_fears_batch(self, x: np.ndarray, only: int | None = None) -> np.ndarray:
        """(N, 6) cues with unknowns already replaced → (N, n_groups) fear per group (or one group's)."""
        out = np.empty((len(x), len(self.group_names) if only is None else 1))
        for start in range(0, len(x), CHUNK_ROWS):
            out[start : start + CHUNK_ROWS] = self._infer_block(x[start : start + CHUNK_ROWS], only).T
        return out

    def alpha_batch(self, x: np.ndarray, only: int | None = None) -> np.ndarray:
        """Activation of every fear level per group: (N, 6) → (n_groups or 1, n_levels, N)."""
        mem: Memberships = [None] * len(CUE_NAMES)
        for i, sampled in self.inputs:
            mem[i] = sampled.grades_batch(x[:, i])
        alpha = np.zeros((len(self.group_names) if only is None else 1, len(self.out_mf), len(x)))
        for (gi, level), s in zip(self.rule_slots, self.strengths_batch(mem), strict=True):
            if only is None or gi == only:
                row = alpha[gi if only is None else 0, level]
                np.maximum(row, s, out=row)
        return alpha

    def _infer_block(self, x: np.ndarray, only: int | None) -> np.ndarray:
        alpha = self.alpha_batch(x, only)
        mu = np.zeros((len(alpha), len(x), self.out_mf.shape[1]))
        for level, sl in enumerate(self.supports):
            part = mu[:, :, sl]
            np.maximum(part, np.minimum(alpha[:, level, :, None], self.out_mf[level, sl]), out=part)
        return self._defuzz(mu)
