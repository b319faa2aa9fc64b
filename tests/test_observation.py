"""The plain input values: what makes a lead followable and a detector's box usable."""

from __future__ import annotations

import math

import pytest

import fearguard as fg


@pytest.mark.parametrize(("bearing", "range_m", "usable", "usable_range"), [
    (2.0, 3.5, True, 3.5), (2.0, None, True, None), (2.0, -1.0, True, None), (2.0, math.inf, True, None),
    (math.nan, 3.5, False, 3.5), (True, 3.5, False, 3.5),
])
def test_a_lead_is_followable_with_a_finite_bearing_and_its_range_is_optional(bearing, range_m, usable, usable_range) -> None:
    lead = fg.Lead(bearing, range_m)
    assert lead.usable is usable and lead.usable_range_m == usable_range


@pytest.mark.parametrize(("box", "usable"), [
    ((10, 20, 30, 40), True), ((10.5, 20.0, 30.0, 40.0), True), ((10, 20, 0, 40), False), ((10, 20, 30, -1), False),
    ((math.nan, 20, 30, 40), False), ((10, True, 30, 40), False), ((10, "20", 30, 40), False),
])
def test_a_box_is_usable_with_finite_numbers_and_a_positive_size(box, usable) -> None:
    assert fg.LeadBox(*box).usable is usable


def test_a_box_scales_to_another_resolution_and_rounds_outward_to_pixels() -> None:
    box = fg.LeadBox(10.0, 20.0, 30.2, 40.6).scaled(0.5)
    assert box == fg.LeadBox(5.0, 10.0, 15.1, 20.3)
    assert box.as_int() == (5, 10, 16, 21)


def test_an_observation_needs_only_its_time() -> None:
    obs = fg.Observation(t_s=1.0)
    assert (obs.speed_mps, obs.frame, obs.cues, obs.lead, obs.ultrasonic_echo_s) == (0.0, None, None, None, None)
