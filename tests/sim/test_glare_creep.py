"""Issue 35, a glare zone with the path known clear: the re-acquisition creep steers by the line the glare leaves readable
and goes on through it, then stops for what stands beyond; a box inside the glare still stops it.

Not the bundled ``glare_zone_clear`` picture: a right-hand arc and a left one, other box colours, other lengths and seeds.
"""

from __future__ import annotations

import textwrap
from pathlib import Path

import pytest

from fearguard.sim.loop import run_scenario
from fearguard.sim.scenario import load_scenario

ARC = """
name = "glare_arc"
scale = "model"
seed = {seed}
duration_s = 55.0
[road]
right_marking = "{right}"
[[road.segments]]
kind = "straight"
length_m = 6.0
[[road.segments]]
kind = "arc"
length_m = 10.0
radius_m = {radius}
turn = "{turn}"
[[road.segments]]
kind = "straight"
length_m = 14.0
[[lighting]]
kind = "glare"
from_m = 6.0
to_m = {glare_to}
strength = 0.9
[[obstacles]]
s_m = {box_m}
lateral_m = 0.0
colour = "{colour}"
"""


def scenario(tmp_path: Path, **kw: object):
    path = tmp_path / "glare.toml"
    path.write_text(textwrap.dedent(ARC.format(**kw)))
    return load_scenario(path)


@pytest.mark.slow
@pytest.mark.parametrize(("seed", "turn", "radius", "right", "colour"),
                         [(0, "right", 9.0, "dashed", "blue"), (4, "left", 12.0, "solid", "white")])
def test_the_car_creeps_through_glare_on_an_arc_and_stops_for_the_box_beyond(tmp_path: Path, seed: int, turn: str, radius: float,
                                                                          right: str, colour: str) -> None:
    result = run_scenario(scenario(tmp_path, seed=seed, turn=turn, radius=radius, right=right, glare_to=13.0, box_m=24.0,
                                   colour=colour))
    m = result.metrics
    assert m.collisions == 0 and m.lane_departures == 0
    assert m.distance_m >= 20.0, m  # through the glare (6–13 m) and on toward the box
    assert m.final_speed_mps is not None and m.final_speed_mps < 0.05 and m.final_gap_m is not None and m.final_gap_m > 0.0


@pytest.mark.slow
def test_a_box_inside_the_glare_still_stops_the_creep(tmp_path: Path) -> None:
    result = run_scenario(scenario(tmp_path, seed=2, turn="right", radius=15.0, right="dashed", glare_to=16.0, box_m=10.0,
                                   colour="orange"))
    m = result.metrics
    assert m.collisions == 0 and m.lane_departures == 0
    assert m.distance_m < 10.0 and m.min_gap_m is not None and m.min_gap_m > 0.1
