"""Following the route where the markings end (policy.route): a car with a map crosses a junction in CAUTION on its
route instead of stopping in its mouth — only with the path known clear, never faster than the doubt speed or than it
can stop within the clear path, for at most ``route_blind_m`` per loss; a trusted picture never reads the route."""

from __future__ import annotations

import dataclasses
import math

import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

import fearguard as fg
from fearguard.fuzzy.loader import bundled_rules_path
from fearguard.lane import GroundLine, LaneGeometry
from fearguard.policy import PolicyConfig, envelope_speed_mps
from fearguard.policy.lane_check import lane_check
from fearguard.policy.route import next_route

ROAD = fg.load_rules(bundled_rules_path("road_car.toml"))
CAR = fg.VehicleLimits.preset("road_car")  # a 0.3-80 m radar: nothing in range is a path known clear to 80 m
CALM = fg.Cues(0.95, 120.0, 0.0, math.inf, 0.5)
LOST = fg.Cues(0.0, 120.0, 0.0, math.inf, 0.5)  # nothing of the lane seen, the radar clear
DT = 0.1


def _drive(route: object, cues_lost: fg.Cues, speed_mps: float, lost_s: float, rules: fg.RuleBase = ROAD,
           car: fg.VehicleLimits = CAR) -> list[fg.Command]:
    """2 s of a trusted picture at ``speed_mps``, then ``lost_s`` of ``cues_lost``; the route steering given throughout."""
    guard = fg.FearGuard(lambda frame: 0.0, rules=rules, vehicle=car)
    cmds, t = [], 0.0
    for i in range(round((2.0 + lost_s) / DT)):
        cues = CALM if i * DT < 2.0 - 1e-9 else cues_lost
        cmds.append(guard.step(fg.Observation(t_s=round(t, 6), speed_mps=speed_mps, cues=cues, route_steering_deg=route)))
        t += DT
    return cmds


@settings(max_examples=40, deadline=None)
@given(speed=st.floats(2.0, 12.0), route=st.floats(-40.0, 40.0))
def test_a_lost_picture_on_a_route_with_the_path_clear_is_crossed_in_caution_for_route_blind_m(speed: float, route: float) -> None:
    cfg = ROAD.policy
    lost_s = cfg.route_blind_m / speed + 2.0  # the budget runs out within the drive
    cmds = _drive(route, LOST, speed, lost_s)
    lost = cmds[round(2.0 / DT):]
    budget_frames = math.floor(cfg.route_blind_m / (speed * DT))  # frames driven before the budget is spent
    doubt = cfg.road_doubt_fraction * CAR.max_speed_mps
    for c in lost[:budget_frames]:
        assert c.mode is not fg.Mode.EMERGENCY, c.reasons
        assert c.speed_limit_mps <= doubt + 1e-9
        assert c.speed_limit_mps <= envelope_speed_mps(CAR.ultrasonic_max_range_m, CAR) + 1e-9
    following = [c for c in lost[:budget_frames] if any("following the route" in r for r in c.reasons)]
    assert len(following) >= budget_frames - 1
    wanted = max(-CAR.max_steering_deg, min(CAR.max_steering_deg, route))
    settle = math.ceil(abs(wanted) / (CAR.max_steering_rate_dps * DT)) + 1  # the rate limit's frames to get there
    assert all(c.steering_deg == pytest.approx(wanted) for c in lost[settle:budget_frames])
    assert lost[-1].mode is fg.Mode.EMERGENCY, "past route_blind_m the emergency machinery takes over"
    assert any("no longer" in r for c in lost[budget_frames:] for r in c.reasons)


def test_without_a_route_the_same_loss_is_an_emergency_after_the_grace() -> None:
    cmds = _drive(None, LOST, 8.0, 3.0)
    assert cmds[-1].mode is fg.Mode.EMERGENCY
    assert not any("route" in r for c in cmds for r in c.reasons)


def test_an_object_nearer_than_a_creep_needs_is_no_clear_path_and_the_route_is_not_followed() -> None:
    near = dataclasses.replace(LOST, obstacle_range_m=3.0)
    cmds = _drive(10.0, near, 5.0, 3.0)
    assert not any("following the route" in r for c in cmds for r in c.reasons)
    assert cmds[-1].mode is fg.Mode.EMERGENCY and cmds[-1].speed_limit_mps == 0.0


