"""The safety invariants of docs/architecture.md, numbered as there, for every bundled rule file × every vehicle preset.

One source of truth: the strategies and the checkers are ``fearguard.testing``'s, the same a user runs
for their own car (``supervisor_invariants``, ``fearguard verify``). The search is deterministic
(``random.Random(seed)``, no example database), so CI tries the same cases every run. The bundled
default rules on the default car get the most examples; every other pair a modest number.
"""

from __future__ import annotations

import math
from pathlib import Path

import pytest

import fearguard as fg
from fearguard.testing import INVARIANTS, Invariant, Subject, find_counterexample
from fearguard.testing.history import Step
from fearguard.testing.subject import distinct_presets, run

ROOT = Path(__file__).resolve().parents[1]
RULE_FILES = sorted((ROOT / "rules").glob("*.toml"))
PRESETS = distinct_presets()
MAIN_EXAMPLES = 60  # [cases] per invariant for the default rules on the default car
MATRIX_EXAMPLES = 4  # [cases] per invariant for every other rule file × preset pair (3 rule files × 6 presets)
HEAVY = {"recovery_is_live": 2, "refilled_buffer": 2, "repeated_frames": 2}  # [cases] long or frame-level histories
SEED = 20261201


def _subject(rules_file: Path, preset: str) -> Subject:
    return Subject.of(rules_file, PRESETS[preset])


_SUBJECTS: dict[tuple[str, str], Subject] = {}


def subject_for(rules_file: Path, preset: str) -> Subject:
    key = (str(rules_file), preset)
    if key not in _SUBJECTS:
        _SUBJECTS[key] = _subject(rules_file, preset)
    return _SUBJECTS[key]


def assert_holds(inv: Invariant, subject: Subject, examples: int) -> None:
    outcome = find_counterexample(inv, subject, examples, SEED)
    assert outcome.counterexample is None, outcome.counterexample.text()


MATRIX = [(r, p) for r in RULE_FILES for p in PRESETS]


@pytest.mark.parametrize("inv", INVARIANTS, ids=[f"{i.number}-{i.key}" for i in INVARIANTS])
@pytest.mark.parametrize(("rules_file", "preset"), MATRIX, ids=[f"{r.stem}-{p}" for r, p in MATRIX])
def test_invariant_holds(inv: Invariant, rules_file: Path, preset: str) -> None:
    main = rules_file.name == "default.toml" and preset == "default"
    assert_holds(inv, subject_for(rules_file, preset), MAIN_EXAMPLES if main else HEAVY.get(inv.key, MATRIX_EXAMPLES))


@pytest.mark.parametrize("key", ["limits_in_range", "pass_through", "deterministic", "watchdog"])
def test_invariants_hold_around_the_hough_lane_steering(key: str) -> None:
    # a real, stateful steering function looking at rendered and synthetic frames (reset between runs)
    subject = Subject.of(None, None, fg.HoughLaneSteering())
    assert_holds(next(i for i in INVARIANTS if i.key == key), subject, 8)


def test_4_unknown_brightness_picks_the_worse_extreme(write_rules) -> None:
    # a variant where glare is worse than darkness, so "unknown brightness" must pick the right extreme
    path = write_rules(('"IF brightness IS dark OR brightness IS glare THEN fear IS very_high"',
                        '"IF brightness IS dark THEN fear IS medium", "IF brightness IS glare THEN fear IS very_high"'))
    subject = Subject.of(path)
    assert_holds(next(i for i in INVARIANTS if i.key == "unknown_is_worst"), subject, 40)
    rb = subject.rules
    assert rb.evaluate(fg.Cues(0.9, math.nan, 0.0, math.inf, 0.5)).fear == rb.evaluate(fg.Cues(0.9, 255.0, 0.0, math.inf, 0.5)).fear


def test_4_no_rule_firing_gives_fear_1_plain(write_rules) -> None:
    rb = fg.load_rules(write_rules(('  "IF qr_staleness_s IS stale THEN fear IS high",\n', "")))
    res = rb.evaluate(fg.Cues(0.9, 120.0, 0.0, 3.0, 20.0))  # only 'stale' is non-zero here: no rule fires
    assert res.fear == 1.0 and res.group_fears["localisation"] == 1.0 and res.level is fg.FearLevel.VERY_HIGH
    assert rb.reference_fear(fg.Cues(0.9, 120.0, 0.0, 3.0, 20.0)) == 1.0


@pytest.mark.parametrize("range_m", [0.05, 0.2, 0.4, 0.6])
def test_5_imminent_collision_enters_at_once(range_m: float) -> None:
    car = fg.VehicleLimits.preset("model_car")  # a car with a range sensor (the default has none)
    cmd = run(Subject.of(None, car), (Step(t_s=0.0, speed_mps=2.0, cues=fg.Cues(0.9, 120.0, 0.0, range_m, 0.5)),)).commands[0]
    if fg.policy.imminent_collision(range_m, 2.0, car):
        assert cmd.mode is fg.Mode.EMERGENCY and cmd.strategy is fg.Strategy.STOP and cmd.speed_limit_mps == 0.0


def test_7_calm_frames_do_reach_normal_very_low() -> None:
    steps = tuple(Step(t_s=0.1 * k, speed_mps=1.0, cues=fg.Cues(0.9, 120.0, 0.0, math.inf, 0.5), steer_output=7.25) for k in range(5))
    cmds = run(Subject.of(), steps).commands
    assert all(c.mode is fg.Mode.NORMAL and c.fear_level is fg.FearLevel.VERY_LOW and c.steering_deg == 7.25 for c in cmds)
