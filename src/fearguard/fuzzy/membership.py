"""Membership-function shapes, sampled on a variable's universe by scikit-fuzzy.

A term is written in TOML as ``low = { trapmf = [0, 0, 0.25, 0.5] }``; this module knows which
scikit-fuzzy generator each shape name means, how many parameters it takes, and what makes them valid.
The bundled rule files' terms come from scikit-fuzzy's samples shipped with the package
(``sampled_terms.py``), so scikit-fuzzy is imported only for other terms.
"""

from __future__ import annotations

from collections.abc import Callable, Sequence
from dataclasses import dataclass
from functools import partial
from itertools import pairwise
from typing import Any

import numpy as np

from fearguard.fuzzy.sampled_terms import shipped_sample


@dataclass(frozen=True)
class Shape:
    """A scikit-fuzzy membership generator and the rule its parameters must follow."""

    sample: Callable[[np.ndarray, Sequence[float]], np.ndarray]
    n_params: int
    requirement: str
    valid: Callable[[Sequence[float]], bool]


def _sorted(p: Sequence[float]) -> bool:
    return all(a <= b for a, b in pairwise(p))


Generator = Callable[[Any, np.ndarray, Sequence[float]], np.ndarray]  # (skfuzzy module, grid, params) → samples
_GENERATORS: dict[str, Generator] = {}


def _skfuzzy() -> Any:
    import skfuzzy  # ~0.8 s of imports: only for a term that is not shipped (sampled_terms.py)

    return skfuzzy


def skfuzzy_sample(shape: str, grid: np.ndarray, params: Sequence[float]) -> np.ndarray:
    """The term sampled by scikit-fuzzy itself."""
    return np.asarray(_GENERATORS[shape](_skfuzzy(), grid, params), dtype=float)


def _sample(shape: str, grid: np.ndarray, params: Sequence[float]) -> np.ndarray:
    shipped = shipped_sample(shape, params, grid)
    return shipped if shipped is not None else skfuzzy_sample(shape, grid, params)


def _shipped_or_skfuzzy(shape: str, generator: Generator) -> Callable[[np.ndarray, Sequence[float]], np.ndarray]:
    """The sampler of one shape: the shipped scikit-fuzzy samples if this term is there, else scikit-fuzzy."""
    _GENERATORS[shape] = generator
    return partial(_sample, shape)


SHAPES: dict[str, Shape] = {
    "trimf": Shape(_shipped_or_skfuzzy("trimf", lambda sk, x, p: sk.trimf(x, list(p))), 3, "a <= b <= c", _sorted),
    "trapmf": Shape(_shipped_or_skfuzzy("trapmf", lambda sk, x, p: sk.trapmf(x, list(p))), 4, "a <= b <= c <= d", _sorted),
    "gaussmf": Shape(_shipped_or_skfuzzy("gaussmf", lambda sk, x, p: sk.gaussmf(x, *p)), 2, "sigma > 0", lambda p: p[1] > 0),
    "gauss2mf": Shape(
        _shipped_or_skfuzzy("gauss2mf", lambda sk, x, p: sk.gauss2mf(x, *p)), 4, "mean1 <= mean2, sigma1 > 0, sigma2 > 0",
        lambda p: p[0] <= p[2] and p[1] > 0 and p[3] > 0,
    ),
    "gbellmf": Shape(_shipped_or_skfuzzy("gbellmf", lambda sk, x, p: sk.gbellmf(x, *p)), 3, "a > 0", lambda p: p[0] > 0),
    "sigmf": Shape(_shipped_or_skfuzzy("sigmf", lambda sk, x, p: sk.sigmf(x, *p)), 2, "any b, c", lambda p: True),
    "smf": Shape(_shipped_or_skfuzzy("smf", lambda sk, x, p: sk.smf(x, *p)), 2, "a < b", lambda p: p[0] < p[1]),
    "zmf": Shape(_shipped_or_skfuzzy("zmf", lambda sk, x, p: sk.zmf(x, *p)), 2, "a < b", lambda p: p[0] < p[1]),
    "pimf": Shape(_shipped_or_skfuzzy("pimf", lambda sk, x, p: sk.pimf(x, *p)), 4, "a <= b <= c <= d", _sorted),
}


def universe_grid(start: float, stop: float, step: float) -> np.ndarray:
    """Uniform sample points from start to stop inclusive (what scikit-fuzzy calls a universe)."""
    n = round((stop - start) / step) + 1
    return start + step * np.arange(n, dtype=float)
