"""docs/architecture.md's layer table, executable: a module imports only from its own floor or below (every import
counts: module level, inside functions, under TYPE_CHECKING), plus the rules the page states by name."""

from __future__ import annotations

import re
from pathlib import Path

import pytest
from tests.architecture.test_import_graph import ROOT, import_graph

DOC = Path(__file__).resolve().parents[2] / "docs" / "architecture.md"

# floor → the package's modules on it (prefixes end with "."); from the bottom up, as docs/architecture.md draws them
FLOORS: tuple[tuple[str, tuple[str, ...]], ...] = (
    ("plain values", ("fearguard.errors", "fearguard.readings", "fearguard.cues", "fearguard.fear", "fearguard.observation",
                      "fearguard.lane", "fearguard.camera", "fearguard.vehicle", "fearguard.files.")),
    ("measurement", ("fearguard.vision.", "fearguard.sensors.", "fearguard.track", "fearguard.track.features",
                     "fearguard.track.floor", "fearguard.track.light", "fearguard.track.profile", "fearguard.track.reading")),
    ("perception", ("fearguard.perception",)),
    ("fear and policy", ("fearguard.fuzzy.", "fearguard.policy.", "fearguard.policy")),
    ("supervisor", ("fearguard.supervisor", "fearguard.steering_deadline")),
    ("drivers and outputs", ("fearguard.drive.", "fearguard.outputs.", "fearguard.sim.", "fearguard.replay.", "fearguard.worlds.",
                             "fearguard.integrations.", "fearguard.testing.", "fearguard.cli", "fearguard.demo", "fearguard",
                             "fearguard.track.learn", "fearguard.track.picture")),
)


def floor_of(module: str) -> int:
    """The floor a module stands on (a package's __init__ stands with its modules)."""
    for level, (_, members) in enumerate(FLOORS):
        for m in members:
            if module == m or (m.endswith(".") and module.startswith(m)) or module + "." == m:
                return level
    raise AssertionError(f"{module} is on no floor of docs/architecture.md's table: add it there and here")


def _edges() -> list[tuple[str, str]]:
    graph, _ = import_graph()
    return list(graph.edges())


def test_every_module_is_on_a_floor() -> None:
    graph, _ = import_graph()
    for module in graph.nodes:
        floor_of(module)


def test_no_module_imports_from_a_floor_above_its_own() -> None:
    up = [(a, b) for a, b in _edges() if floor_of(b) > floor_of(a)]
    assert not up, "imports from above: " + "; ".join(f"{a} ({FLOORS[floor_of(a)][0]}) → {b} ({FLOORS[floor_of(b)][0]})" for a, b in up)


@pytest.mark.parametrize(("source", "forbidden", "rule"), [
    ("fearguard.vision.", ("fearguard.policy", "fearguard.supervisor", "fearguard.perception"), "vision imports no policy or supervisor"),
    ("fearguard.sensors.", ("fearguard.policy", "fearguard.supervisor", "fearguard.perception"), "sensors import no policy or supervisor"),
    ("fearguard.supervisor", ("fearguard.vision",), "the supervisor imports no vision (perception measures the lane)"),
    ("fearguard.policy", ("fearguard.files", "fearguard.vision", "fearguard.perception"), "policy reads no files and sees no pixels"),
])
def test_the_rules_the_page_states_by_name(source: str, forbidden: tuple[str, ...], rule: str) -> None:
    bad = [(a, b) for a, b in _edges() if a.startswith(source) and any(b == f or b.startswith(f + ".") for f in forbidden)]
    assert not bad, f"{rule}: " + "; ".join(f"{a} → {b}" for a, b in bad)


def test_the_page_names_every_module_and_error_class() -> None:
    """docs/architecture.md names every module of the package (its path) and every exception class errors.py defines."""
    text = DOC.read_text(encoding="utf-8")
    missing = []
    for path in sorted(ROOT.rglob("*.py")):
        rel = path.relative_to(ROOT).as_posix()
        if path.name == "__init__.py" or rel.startswith(("rules/", "scenarios/")):
            continue
        if rel not in text and path.name not in text:
            missing.append(rel)
    assert not missing, f"docs/architecture.md does not name: {', '.join(missing)}"
    errors = (ROOT / "errors.py").read_text(encoding="utf-8")
    classes = set(re.findall(r"^class (\w+)\(", errors, flags=re.M))
    named = {c for c in classes if c in text}
    assert classes and named == classes, f"docs/architecture.md misses the error classes {sorted(classes - named)}"
