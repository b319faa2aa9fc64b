"""Scenario files written from TOML snippets for simulator tests."""

from __future__ import annotations

import textwrap
from pathlib import Path

from fearguard.sim.scenario import Scenario, load_scenario


def scenario_from(tmp_path: Path, head: str, road: str, body: str, name: str = "s.toml") -> Scenario:
    """Load a scenario made of a head snippet, a road section and a body snippet (each dedented)."""
    path = tmp_path / name
    path.write_text(textwrap.dedent(head) + road + textwrap.dedent(body))
    return load_scenario(path)
