"""The compiled engine against scikit-fuzzy's own ControlSystemSimulation, and its own contracts."""

from __future__ import annotations

import math

import numpy as np
import pytest

import fearguard as fg
from fearguard.fear import Cause

AGREEMENT = 5e-4  # issue #2: engine vs reference_fear on random cue vectors


def random_cues(n: int, seed: int) -> np.ndarray:
    rng = np.random.default_rng(seed)
    x = np.column_stack([rng.uniform(0, 1, n), rng.uniform(0, 255, n), rng.uniform(0, 1, n),
                         rng.uniform(0, 5, n), rng.uniform(0, 40, n)])
    x[rng.uniform(size=x.shape) < 0.03] = np.nan  # some unknown cues too
    return x


@pytest.mark.slow
def test_engine_agrees_with_scikit_fuzzy_on_1000_random_vectors(rules: fg.RuleBase) -> None:
    x = random_cues(1000, seed=7)
    ref = np.array([rules.reference_fear(row) for row in x])
    eng = np.array([rules.evaluate(row).fear for row in x])
    assert np.abs(ref - eng).max() <= AGREEMENT


@pytest.mark.slow
def test_road_car_rules_agree_with_scikit_fuzzy() -> None:
    rb = fg.load_rules("rules/road_car.toml")
    rng = np.random.default_rng(3)
    x = np.column_stack([rng.uniform(0, 1, 200), rng.uniform(0, 255, 200), rng.uniform(0, 1, 200),
                         rng.uniform(0, 120, 200), rng.uniform(0, 150, 200)])
    assert max(abs(rb.reference_fear(r) - rb.evaluate(r).fear) for r in x) <= AGREEMENT


def test_batch_equals_scalar_path(rules: fg.RuleBase) -> None:
    x = random_cues(3000, seed=11)  # more than one block of rows
    scalar = np.array([rules.evaluate(row).fear for row in x])
    np.testing.assert_allclose(rules.evaluate_batch(x), scalar, rtol=0, atol=1e-12)


def test_batch_rejects_wrong_shapes(rules: fg.RuleBase) -> None:
    with pytest.raises(ValueError, match=r"shape \(N, 5\)"):
        rules.evaluate_batch(np.zeros((3, 4)))


def test_calm_cues_give_very_low_fear_and_hazards_raise_it(rules: fg.RuleBase) -> None:
    calm = fg.Cues(lane_confidence=0.9, brightness=120.0, occlusion=0.0, obstacle_range_m=3.0, qr_staleness_s=0.5)
    res = rules.evaluate(calm)
    assert res.level is fg.FearLevel.VERY_LOW and res.fear < 0.1
    lost = rules.evaluate(fg.Cues(0.1, 120.0, 0.9, 3.0, 0.5))
    assert lost.level is fg.FearLevel.VERY_HIGH and lost.dominant_cause is Cause.ROAD
    assert lost.top_rules(1)[0][0] == "IF occlusion IS heavy AND lane_confidence IS low THEN fear IS very_high"
    near = rules.evaluate(fg.Cues(0.9, 120.0, 0.0, 0.6, 0.5))
    assert near.level is fg.FearLevel.HIGH and near.dominant_cause is Cause.COLLISION
    stale = rules.evaluate(fg.Cues(0.9, 120.0, 0.0, 3.0, 25.0))
    assert stale.dominant_cause is Cause.LOCALISATION and stale.fear >= rules.policy.emergency_enter_fear


def test_activations_explain_every_rule(rules: fg.RuleBase) -> None:
    res = rules.evaluate(fg.Cues(0.4, 120.0, 0.35, 3.0, 0.5))
    assert set(res.activations) == {r.text for r in rules.rules}
    assert all(0.0 <= s <= 1.0 for s in res.activations.values())
    assert res.activations["IF lane_confidence IS medium THEN fear IS low"] == pytest.approx(0.6)
    assert res.group_fears and set(res.cause_fears) == set(Cause)
    assert res.fear == max(res.group_fears.values())


def test_inputs_beyond_the_universe_are_clipped_like_scikit_fuzzy(rules: fg.RuleBase) -> None:
    far = rules.evaluate(fg.Cues(0.9, 120.0, 0.0, math.inf, 0.5)).fear
    assert far == rules.evaluate(fg.Cues(0.9, 120.0, 0.0, 4.0, 0.5)).fear == rules.evaluate(fg.Cues(0.9, 120.0, 0.0, 50.0, 0.5)).fear
    assert rules.reference_fear(fg.Cues(0.9, 120.0, 0.0, math.inf, 0.5)) == pytest.approx(far, abs=AGREEMENT)


def test_weights_scale_the_firing_strength(write_rules) -> None:
    path = write_rules(('"IF lane_confidence IS low THEN fear IS high"', '"IF lane_confidence IS low THEN fear IS high WITH 0.5"'))
    rb = fg.load_rules(path)
    res = rb.evaluate(fg.Cues(0.0, 120.0, 0.0, 3.0, 0.5))
    assert res.activations["IF lane_confidence IS low THEN fear IS high WITH 0.5"] == 0.5
    assert res.fear == pytest.approx(rb.reference_fear(fg.Cues(0.0, 120.0, 0.0, 3.0, 0.5)), abs=AGREEMENT)