@pytest.mark.parametrize("range_m", [6.0, 12.0, 25.0])
def test_the_route_is_followed_no_faster_than_the_car_stops_within_the_clear_path(range_m: float) -> None:
    ahead = dataclasses.replace(LOST, obstacle_range_m=range_m)
    for c in _drive(0.0, ahead, 4.0, 3.0)[round(2.0 / DT):]:
        if any("following the route" in r for r in c.reasons):
            assert c.speed_limit_mps <= envelope_speed_mps(range_m, CAR) + 1e-9


@settings(max_examples=40, deadline=None)
@given(route=st.one_of(st.floats(allow_nan=True, allow_infinity=True), st.just("left"), st.just(None)), speed=st.floats(0.0, 20.0))
def test_a_trusted_picture_never_reads_the_route(route: object, speed: float) -> None:
    guard_on, guard_off = (fg.FearGuard(lambda frame: 3.0, rules=ROAD, vehicle=CAR) for _ in range(2))
    for i in range(30):
        obs = fg.Observation(t_s=i * DT, speed_mps=speed, cues=CALM)
        with_route = guard_on.step(dataclasses.replace(obs, route_steering_deg=route))
        without = guard_off.step(obs)
        assert dataclasses.replace(with_route, reasons=()) == dataclasses.replace(without, reasons=())


@pytest.mark.parametrize("route", [math.nan, math.inf, -math.inf, "left", [1.0]])
def test_a_route_that_is_no_number_is_said_once_and_no_route_is_followed(route: object) -> None:
    cmds = _drive(route, LOST, 8.0, 3.0)
    notes = [r for c in cmds for r in c.reasons if "route_steering_deg" in r]
    assert len(notes) == 1 and "no route followed" in notes[0]
    assert cmds[-1].mode is fg.Mode.EMERGENCY


@pytest.mark.parametrize("rules_file", ["default.toml", "duckiebot.toml"])
def test_a_rule_file_with_route_blind_m_zero_never_follows_a_route(rules_file: str) -> None:
    rules = fg.load_rules(bundled_rules_path(rules_file))
    rules = dataclasses.replace(rules, policy=dataclasses.replace(rules.policy, route_blind_m=0.0))
    car = fg.VehicleLimits.preset("duckiebot" if rules_file == "duckiebot.toml" else "donkey")
    speed = 0.5 * car.max_speed_mps
    with_route, without = _drive(5.0, LOST, speed, 3.0, rules, car), _drive(None, LOST, speed, 3.0, rules, car)
    answer = [(c.mode, c.speed_limit_mps, c.steering_deg) for c in without]
    assert [(c.mode, c.speed_limit_mps, c.steering_deg) for c in with_route] == answer


def test_the_bundled_duckiebot_follows_its_route_across_a_junction_and_default_follows_none() -> None:
    """A Duckiebot's intersection navigation gives the way through a junction (worlds/duckietown): its rule file follows
    it for a junction's crossing; the default rule file (no world gives that car a route) follows none."""
    assert fg.load_rules(bundled_rules_path("default.toml")).policy.route_blind_m == 0.0
    rules = fg.load_rules(bundled_rules_path("duckiebot.toml"))
    assert 0.6 <= rules.policy.route_blind_m <= 3.0  # a junction tile (0.585 m) and its approach and exit, not a drive
    car = dataclasses.replace(fg.VehicleLimits.preset("duckiebot"), has_ultrasonic=True, ultrasonic_max_range_m=1.2)  # path known clear
    cmds = _drive(5.0, LOST, 0.15, 3.0, rules, car)[round(2.0 / DT):]
    assert any("following the route" in r for c in cmds[:5] for r in c.reasons)
    assert all(c.mode is not fg.Mode.EMERGENCY for c in cmds[:5])


# -- the pure step ------------------------------------------------------------------------------------------------
CFG = dataclasses.replace(PolicyConfig(), route_blind_m=40.0, road_doubt_fraction=0.5)


@given(routed=st.floats(0.0, 100.0), route=st.one_of(st.none(), st.floats(-30, 30)), clear=st.floats(0.0, 200.0),
       doubt=st.sampled_from(["", "nothing is known about the path ahead"]), speed=st.one_of(st.none(), st.floats(0.0, 30.0)),
       dt=st.floats(0.0, 0.2), calm=st.booleans())
