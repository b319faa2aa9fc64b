"""Runs as data: a plan is a list of rows, ``run_row`` runs one, the suite puts the rows in a table.

A ``RunSpec`` names one run completely — the world, the run in it (a scenario file, a map's drive), the controller,
the seed and the world's own options — and is a plain, JSON-able value, so a plan can be written down, resumed, or
shipped to another process (the cluster issue puts an executor behind ``run_row``). ``run_row(spec)`` is deterministic
apart from its timing fields: the same spec gives the same row on any machine. Each world registers the function that
runs one of its rows (``ROW_RUNNERS``: world → "module:function", imported when first used, so a plan for one world
never imports another's simulator).
"""

from __future__ import annotations

import importlib
from collections.abc import Callable, Mapping
from dataclasses import dataclass, field
from typing import Any

from fearguard.drive.interrupt import StopSignal

ROW_RUNNERS: dict[str, str] = {  # world → the function that runs one of its rows: RunSpec → row (a JSON-able dict)
    "sim": "fearguard.sim.suite:run_row",
    "duckietown": "fearguard.worlds.duckietown.suite:run_row",
    "replay": "fearguard.replay.fleet:run_row",  # a recording of a fleet replayed into its folder
    "metadrive": "fearguard.worlds.metadrive.suite:run_row",
}


@dataclass(frozen=True)
class RunSpec:
    """One run of a plan: which world, which run in it, which controller and seed, and the world's options."""

    world: str  # a key of ROW_RUNNERS
    name: str  # the run in its world: a scenario file, a suite's run name
    controller: str
    seed: int
    options: Mapping[str, Any] = field(default_factory=dict)  # the world's own knobs (JSON values)

    @property
    def key(self) -> tuple[str, str, str, int]:
        """The run's identity (resume: a row with this key is already done). A plan names each run uniquely in its world
        (a sweep puts its combination into the name), so the options are not part of it."""
        return (self.world, self.name, self.controller, self.seed)

    def to_json(self) -> dict[str, Any]:
        return {"world": self.world, "name": self.name, "controller": self.controller, "seed": self.seed,
                "options": dict(self.options)}

    @classmethod
    def from_json(cls, data: Mapping[str, Any]) -> RunSpec:
        return cls(str(data["world"]), str(data["name"]), str(data["controller"]), int(data["seed"]), dict(data.get("options") or {}))


def runner(world: str) -> Callable[[RunSpec, StopSignal | None], dict[str, Any]]:
    """The function that runs one row of ``world`` (a ValueError naming the known worlds otherwise)."""
    if world not in ROW_RUNNERS:
        raise ValueError(f"unknown world {world!r}; known: {', '.join(ROW_RUNNERS)}")
    module, _, function = ROW_RUNNERS[world].partition(":")
    return getattr(importlib.import_module(module), function)  # type: ignore[no-any-return]


def run_row(spec: RunSpec, stop: StopSignal | None = None) -> dict[str, Any]:
    """Run one row of a plan: its spec (``"spec"``) and the world's row fields (``"interrupted": true`` when ``stop``
    cut it short: not a result). A top-level function: a worker process (or a cluster) can run it."""
    row = runner(spec.world)(spec, stop)
    return {"spec": spec.to_json(), **row}


def row_key(row: Mapping[str, Any]) -> tuple[str, str, str, int] | None:
    """The key of the run a row holds: from its spec, or — a row of a suite written before plans — the simulator's
    scenario, controller and seed. None: not a row of a run."""
    data = row.get("spec")
    try:
        if isinstance(data, Mapping):
            return RunSpec.from_json(data).key
        if {"scenario", "seed", "controller", "passed"} <= row.keys():
            return ("sim", str(row["scenario"]), str(row["controller"]), int(row["seed"]))
    except (KeyError, TypeError, ValueError):
        return None
    return None
