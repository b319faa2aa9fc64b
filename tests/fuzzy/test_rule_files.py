"""Rule files: the shipped ones load; every kind of mistake fails with RuleError naming file, line/key."""

from __future__ import annotations

import dataclasses
import re
import subprocess
import sys
from pathlib import Path

import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from tests.conftest import RULES_DIR

import fearguard as fg
from fearguard.cues import calm_values
from fearguard.fuzzy.loader import bundled_rules_path
from fearguard.fuzzy.rule_text import RuleSyntaxError, parse_rule


def test_bundled_rules_are_package_data_and_match_repo_copies() -> None:
    for name in ("default.toml", "road_car.toml"):
        assert bundled_rules_path(name).read_text() == (RULES_DIR / name).read_text()
    assert fg.load_rules().name == "model car 1:10"


def test_every_shipped_rule_file_loads() -> None:
    for path in sorted(RULES_DIR.glob("*.toml")):
        rb = fg.load_rules(path)
        assert len(rb.rules) >= 10 and rb.groups


def test_load_rules_works_from_another_directory(tmp_path: Path) -> None:
    out = subprocess.run([sys.executable, "-c", "import fearguard; print(fearguard.load_rules().name)"],
                         cwd=tmp_path, capture_output=True, text=True, check=True)
    assert out.stdout.strip() == "model car 1:10"


BAD_FILES = [
    # (replacement, what the message must contain, the key or line it must name)
    (("occlusion IS heavy AND lane_confidence IS low THEN", "occlusion IS hevy AND lane_confidence IS low THEN"),
     "unknown term 'hevy' of occlusion", r"line \d+, key groups\.road_lost\.rules\[0\]"),
    (('"IF lane_confidence IS high THEN fear IS very_low"', '"IF lane_confidance IS high THEN fear IS very_low"'),
     "unknown variable 'lane_confidance'", r"line \d+, key groups\.lane\.rules\[0\]"),
    (('"IF lane_confidence IS high THEN fear IS very_low"', '"IF lane_confidence IS high fear IS very_low"'),
     "malformed rule: expected THEN", r"groups\.lane\.rules\[0\]"),
    (('"IF lane_confidence IS high THEN fear IS very_low"', '"IF lane_confidence IS high THEN fear IS scary"'),
     "unknown fear level 'scary'", r"groups\.lane"),
    (('"IF lane_confidence IS high THEN fear IS very_low"', '"IF lane_confidence IS high THEN fear IS very_low WITH 2"'),
     "WITH needs a number between 0 and 1", r"groups\.lane"),
    (("high = { trapmf = [0.5, 0.75, 1.0, 1.0] }", "high = { trapmf = [1.5, 1.75, 2.0, 2.0] }"),
     "the universe does not contain the term", r"line 15, key variables\.lane_confidence\.high"),
    (("high = { trapmf = [0.5, 0.75, 1.0, 1.0] }", "high = { trapmf = [0.75, 0.5, 1.0, 1.0] }"),
     "a <= b <= c <= d", r"variables\.lane_confidence\.high"),
    (("high = { trapmf = [0.5, 0.75, 1.0, 1.0] }", "high = { wobblemf = [0.5] }"),
     "unknown membership shape 'wobblemf'", r"variables\.lane_confidence\.high"),
    (("high = { trapmf = [0.5, 0.75, 1.0, 1.0] }", "high = [0.5, 0.75, 1.0, 1.0]"),
     "must be written like", r"variables\.lane_confidence\.high"),
    (("[variables.lane_confidence]", "[variables.lane_quality]"), "unknown variable 'lane_quality'", r"variables\.lane_quality"),
    (("universe = [0.0, 1.0, 0.001]\nlow", "universe = [0.0, 1.0]\nlow"), "universe = [start, stop, step]", r"universe"),
    (("universe = [0.0, 1.0, 0.001]\nlow", "universe = [0.0, 1.0, 0.3]\nlow"), "step must divide", r"universe"),
    (("universe = [0.0, 1.0, 0.001]\nlow", "universe = [0.2, 1.0, 0.001]\nlow"), "must cover the cue's range", r"universe"),
    (("normal_band = [80.0, 180.0]", "normal_band = [80.0, 300.0]"), "normal_band", r"variables\.brightness\.normal_band"),
    (("normal_band = [80.0, 180.0]", ""), "brightness needs normal_band", r"normal_band"),
    (("very_high = { trimf = [0.75, 1.0, 1.0] }", "extreme = { trimf = [0.75, 1.0, 1.0] }"), "fear terms must be exactly", r"key fear"),
    (('cause = "collision"', 'cause = "bumps"'), "must be one of 'collision'", r"groups\.collision\.cause"),
    (('cause = "collision"', 'cause = "collision"\npriority = 3'), "unknown key 'priority'", r"groups\.collision\.priority"),
    (("hold_s = 2.0 ", "hold_secs = 2.0 "), "unknown key 'hold_secs' (did you mean 'hold_s'?)", r"line \d+, key policy\.hold_secs"),
    (("hold_s = 2.0 ", "hold_s = -1.0 "), "must be >= 0", r"policy\.hold_s"),
    (("enter_frames = 3 ", "enter_frames = 0 "), "whole number >= 1", r"policy\.enter_frames"),
    (("recovery_min_guide = 0.15 ", "recovery_min_guide = 1.5 "), "must be in [0, 1]", r"policy\.recovery_min_guide"),
    (("emergency_exit_fear = 0.5 ", "emergency_exit_fear = 0.8 "), "below emergency_enter_fear", r"policy\.emergency_exit_fear"),
    (("high = 0.4, very_high = 0.3", "high = 0.4, very_high = 0.5"), "must not increase with fear", r"policy\.speed_fraction"),
    (("high = 0.4, very_high = 0.3", "high = 0.4"), "needs exactly the levels", r"policy\.speed_fraction"),
    (("high = 0.4, very_high = 0.3 }", "high = 0.4, very_high = nan }"), "each fraction must be a number", r"policy\.speed_fraction"),
    (("speed_fraction = { very_low = 1.0, low = 0.8, medium = 0.6, high = 0.4, very_high = 0.3 }", "speed_fraction = [1.0, 0.5]"),
     "must be a table like", r"policy\.speed_fraction"),
    (("comfort_accel_mps2 = 0.5 ", 'comfort_accel_mps2 = "fast" '), "finite number", r"policy\.comfort_accel_mps2"),
    (('name = "model car 1:10"', 'name = "x"\ncolour = "red"'), "unknown key 'colour'", r"line 10, key colour"),
    (('name = "model car 1:10"', 'name = "x"\n[[oops'), "TOML syntax", r"line"),
]


