"""Issue 35 item 3: a moving object ahead is followed at its speed with the rules' time gap (``decision.follow_step``)."""

from __future__ import annotations

import math

from hypothesis import given
from hypothesis import strategies as st

import fearguard as fg
from fearguard.policy.decision import follow_step
from fearguard.testing.subject import distinct_presets

RULES = {"default": fg.load_rules(), "road_car": fg.load_rules("rules/road_car.toml"), "duckiebot": fg.load_rules("rules/duckiebot.toml")}
CARS = {name: (car, (RULES["road_car"] if car.max_speed_mps > 10 else RULES["duckiebot"] if car.max_speed_mps <= 0.5
                     else RULES["default"]).policy) for name, car in distinct_presets().items()}
scale = st.floats(0.0, 1.0)


@given(name=st.sampled_from(sorted(CARS)), d=scale, d2=scale, v=scale, lead=scale)
def test_the_cap_settles_at_the_leads_speed_at_the_time_gap_and_falls_with_the_range(
    name: str, d: float, d2: float, v: float, lead: float,
) -> None:
    car, cfg = CARS[name]
    v_mps, lead_mps = v * car.max_speed_mps, lead * car.max_speed_mps
    far = car.stop_margin_m + cfg.follow_time_gap_s * car.max_speed_mps * 3
    near_m, far_m = sorted((d * far, d2 * far))
    closing = v_mps - lead_mps
    cap_near, _ = follow_step(near_m, v_mps, closing, cfg, car)
    cap_far, _ = follow_step(far_m, v_mps, closing, cfg, car)
    if lead_mps <= cfg.moving_object_min_mps:  # it stands: the envelope and fear answer, not the follower
        assert math.isinf(cap_near) and math.isinf(cap_far)
        return
    assert cap_near <= cap_far  # nearer never allows more
    wanted = car.stop_margin_m + cfg.follow_time_gap_s * lead_mps
    at_gap, _ = follow_step(wanted, v_mps, closing, cfg, car)
    assert math.isclose(at_gap, lead_mps, rel_tol=1e-9)
    if near_m < wanted:
        assert cap_near <= lead_mps  # inside the gap: no faster than the lead, until the gap is back


@given(d=st.floats(0.0, 500.0), v=st.floats(0.0, 40.0))
def test_unknown_motion_or_nothing_ahead_gives_no_follow_cap(d: float, v: float) -> None:
    car, cfg = CARS["road_car"] if "road_car" in CARS else next(iter(CARS.values()))
    assert follow_step(d, None, 1.0, cfg, car) == (math.inf, "")
    assert follow_step(d, v, None, cfg, car) == (math.inf, "")
    assert follow_step(d, v, math.nan, cfg, car) == (math.inf, "")
    assert follow_step(math.inf, v, 0.0, cfg, car) == (math.inf, "")
