"""Write ``sampled_terms.npz``: every term of the bundled rule files, sampled by scikit-fuzzy itself.

``python -m fearguard.fuzzy.ship_terms`` after editing a bundled rule file (tests/test_sampled_terms.py
fails until then). Nothing imports this module: it is the tool, ``sampled_terms.py`` the lookup.
"""

from __future__ import annotations

from collections.abc import Iterable
from pathlib import Path

import numpy as np

from fearguard.fuzzy.loader import bundled_rules_path, load_rules
from fearguard.fuzzy.membership import skfuzzy_sample
from fearguard.fuzzy.sampled_terms import SHIPPED, term_key

BUNDLED_RULE_FILES = ("default.toml", "road_car.toml")


def sample_all(paths: Iterable[Path]) -> dict[str, np.ndarray]:
    """Every term of these rule files sampled by scikit-fuzzy itself (never the shipped file), by key."""
    samples: dict[str, np.ndarray] = {}
    for path in paths:
        rules = load_rules(path)
        for var in [*rules.variables.values(), rules.fear_variable]:
            for shape, params in var.shapes.values():
                samples[term_key(shape, params, var.universe)] = skfuzzy_sample(shape, var.universe, params)
    return samples


def main() -> None:
    samples = sample_all(bundled_rules_path(name) for name in BUNDLED_RULE_FILES)
    np.savez_compressed(SHIPPED, **samples)
    print(f"{SHIPPED}: {len(samples)} terms of {', '.join(BUNDLED_RULE_FILES)} sampled by scikit-fuzzy")


if __name__ == "__main__":
    main()