@pytest.mark.parametrize(("replacement", "message", "where"), BAD_FILES, ids=[b[1][:30] for b in BAD_FILES])
def test_bad_rule_file_names_file_where_and_what(write_rules, replacement, message, where) -> None:
    path = write_rules(replacement)
    with pytest.raises(fg.RuleError) as err:
        fg.load_rules(path)
    text = str(err.value)
    assert text.startswith(str(path)), text
    assert message in text, text
    assert re.search(where, text), text


def test_missing_and_unreadable_files(tmp_path: Path) -> None:
    with pytest.raises(fg.RuleError, match="no such file"):
        fg.load_rules(tmp_path / "nope.toml")
    binary = tmp_path / "bin.toml"
    binary.write_bytes(b"\xff\xfe\x00garbage")
    with pytest.raises(fg.RuleError, match="UTF-8"):
        fg.load_rules(binary)


def test_missing_tables(tmp_path: Path) -> None:
    path = tmp_path / "empty.toml"
    path.write_text('name = "empty"\n')
    with pytest.raises(fg.RuleError, match="key variables: missing table"):
        fg.load_rules(path)


@pytest.mark.parametrize(
    ("text", "problem"),
    [
        ("IF a IS b", "ends too early"),
        ("IF (a IS b THEN fear IS low", "not closed"),
        ("IF a IS b THEN speed IS low", "concludes about 'fear'"),
        ("IF a IS b THEN fear IS low WITH lots", "needs a number"),
        ("IF a IS b THEN fear IS low extra", "unexpected 'extra'"),
        ("IF AND IS b THEN fear IS low", "expected a variable name"),
    ],
)
def test_rule_syntax_errors(text: str, problem: str) -> None:
    with pytest.raises(RuleSyntaxError, match=problem):
        parse_rule(text)


def test_rule_grammar_precedence_and_weights() -> None:
    from fearguard.fuzzy.rule_text import And, Is, Not, Or

    rule = parse_rule("if a is x or not b is y and c is not z then fear is high with 0.5")
    assert rule.level == "high" and rule.weight == 0.5
    assert rule.antecedent == Or((Is("a", "x"), And((Not(Is("b", "y")), Not(Is("c", "z"))))))


def _policy_table(doc: str) -> dict[str, tuple[str, str]]:
    """docs/rules.md's [policy] table: key → (default column, road_car column)."""
    rows = re.findall(r"^\| `(\w+)` \| [^|]* \| ([^|]*) \| ([^|]*) \|", doc, flags=re.M)
    return {key: (default.strip(), road.strip()) for key, default, road in rows}


def _as_text(value: object) -> str:
    return ", ".join(map(str, value)) if isinstance(value, tuple) else str(value)


def test_the_policy_table_of_the_docs_is_what_the_files_load() -> None:
    from dataclasses import fields

    from fearguard.policy import PolicyConfig

    table = _policy_table((RULES_DIR.parent / "docs" / "rules.md").read_text())
    road = fg.load_rules(RULES_DIR / "road_car.toml").policy
    for f in fields(PolicyConfig):
        assert f.name in table, f"docs/rules.md does not describe [policy] {f.name}"
        assert table[f.name] == (_as_text(getattr(PolicyConfig(), f.name)), _as_text(getattr(road, f.name))), f.name


def test_the_default_file_spells_out_every_policy_number() -> None:
    from fearguard.policy import PolicyConfig

    text = (RULES_DIR / "default.toml").read_text()
    assert fg.load_rules(RULES_DIR / "default.toml").policy == PolicyConfig()  # the file says what the code defaults to
    for key in PolicyConfig.__dataclass_fields__:
        assert re.search(rf"^{key} = ", text, flags=re.M), f"default.toml [policy] does not show {key}"


@given(occlusion=st.floats(0.3, 1.0))
@settings(max_examples=60, deadline=None)
def test_a_third_of_the_markings_hidden_raises_fear_by_a_fifth_on_every_shipped_file(occlusion: float) -> None:
    """Issue 33's occluder bar, as a property of the rule files: with the other cues calm, occlusion ≥ 0.3 (a box over a
    line, an object in the lane) gives fear at least 0.2 above calm — no plateau at LOW between partial and heavy."""
    for path in sorted(RULES_DIR.glob("*.toml")):
        rb = fg.load_rules(path)
        calm = fg.Cues(*calm_values(rb.brightness_band))
        hidden = rb.evaluate(dataclasses.replace(calm, occlusion=occlusion)).fear
        assert hidden >= rb.evaluate(calm).fear + 0.2, (path.name, occlusion)
