"""How the ego lane bends: both boundaries as one hyperbola pair, traced along their marking ridges.

A lane boundary on flat ground, x(d) = x₀ + θ·d + (κ/2)·d² (lateral offset over forward distance d, curvature κ),
seen by a pinhole camera whose horizon is image row h, is the image curve

    u(v) = k / (v − h) + b · (v − h) + c        (k ∝ κ, the same for both boundaries of a lane)

— the *hyperbola-pair* lane model (Chen & Wang, 2006): the straight line b·(v − h) + c of the classic pipeline plus
one shared term for the bend. It is linear in its five unknowns (k, b and c of each side), so a least-squares fit
of the marking ridges' inner edges (``ridges.scan_ridges``) gives it; scanning again along the fitted curve finds
the ridges the straight chord missed on a curve (each scan looks ``ridges.SEARCH`` of the width either side), so a
few rounds trace the markings round the bend as far as they stay ridges. The straight lines stay the lane model's
tracked state (the Kalman tracks, the confidence); the bend moves only the aim point, which the chord of a curve
puts on its outside (the car under-steers and drifts out of a tight curve).

Written by hand: a three-term linear least-squares fit and a loop of ridge scans; no library fits this model.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from fearguard.vision.lanes import REFIT_MIN_ROWS, LaneLine, RoadRegion
from fearguard.vision.ridges import RidgeMaps, scan_ridges

ROUNDS = 2  # [-] scan → fit rounds: each reaches ridges up to ridges.SEARCH beyond the last curve (a third traced no
#   more on the synthetic bends of tests/vision/test_bend.py); a round whose curve stays on the last scan's ends it
MIN_HORIZON_GAP_PX = 2.0  # [px] rows closer to the horizon than this are not fitted (the bend term diverges there)
OUTLIER_PX = 0.012  # [-] of the width: an inner edge this far off the fitted curve is not on it (refitted without)
BEND_PRIOR = 1e-4  # [-] ridge weight that pulls k toward 0 (a straight lane) when the rows cannot tell the bend
MIN_SPAN = 0.25  # [-] of the road rows: a side's ridges must spread over this many rows to take part in the fit (one dash
#   near the car tells no bend: fitted to it alone, the aim swung 42° on a synthetic road)


@dataclass(frozen=True)
class Bend:
    """The lane's boundaries as u = k/(v − h) + b·(v − h) + c in working pixels (None: that side not traced)."""

    horizon_v_px: float
    k_px2: float  # the shared bend term (+: the lane bends right in the picture, toward +u, away from the horizon)
    left: tuple[float, float] | None  # (b, c) of the left boundary
    right: tuple[float, float] | None
    rows: tuple[int, int]  # the image rows the traced ridges span (first, last)

    def u_at(self, side: tuple[float, float], v_px: float | np.ndarray) -> float | np.ndarray:
        x = np.maximum(np.asarray(v_px, np.float64) - self.horizon_v_px, MIN_HORIZON_GAP_PX)
        return self.k_px2 / x + side[0] * x + side[1]


def trace_bend(
    maps: RidgeMaps, region: RoadRegion, left: LaneLine | None, right: LaneLine | None, lane_width_px: np.ndarray,
    horizon_v_px: float,
) -> Bend | None:
    """The hyperbola pair through the marking ridges along both boundaries, starting from their straight lines; None
    when no side has REFIT_MIN_ROWS ridge rows spread over MIN_SPAN of the road rows (a side without them is not traced:
    None in the result). ``lane_width_px``: the lane width on each road row."""
    rows = np.arange(region.top_v_px, region.bottom_v_px + 1)
    x = rows - horizon_v_px
    usable = x >= MIN_HORIZON_GAP_PX
    rows, x, lane_width_px = rows[usable], x[usable], lane_width_px[usable]
    sides = [(i, line) for i, line in enumerate((left, right)) if line is not None]
    if not sides or len(rows) < REFIT_MIN_ROWS:
        return None
    centres = np.array([line.u_at(rows) for _, line in sides])
    inner_is_left = np.array([i == 1 for i, _ in sides])
    best: tuple[int, np.ndarray, np.ndarray, np.ndarray] | None = None  # rows found, the fit, the ridge rows, their edges
    tol = OUTLIER_PX * region.width_px
    for _ in range(ROUNDS):
        scan = scan_ridges(maps, rows, centres, lane_width_px, inner_is_left)
        ok = scan.ok
        found = int(ok.sum())
        if best is not None and found <= best[0]:
            break
        solved = _fit(x, scan.inner_u, ok & _spans(ok, MIN_SPAN * len(rows)), tol)
        if solved is None:
            break
        best = (found, solved, ok, scan.inner_u)
        curves = _curves(solved, x, len(sides))
        moved = np.where(np.isnan(curves), centres, curves)  # a side without ridges keeps its line
        if np.abs(moved - centres).max() < 1.0:  # the curve is where the last scan looked: another finds the same ridges
            break
        centres = moved
    if best is None:
        return None
    _, params, ok, inner_u = best
    if len(sides) == 2 and _cross(params, x, ok):  # two boundaries of one lane never meet: the weaker side's ridges are
        ok = ok.copy()  # another marking's (a far line of the other side, a dash of the next lane); traced without it
        ok[int(np.argmin(ok.sum(axis=1)))] = False
        params = _fit(x, inner_u, ok & _spans(ok, MIN_SPAN * len(rows)), tol)
        if params is None:
            return None
    traced = ok.any(axis=0)
    per_side: list[tuple[float, float] | None] = [None, None]
    for j, (i, _) in enumerate(sides):
        b, c = float(params[1 + 2 * j]), float(params[2 + 2 * j])
        if not np.isnan(b):
            per_side[i] = (b, c)
    span = rows[traced]
    return Bend(horizon_v_px, float(params[0]), per_side[0], per_side[1], (int(span[0]), int(span[-1])))