def test_three_way_and_or_not_agree_with_reference(write_rules) -> None:
    path = write_rules((
        '"IF occlusion IS NOT none AND lane_confidence IS NOT high THEN fear IS medium"',
        '"IF occlusion IS NOT none AND lane_confidence IS NOT high AND NOT (occlusion IS heavy OR occlusion IS none OR '
        'lane_confidence IS low) THEN fear IS medium"',
    ))
    rb = fg.load_rules(path)
    for row in random_cues(100, seed=5):
        assert rb.evaluate(row).fear == pytest.approx(rb.reference_fear(row), abs=AGREEMENT)


def test_gaussian_fear_terms_also_agree(write_rules) -> None:
    path = write_rules(
        ("very_low = { trimf = [0.0, 0.0, 0.25] }", "very_low = { gaussmf = [0.0, 0.1] }"),
        ("medium = { trimf = [0.25, 0.5, 0.75] }\nhigh", "medium = { gaussmf = [0.5, 0.1] }\nhigh"),
    )
    rb = fg.load_rules(path)
    for row in random_cues(100, seed=9):
        assert rb.evaluate(row).fear == pytest.approx(rb.reference_fear(row), abs=AGREEMENT)
    np.testing.assert_allclose(rb.evaluate_batch(random_cues(50, 2)), [rb.evaluate(r).fear for r in random_cues(50, 2)], atol=1e-12)


def test_level_of_takes_the_stronger_term_and_the_higher_on_ties(rules: fg.RuleBase) -> None:
    assert rules.level_of(0.0) is fg.FearLevel.VERY_LOW
    assert rules.level_of(0.125) is fg.FearLevel.LOW  # very_low and low both 0.5: the higher wins
    assert rules.level_of(0.74) is fg.FearLevel.HIGH
    assert rules.level_of(1.0) is fg.FearLevel.VERY_HIGH


MINIMAL = """
name = "one cue"
[variables.obstacle_range_m]
universe = [0.0, 4.0, 0.01]
near = { trapmf = [0.0, 0.0, 0.5, 1.0] }
far = { trapmf = [0.5, 1.0, 4.0, 4.0] }
[fear]
universe = [0.0, 1.0, 0.005]
very_low = { trimf = [0.0, 0.0, 0.25] }
low = { trimf = [0.0, 0.25, 0.5] }
medium = { trimf = [0.25, 0.5, 0.75] }
high = { trimf = [0.5, 0.75, 1.0] }
very_high = { trimf = [0.75, 1.0, 1.0] }
[groups.collision]
cause = "collision"
rules = ["IF obstacle_range_m IS near THEN fear IS very_high"]
"""


def test_a_minimal_rule_base_ignores_cues_it_does_not_use(tmp_path) -> None:
    path = tmp_path / "minimal.toml"
    path.write_text(MINIMAL)
    rb = fg.load_rules(path)
    assert rb.policy == fg.PolicyConfig() and rb.brightness_band == (0.0, 255.0)
    assert rb.evaluate(fg.Cues(math.nan, math.nan, math.nan, 0.2, math.nan)).fear > 0.9
    # nothing fires when far: the (incomplete) rule base answers with the worst fear
    far = rb.evaluate(fg.Cues(0.9, 120.0, 0.0, 3.0, 0.5))
    assert far.fear == 1.0 and far.top_rules() == [] and rb.evaluate_batch(np.array([[0.9, 120.0, 0.0, 3.0, 0.5]]))[0] == 1.0
    # the same with Gaussian fear terms (dense path)
    path.write_text(MINIMAL.replace("very_low = { trimf = [0.0, 0.0, 0.25] }", "very_low = { gaussmf = [0.0, 0.1] }"))
    assert fg.load_rules(path).evaluate(fg.Cues(0.9, 120.0, 0.0, 3.0, 0.5)).fear == 1.0


def test_unknown_brightness_takes_the_worse_extreme(write_rules) -> None:
    rb = fg.load_rules(write_rules(('"IF brightness IS dark OR brightness IS glare THEN fear IS very_high"',
                                    '"IF brightness IS dark THEN fear IS high", "IF brightness IS glare THEN fear IS very_high"')))
    glare = rb.evaluate(fg.Cues(0.9, 255.0, 0.0, 3.0, 0.5)).fear
    assert glare > rb.evaluate(fg.Cues(0.9, 0.0, 0.0, 3.0, 0.5)).fear
    assert rb.evaluate(fg.Cues(0.9, math.nan, 0.0, 3.0, 0.5)).fear == glare
    assert rb.reference_fear(fg.Cues(0.9, math.nan, 0.0, 3.0, 0.5)) == pytest.approx(glare, abs=AGREEMENT)
