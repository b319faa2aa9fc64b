"""Road geometry: poses along straight and arc segments, and the projection back to (s, lateral)."""

from __future__ import annotations

import math

import numpy as np
import pytest
from hypothesis import given
from hypothesis import strategies as st

from fearguard.sim.road import Road
from fearguard.sim.scenario import Marking, RoadSpec, Segment


def road_of(*segments: Segment) -> Road:
    return Road(RoadSpec(0.5, 0.04, 0.3, 0.6, 0.06, 0, 0, Marking("solid", "white"), tuple(segments)))


@pytest.mark.parametrize("turn", ["left", "right"])
@pytest.mark.parametrize(("length", "radius"), [(3.0, 2.0), (10.0, 25.0), (math.pi * 5 / 2, 5.0)])
def test_arc_heading_change_is_length_over_radius(turn: str, length: float, radius: float) -> None:
    road = road_of(Segment("straight", 2.0), Segment("arc", length, radius, turn), Segment("straight", 1.0))
    sign = 1.0 if turn == "left" else -1.0
    h0, h1 = road.heading_at(np.array([2.0, 2.0 + length]))
    assert h1 - h0 == pytest.approx(sign * length / radius)
    assert road.heading_at(2.0 + length + 0.5) == pytest.approx(sign * length / radius)  # straight after the arc


def test_quarter_circle_ends_where_geometry_says() -> None:
    road = road_of(Segment("straight", 10.0), Segment("arc", math.pi * 5 / 2, 5.0, "left"))
    x, y, h = road.pose_at(10.0 + math.pi * 5 / 2)
    assert (float(x), float(y), float(h)) == pytest.approx((15.0, 5.0, math.pi / 2))
    x, y = road.point_at(10.0, 1.0)  # 1 m to the left of the start of the arc
    assert (float(x), float(y)) == pytest.approx((10.0, 1.0))
    assert road.length_m == pytest.approx(10.0 + math.pi * 5 / 2)


def test_road_continues_straight_before_the_start_and_after_the_end() -> None:
    road = road_of(Segment("arc", math.pi, 2.0, "right"))
    x, y, h = road.pose_at(-3.0)
    assert (float(x), float(y), float(h)) == pytest.approx((-3.0, 0.0, 0.0))
    x_end, y_end, h_end = road.end_pose
    x, y, h = road.pose_at(road.length_m + 2.0)
    assert (float(x), float(y)) == pytest.approx((x_end + 2.0 * math.cos(h_end), y_end + 2.0 * math.sin(h_end)))
    s, lat = road.project(np.array([-3.0, float(x)]), np.array([0.5, float(y)]))
    assert s == pytest.approx([-3.0, road.length_m + 2.0]) and lat == pytest.approx([0.5, 0.0], abs=1e-9)


def test_segment_index_and_lookup() -> None:
    road = road_of(Segment("straight", 2.0), Segment("arc", 3.0, 4.0, "left"), Segment("straight", 1.0))
    assert road.segment_index(np.array([-1.0, 0.0, 1.99, 2.0, 4.99, 5.0, 9.0])).tolist() == [0, 0, 0, 1, 1, 2, 2]
    assert road.segment_at(3.0).kind == "arc"


segments = st.lists(
    st.one_of(
        st.builds(lambda length: Segment("straight", length), st.floats(0.5, 20.0)),
        st.builds(lambda radius, angle, turn: Segment("arc", radius * angle, radius, turn),
                  st.floats(1.0, 30.0), st.floats(0.05, math.pi / 2), st.sampled_from(["left", "right"])),
    ),
    min_size=1, max_size=3,
).filter(lambda segs: sum(s.length_m / s.radius_m for s in segs) <= math.pi)  # never turns back onto itself


@given(segments, st.floats(0.0, 1.0), st.floats(-0.3, 0.3))
def test_pose_projection_round_trip(segs: list[Segment], where: float, lat_share: float) -> None:
    road = road_of(*segs)
    radius = min([s.radius_m for s in segs if s.kind == "arc"] + [10.0])
    s = where * road.length_m
    lateral = lat_share * radius
    x, y = road.point_at(s, lateral)
    s_back, lat_back = road.project(x, y)
    assert float(s_back) == pytest.approx(s, abs=1e-6)
    assert float(lat_back) == pytest.approx(lateral, abs=1e-6)


@given(segments, st.floats(0.0, 1.0))
def test_route_is_continuous_and_unit_speed(segs: list[Segment], where: float) -> None:
    road = road_of(*segs)
    s = where * road.length_m
    ds = 1e-4
    x, y, _ = road.pose_at(np.array([s, s + ds]))
    assert math.hypot(float(x[1] - x[0]), float(y[1] - y[0])) == pytest.approx(ds, rel=1e-3)
