"""Membership-function shapes, sampled on a variable's universe by scikit-fuzzy.

A term is written in TOML as ``low = { trapmf = [0, 0, 0.25, 0.5] }``; this module knows which
scikit-fuzzy generator each shape name means, how many parameters it takes, and what makes them valid.
"""

from __future__ import annotations

from collections.abc import Callable, Sequence
from dataclasses import dataclass
from itertools import pairwise

import numpy as np
import skfuzzy


@dataclass(frozen=True)
class Shape:
    """A scikit-fuzzy membership generator and the rule its parameters must follow."""

    sample: Callable[[np.ndarray, Sequence[float]], np.ndarray]
    n_params: int
    requirement: str
    valid: Callable[[Sequence[float]], bool]


def _sorted(p: Sequence[float]) -> bool:
    return all(a <= b for a, b in pairwise(p))


SHAPES: dict[str, Shape] = {
    "trimf": Shape(lambda x, p: skfuzzy.trimf(x, list(p)), 3, "a <= b <= c", _sorted),
    "trapmf": Shape(lambda x, p: skfuzzy.trapmf(x, list(p)), 4, "a <= b <= c <= d", _sorted),
    "gaussmf": Shape(lambda x, p: skfuzzy.gaussmf(x, *p), 2, "sigma > 0", lambda p: p[1] > 0),
    "gauss2mf": Shape(
        lambda x, p: skfuzzy.gauss2mf(x, *p), 4, "sigma1 > 0, sigma2 > 0", lambda p: p[1] > 0 and p[3] > 0
    ),
    "gbellmf": Shape(lambda x, p: skfuzzy.gbellmf(x, *p), 3, "a > 0", lambda p: p[0] > 0),
    "sigmf": Shape(lambda x, p: skfuzzy.sigmf(x, *p), 2, "any b, c", lambda p: True),
    "smf": Shape(lambda x, p: skfuzzy.smf(x, *p), 2, "a < b", lambda p: p[0] < p[1]),
    "zmf": Shape(lambda x, p: skfuzzy.zmf(x, *p), 2, "a < b", lambda p: p[0] < p[1]),
    "pimf": Shape(lambda x, p: skfuzzy.pimf(x, *p), 4, "a <= b <= c <= d", _sorted),
}


def universe_grid(start: float, stop: float, step: float) -> np.ndarray:
    """Uniform sample points from start to stop inclusive (what scikit-fuzzy calls a universe)."""
    n = round((stop - start) / step) + 1
    return start + step * np.arange(n, dtype=float)