def test_next_route_follows_only_a_given_route_with_budget_and_a_clear_path(
    routed: float, route: float | None, clear: float, doubt: str, speed: float | None, dt: float, calm: bool
) -> None:
    step = next_route(routed, route, calm, clear, doubt, speed, dt, CFG, CAR)
    if calm:
        assert step.routed_m == 0.0 and not step.following
        return
    can = route is not None and not doubt and routed < CFG.route_blind_m
    assert step.following is can
    if not can:
        assert step.routed_m == routed and math.isinf(step.cap_mps)
        return
    moved = (speed if speed is not None else CAR.max_speed_mps) * dt
    assert step.routed_m == pytest.approx(routed + moved)
    assert step.cap_mps <= CFG.road_doubt_fraction * CAR.max_speed_mps + 1e-12
    assert step.cap_mps <= envelope_speed_mps(clear, CAR) + 1e-12
    assert step.steering_deg == route


def test_next_route_says_why_it_stops_following() -> None:
    step = next_route(40.0, 5.0, False, 80.0, "", 10.0, 0.1, CFG, CAR)
    assert not step.following and "at most 40 m" in step.why and "no longer" in step.why


@pytest.mark.parametrize("bearing", [0.4, -3.0, 5.0])
def test_the_route_is_followed_rather_than_a_lead_seen_where_the_markings_end(bearing: float) -> None:
    """At a junction a vehicle ahead may cross it elsewhere: the route, not the lead, guides (MetaDrive SXS seed 5: a car
    40 m ahead went straight on while the route turned left; following it took the car off the route)."""
    guard = fg.FearGuard(lambda frame: 0.0, rules=ROAD, vehicle=CAR)
    lead = fg.Lead(bearing_deg=bearing, range_m=40.0)
    cmds = []
    for i in range(50):
        cues = CALM if i < 20 else dataclasses.replace(LOST, obstacle_range_m=40.0)
        cmds.append(guard.step(fg.Observation(t_s=i * DT, speed_mps=7.0, cues=cues, lead=lead if i >= 20 else None,
                                              route_steering_deg=16.0)))
    assert all(c.mode is not fg.Mode.EMERGENCY for c in cmds)
    assert cmds[-1].steering_deg == pytest.approx(16.0)
    without = _drive(None, dataclasses.replace(LOST, obstacle_range_m=40.0), 7.0, 3.0)
    assert without[-1].mode is fg.Mode.EMERGENCY  # without a route: EMERGENCY (a lead to follow, or a stop)


# -- yielding while crossing ------------------------------------------------------------------------------------
def test_crossing_on_the_route_a_vehicle_coming_toward_the_car_is_yielded_to_until_gone_for_hold_s() -> None:
    """Turning across the oncoming lanes (MetaDrive SXS seed 5): a car seen coming at 12 m/s stops the crossing; once
    it has not been seen for ``hold_s`` the crossing goes on."""
    guard = fg.FearGuard(lambda frame: 0.0, rules=ROAD, vehicle=CAR)
    cmds, seen_until = [], 3.0
    for i in range(80):
        t = i * DT
        oncoming = 2.0 <= t < seen_until
        cues = CALM if t < 2.0 - 1e-9 else dataclasses.replace(LOST, obstacle_range_m=40.0 - 19.0 * (t - 2.0) if oncoming else math.inf)
        cmds.append(guard.step(fg.Observation(t_s=round(t, 6), speed_mps=7.0 if t < seen_until else 0.0, cues=cues,
                                              range_rate_mps=-19.0 if oncoming else None, route_steering_deg=12.0)))
    by_t = {round(i * DT, 1): c for i, c in enumerate(cmds)}
    yielding = [t for t, c in by_t.items() if any("yielding" in r for r in c.reasons)]
    assert yielding and min(yielding) <= 2.3
    assert all(by_t[t].speed_limit_mps == 0.0 for t in yielding if t >= 2.4)
    hold = ROAD.policy.hold_s
    assert max(yielding) <= seen_until + hold + 1e-6  # none seen for hold_s: the crossing goes on
    after = [c for t, c in by_t.items() if t > seen_until + hold + 0.2]
    assert after and all(any("following the route" in r for r in c.reasons) and c.speed_limit_mps > 0.0 for c in after)
    assert all(c.mode is not fg.Mode.EMERGENCY for c in cmds[round(2.0 / DT):] if not any("collision" in r for r in c.reasons))


