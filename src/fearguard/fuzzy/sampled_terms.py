"""scikit-fuzzy's samples of the bundled rule files' terms, shipped with the package (``sampled_terms.npz``).

Importing scikit-fuzzy costs about 0.8 s (it pulls in scipy.optimize, scipy.spatial, networkx); a car
starting its loop should not pay that for the bundled rules, whose terms never change. The file holds
every term of the bundled rule files as scikit-fuzzy sampled it, keyed by shape, parameters and a digest
of the universe's sample points, so a lookup is exact for any rule file that uses the same term on the
same universe; any other term is sampled by scikit-fuzzy as before. Regenerate after editing a bundled
rule file: ``python -m fearguard.fuzzy.ship_terms`` (a test checks the file against scikit-fuzzy).
"""

from __future__ import annotations

from collections.abc import Sequence
from functools import lru_cache
from pathlib import Path

import numpy as np

SHIPPED = Path(__file__).with_name("sampled_terms.npz")


def term_key(shape: str, params: Sequence[float], grid: np.ndarray) -> str:
    """The key of one sampled term: shape, exact parameters, and a digest of the exact sample points."""
    import hashlib  # its OpenSSL binding costs an import on the car only when the rules are loaded

    digest = hashlib.sha256(np.ascontiguousarray(grid, dtype=float).tobytes()).hexdigest()[:20]
    return f"{shape}({', '.join(repr(float(p)) for p in params)}) on {digest}"


@lru_cache(maxsize=1)
def _shipped() -> dict[str, np.ndarray]:
    if not SHIPPED.is_file():
        return {}
    with np.load(SHIPPED) as data:
        return {key: data[key] for key in data.files}


def shipped_sample(shape: str, params: Sequence[float], grid: np.ndarray) -> np.ndarray | None:
    """The shipped scikit-fuzzy sample of this term on this grid, or None if it is not shipped."""
    found = _shipped().get(term_key(shape, params, grid))
    return None if found is None or found.shape != np.shape(grid) else found.copy()
