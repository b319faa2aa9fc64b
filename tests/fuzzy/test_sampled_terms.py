"""The shipped term samples are scikit-fuzzy's own, and the car builds a FearGuard without importing scikit-fuzzy."""

from __future__ import annotations

import subprocess
import sys

import numpy as np

import fearguard as fg
from fearguard.fuzzy.loader import bundled_rules_path
from fearguard.fuzzy.membership import skfuzzy_sample
from fearguard.fuzzy.sampled_terms import _shipped, shipped_sample, term_key
from fearguard.fuzzy.ship_terms import BUNDLED_RULE_FILES, sample_all


def test_the_shipped_samples_are_exactly_what_scikit_fuzzy_samples_for_every_bundled_term():
    fresh = sample_all(bundled_rules_path(name) for name in BUNDLED_RULE_FILES)
    shipped = _shipped()
    assert set(shipped) == set(fresh), "sampled_terms.npz is stale: run python -m fearguard.fuzzy.ship_terms"
    for key, samples in fresh.items():
        assert np.array_equal(shipped[key], samples), key


def test_bundled_rules_use_the_shipped_samples_and_other_terms_scikit_fuzzy(write_rules):
    rules = fg.load_rules()
    var = rules.variables["lane_confidence"]
    for term, (shape, params) in var.shapes.items():
        assert shipped_sample(shape, params, var.universe) is not None
        assert np.array_equal(var.terms[term], skfuzzy_sample(shape, var.universe, params))
    changed = fg.load_rules(write_rules(("universe = [0.0, 1.0, 0.001]", "universe = [0.0, 1.0, 0.002]")))
    var = changed.variables["lane_confidence"]
    shape, params = next(iter(var.shapes.values()))
    assert shipped_sample(shape, params, var.universe) is None, "another universe is not in the shipped file"
    assert np.array_equal(next(iter(var.terms.values())), skfuzzy_sample(shape, var.universe, params))


def test_the_key_is_exact_in_parameters_and_sample_points():
    grid = np.linspace(0.0, 1.0, 11)
    assert term_key("trimf", (0, 0.5, 1), grid) == term_key("trimf", (0.0, 0.5, 1.0), grid.copy())
    assert term_key("trimf", (0, 0.5, 1), grid) != term_key("trimf", (0, 0.5 + 1e-15, 1), grid)
    assert term_key("trimf", (0, 0.5, 1), grid) != term_key("trimf", (0, 0.5, 1), np.nextafter(grid, 2.0))


def test_building_a_fearguard_with_a_bundled_rule_file_does_not_import_scikit_fuzzy():
    probe = (
        "import sys, fearguard as fg; from fearguard.fuzzy.loader import bundled_rules_path\n"
        "fg.FearGuard(lambda f: 0.0); fg.FearGuard(lambda f: 0.0, rules=bundled_rules_path('road_car.toml'))\n"
        "print('skfuzzy' in sys.modules)"
    )
    out = subprocess.run([sys.executable, "-c", probe], check=True, capture_output=True, text=True).stdout
    assert out.strip() == "False"