def _fit(x: np.ndarray, inner_u: np.ndarray, ok: np.ndarray, tol: float) -> np.ndarray | None:
    """Least squares of [k, b₁, c₁, b₂, c₂, ...] over the ok rows of each side (a side without rows: NaN), k pulled
    toward 0 by BEND_PRIOR; one refit without the rows farther than ``tol`` from the first fit. Solved by its normal
    equations (sums over the rows, a (1 + 2·sides)² system, Jacobi-scaled): a few array operations per fit."""
    sides = ok.shape[0]
    solution = None
    for _ in range(2):
        if not ok.any():
            return None
        w = ok.astype(np.float64)
        u = np.where(ok, inner_u, 0.0)
        inv, n = 1.0 / x, len(w[0])
        size = 1 + 2 * sides
        normal = np.zeros((size, size))
        rhs = np.zeros(size)
        normal[0, 0] = (w @ (inv * inv)).sum() + BEND_PRIOR**2 * w.sum() * (inv[ok.any(axis=0)].max()) ** 2
        rhs[0] = (u * inv).sum()
        for j in range(sides):
            b, c = 1 + 2 * j, 2 + 2 * j
            normal[0, b] = normal[b, 0] = w[j].sum()  # (1/x)·x
            normal[0, c] = normal[c, 0] = w[j] @ inv
            normal[b, b], normal[b, c], normal[c, c] = w[j] @ (x * x), w[j] @ x, w[j].sum()
            normal[c, b] = normal[b, c]
            rhs[b], rhs[c] = u[j] @ x, u[j].sum()
        empty = np.repeat(w.sum(axis=1) == 0, 2)
        normal[1:, 1:][np.diag(empty)] = 1.0  # a side without rows: its own unknowns, decoupled (NaN below)
        d = 1.0 / np.sqrt(np.diag(normal))
        solution = d * np.linalg.solve(normal * d[:, None] * d[None, :], rhs * d)
        solution[1:][empty] = np.nan
        residual = np.abs(_curves(solution, x, sides) - np.where(ok, inner_u, np.nan))
        keep = ok & (residual <= tol)
        if keep.sum() == ok.sum():
            break
        ok = keep & _spans(keep, MIN_SPAN * n)
    return solution


def _cross(params: np.ndarray, x: np.ndarray, ok: np.ndarray) -> bool:
    """Whether the fitted left and right boundaries meet on the rows the ridges span (right − left ≤ 0 somewhere)."""
    rows = ok.any(axis=0)
    if not rows.any() or np.isnan(params[1:]).any():
        return False
    span = x[np.flatnonzero(rows)[0] : np.flatnonzero(rows)[-1] + 1]
    left, right = _curves(params, span, 2)
    return bool((right - left <= 0).any())


def _spans(ok: np.ndarray, min_rows: float) -> np.ndarray:
    """(sides, 1) bool: the side has REFIT_MIN_ROWS ridge rows spread over at least ``min_rows`` rows (a bend is not
    told by one dash: fitted to it, k can take any value)."""
    idx = np.arange(ok.shape[1])
    first = np.where(ok, idx, ok.shape[1]).min(axis=1)
    last = np.where(ok, idx, -1).max(axis=1)
    return ((ok.sum(axis=1) >= REFIT_MIN_ROWS) & (last - first >= min_rows))[:, None]


def _curves(params: np.ndarray, x: np.ndarray, sides: int) -> np.ndarray:
    """Each side's fitted u on the rows x (v − h); a side without a fit stays NaN."""
    return np.array([params[0] / x + params[1 + 2 * j] * x + params[2 + 2 * j] for j in range(sides)])
