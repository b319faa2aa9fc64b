"""Sparse dashed markings on both sides (worn paint): the lane is still a lane. A dash between two others is no weaker
evidence of the line than they were (the track holds its support, vision/lane_tracker.py), so the picture does not
flicker between trusted and lost as the dashes pass, and the car keeps driving.

Not the bundled scenario's picture (``scenarios/sparse_dashes``): other dash lengths and gaps, yellow
paint, pale concrete, turns both ways and other seeds.
"""

from __future__ import annotations

import textwrap
from pathlib import Path

import pytest

from fearguard.sim.loop import run_scenario
from fearguard.sim.scenario import load_scenario

DASHED = """
name = "dashed_{turn}"
scale = "model"
seed = {seed}
duration_s = 12.0
[road]
left_marking = "dashed"
right_marking = "dashed"
left_colour = "{colour}"
dash_length_m = {dash}
dash_gap_m = {gap}
surface = "{surface}"
[[road.segments]]
kind = "straight"
length_m = 7.0
[[road.segments]]
kind = "arc"
length_m = 6.0
radius_m = 12.0
turn = "{turn}"
[[road.segments]]
kind = "straight"
length_m = 10.0
"""


@pytest.mark.slow
@pytest.mark.parametrize(("seed", "dash", "gap", "colour", "surface", "turn"), [
    (3, 0.2, 0.5, "white", "asphalt", "right"),
    (8, 0.12, 0.45, "yellow", "asphalt", "left"),
    (12, 0.2, 0.5, "white", "pale", "left"),
])
def test_sparse_dashes_keep_the_car_driving_without_an_emergency(tmp_path: Path, seed: int, dash: float, gap: float, colour: str,
                                                                 surface: str, turn: str) -> None:
    path = tmp_path / "dashed.toml"
    path.write_text(textwrap.dedent(DASHED.format(seed=seed, dash=dash, gap=gap, colour=colour, surface=surface, turn=turn)))
    m = run_scenario(load_scenario(path)).metrics
    assert m.collisions == 0
    assert m.lane_departures == 0
    assert m.emergency_entries == 0, "a dashed lane read as lost"
    assert m.distance_m >= 12.0