def test_a_vehicle_moving_away_or_standing_is_no_reason_to_yield() -> None:
    for rate in (3.0, 0.0, -7.0):  # pulling away, steady, and closing at the car's own speed: a standing object
        step = next_route(10.0, 5.0, False, 50.0, "", 7.0, 0.1, CFG, CAR, t_s=5.0, object_speed_mps=7.0 + rate)
        assert step.following and step.cap_mps > 0.0 and step.oncoming_t_s is None
    step = next_route(10.0, 5.0, False, 50.0, "", 7.0, 0.1, CFG, CAR, t_s=5.0, object_speed_mps=-3.0)
    assert step.cap_mps == 0.0 and step.oncoming_t_s == 5.0 and "yielding" in step.why


# -- a departure the route asks for ---------------------------------------------------------------------------------
def _lane() -> LaneGeometry:
    """A straight 3.5 m lane seen from 4 to 20 m, the car in its middle."""
    return LaneGeometry(GroundLine(1.75, 0.0), GroundLine(-1.75, 0.0), 4.0, 20.0, 0.0)


@pytest.mark.parametrize("route", [-20.0, -28.0])
def test_the_lane_check_lets_a_departure_the_route_asks_for_through(route: float) -> None:
    cfg = ROAD.policy
    args = (_lane(), route, 10.0, CAR, cfg.lane_check_lookahead_s, cfg.lane_check_min_deg)
    assert lane_check(*args).override_deg is not None  # without the route: overridden, back into the lane
    intended = lane_check(*args, route_deg=route + 0.5 * cfg.lane_check_min_deg)
    assert intended.override_deg is None and "intended departure" in intended.why
    stray = lane_check(*args, route_deg=0.0)  # the route stays in the lane: the estimator strays, overridden
    assert stray.override_deg is not None
    other = lane_check(*args, route_deg=-route)  # the route leaves to the other side
    assert other.override_deg is not None


def test_after_an_emergency_in_the_junction_the_creep_follows_the_route_as_one_creep() -> None:
    """Stopped in the junction (a vehicle passed close), the picture still lost: the creep goes on along the route past
    ``recovery_creep_m`` without stopping every car length, within the route's budget."""
    guard = fg.FearGuard(lambda frame: 0.0, rules=ROAD, vehicle=CAR)
    speed, t, cmds = 7.0, 0.0, []
    for i in range(400):
        t = round(i * DT, 6)
        if t < 2.0:
            cues = CALM
        elif t < 2.5:
            cues = dataclasses.replace(LOST, obstacle_range_m=3.0)  # close: an EMERGENCY STOP for the collision risk
        else:
            cues = LOST
        cmd = guard.step(fg.Observation(t_s=t, speed_mps=speed, cues=cues, route_steering_deg=10.0))
        cmds.append(cmd)
        speed = min(cmd.speed_limit_mps, max(0.0, speed - 6.0 * DT)) if cmd.speed_limit_mps < speed else cmd.speed_limit_mps
    creeping = [c for c in cmds if any("creep on the route" in r for r in c.reasons)]
    assert creeping, "a creep on the route"
    crept = [float(r.split("creep on the route (")[1].split(" of")[0]) for c in creeping for r in c.reasons if "creep on the route (" in r]
    assert max(crept) > 2.0 * ROAD.policy.recovery_creep_m
    assert all(c.speed_limit_mps > 0.0 for c in creeping[5:])  # one creep: no stop every car length
    assert all(c.steering_deg == pytest.approx(10.0) for c in creeping[5:])
    crawl = ROAD.policy.crawl_fraction * CAR.max_speed_mps
    assert max(c.speed_limit_mps for c in creeping) > 1.5 * crawl  # at the route's cap, not at crawl speed
    assert all(c.speed_limit_mps <= ROAD.policy.road_doubt_fraction * CAR.max_speed_mps + 1e-9 for c in creeping)
