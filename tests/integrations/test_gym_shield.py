"""FearGuardShield on the real highway-env (run by .ci/highway.sh in its own environment; skipped elsewhere)."""

from __future__ import annotations

import math
import sys
from collections import Counter
from pathlib import Path
from typing import Any

import numpy as np
import pytest

gymnasium = pytest.importorskip("gymnasium", reason="gymnasium + highway-env are installed by .ci/highway.sh")
highway_env = pytest.importorskip("highway_env", reason="gymnasium + highway-env are installed by .ci/highway.sh")

import fearguard as fg  # noqa: E402
from fearguard.integrations.gym import (  # noqa: E402
    FearGuardShield,
    entered_lanes,
    highway_leads,
    highway_observation,
    highway_vehicle,
    lane_change_refusal,
    lane_lead,
)

sys.path.insert(0, str(Path(__file__).parent))
from highway_agent import AggressiveAgent  # noqa: E402

SEEDS = range(20)
CONFIG = {
    "action": {"type": "ContinuousAction"},
    "observation": {"type": "Kinematics", "normalize": False},
    "lanes_count": 3,
    "vehicles_count": 20,
    "policy_frequency": 5,  # [Hz] the agent steers a lane change itself: 1 Hz (the default) is too coarse for that
    "simulation_frequency": 15,
    "duration": 30,  # [s]
}
SURROUNDING_M = 100.0  # [m] traffic within this distance of the ego is "the surrounding traffic"


def make(shielded: bool = True):
    env = gymnasium.make("highway-v0", config=CONFIG)
    return FearGuardShield(env) if shielded else env


def crash_kind(env) -> str:
    """Which vehicle the ego hit: the nearest one, ahead or behind along the ego lane (or beside it)."""
    base = env.unwrapped
    ego = base.vehicle
    other = min((v for v in base.road.vehicles if v is not ego), key=lambda v: float(np.linalg.norm(v.position - ego.position)))
    lane = base.road.network.get_lane(ego.lane_index)
    ds = lane.local_coordinates(other.position)[0] - lane.local_coordinates(ego.position)[0]
    if abs(ds) < (ego.LENGTH + other.LENGTH) / 2 - 1.0:
        return "side"
    return "into the car ahead" if ds > 0 else "hit from behind"


def episode(seed: int, shielded: bool = True) -> dict:
    env = make(shielded)
    env.reset(seed=seed)
    agent = AggressiveAgent(env, seed)
    ego_speeds, traffic_speeds, modes, crash = [], [], Counter(), None
    while True:
        _, _, terminated, truncated, info = env.step(agent())
        base = env.unwrapped
        ego = base.vehicle
        ego_speeds.append(ego.speed)
        near = [v.speed for v in base.road.vehicles if v is not ego and abs(v.position[0] - ego.position[0]) <= SURROUNDING_M]
        if near:
            traffic_speeds.append(float(np.mean(near)))
        if shielded:
            modes[info["fearguard"].mode.name] += 1
        if info["crashed"]:
            crash = crash_kind(env)
        if terminated or truncated:
            break
    env.close()
    return {"ego": float(np.mean(ego_speeds)), "traffic": float(np.mean(traffic_speeds)), "modes": modes, "crash": crash}


@pytest.fixture(scope="module")
def shielded_runs() -> list[dict]:
    runs = [episode(seed) for seed in SEEDS]
    crashes = Counter(r["crash"] for r in runs if r["crash"])
    ego, traffic = (float(np.mean([r[k] for r in runs])) for k in ("ego", "traffic"))
    modes = sum((r["modes"] for r in runs), Counter())
    print(
        f"\nshield, aggressive agent, {len(runs)} seeds: crashes {sum(crashes.values())} {dict(crashes)}; "
        f"mean speed {ego:.1f} m/s vs traffic {traffic:.1f} m/s = {100 * ego / traffic:.0f} %; modes {dict(modes)}"
    )
    return runs


def test_an_aggressive_agent_shielded_never_hits_the_car_ahead_and_rarely_crashes(shielded_runs):
    crashes = Counter(r["crash"] for r in shielded_runs if r["crash"])
    assert crashes["into the car ahead"] == 0
    assert sum(crashes.values()) <= 0.10 * len(shielded_runs)


def test_an_aggressive_agent_shielded_keeps_up_with_the_surrounding_traffic(shielded_runs):
    ego = float(np.mean([r["ego"] for r in shielded_runs]))
    traffic = float(np.mean([r["traffic"] for r in shielded_runs]))
    assert ego >= 0.85 * traffic


def test_without_the_shield_the_same_agent_hits_the_car_ahead():
    kinds = Counter(episode(seed, shielded=False)["crash"] for seed in SEEDS[:3])
    assert kinds["into the car ahead"] >= 2, kinds


def test_the_command_is_in_info_and_the_guard_is_reset_on_reset():
    env = make()
    for _ in range(2):  # a second episode starts its clock at 0 again: no "time did not increase" fault
        env.reset(seed=3)
        for _ in range(5):
            _, _, _, _, info = env.step(np.array([0.0, 0.0], np.float32))
            cmd = info["fearguard"]
            assert isinstance(cmd, fg.Command)
            assert not any(r.startswith("fault") for r in cmd.reasons), cmd.reasons


def test_full_throttle_is_clipped_so_the_speed_stays_within_the_limit_or_brakes_hardest_toward_it():
    env = make()
    env.reset(seed=1)
    base = env.unwrapped
    hardest_mps = -base.action_type.acceleration_range[0] / base.config["policy_frequency"]  # speed lost in one step
    clipped = 0
    for _ in range(60):
        before = base.vehicle.speed
        _, _, terminated, _, info = env.step(np.array([1.0, 0.0], np.float32))
        limit = info["fearguard"].speed_limit_mps
        assert base.vehicle.speed <= max(limit, before - hardest_mps) + 1e-6
        clipped += info["fearguard_action"][0] < 1.0
        if terminated:
            break
    assert clipped > 0


def test_steering_signs_right_in_highway_env_is_negative_degrees_in_fearguard():
    env = make()
    env.reset(seed=2)
    _, _, _, _, info = env.step(np.array([0.0, 0.5], np.float32))  # + = right in highway-env
    assert info["fearguard"].steering_deg == pytest.approx(-22.5)
    assert info["fearguard_action"][1] == pytest.approx(0.5)  # the agent's steering passes unchanged


def test_the_lane_being_entered_counts_its_vehicle_ahead():
    env = make()
    env.reset(seed=0)
    base = env.unwrapped
    ego = base.vehicle
    side = base.road.network.side_lanes(ego.lane_index)[0]
    ego.heading = 0.3 if side[2] > ego.lane_index[2] else -0.3  # steeply into the side lane (y points down)
    assert entered_lanes(base.road, ego)[0] == side
    lanes = {lead.lane_index for lead in highway_leads(env)}
    assert lanes <= {ego.lane_index, side}
    assert (side in lanes) == (lane_lead(base.road, ego, side) is not None)


def test_the_vehicle_is_the_envs_car_and_the_lead_speed_comes_from_the_simulator():
    env = make()
    env.reset(seed=4)
    base = env.unwrapped
    v = highway_vehicle(env)
    assert (v.wheelbase_m, v.width_m, v.max_steering_deg, v.max_decel_mps2) == (5.0, 2.0, pytest.approx(45.0), 5.0)
    assert v.lead_max_decel_mps2 == 6.0  # IDMVehicle.ACC_MAX: the traffic's hardest braking
    assert v.max_lateral_accel_mps2 == pytest.approx(v.max_speed_mps**2 / v.wheelbase_m)  # ±45° at top speed: no tyre model
    obs = highway_observation(env, v)
    lead = min(highway_leads(env), key=lambda lead: lead.range_m)
    assert obs.range_rate_mps is not None and obs.speed_mps == pytest.approx(base.vehicle.speed)
    assert obs.cues.obstacle_range_m <= 150.0 and lead.range_m <= obs.cues.obstacle_range_m


def _env_and_side_lane() -> tuple[Any, Any, Any, Any, Any, float]:
    """A fresh env (seed 0), its ego and road, the first lane beside the ego's, and the ego's s on that lane."""
    env = make()
    env.reset(seed=0)
    ego, road = env.unwrapped.vehicle, env.unwrapped.road
    side = road.network.side_lanes(ego.lane_index)[0]
    lane = road.network.get_lane(side)
    return env, ego, road, side, lane, lane.local_coordinates(ego.position)[0]


def test_a_car_beside_is_not_ahead_and_blocks_a_lane_change_toward_it():
    env, ego, road, side, lane, s_ego = _env_and_side_lane()
    other = next(o for o in road.vehicles if o is not ego)
    other.position = lane.position(s_ego + 2.0, 0.0)  # beside the ego, its centre 2 m ahead (overlapping)
    other.heading, other.lane_index = lane.heading_at(s_ego), side
    lead = lane_lead(road, ego, side)
    assert lead is None or lead.range_m > 0.0  # the car beside is not "ahead at 0 m" (it would stop the ego)
    toward = 0.3 if side[2] > ego.lane_index[2] else -0.3  # rad, + = right
    assert "beside" in lane_change_refusal(env, highway_vehicle(env), toward)
    _, _, _, _, info = env.step(np.array([0.0, toward / math.radians(45.0)], np.float32))
    assert "beside" in info["fearguard_lane_change"]
    assert abs(info["fearguard_action"][1]) < abs(toward / math.radians(45.0))  # steered to keep the lane instead


def test_a_cut_in_close_behind_a_faster_car_is_rss_safe_but_refused_when_the_rules_would_stop_for_it():
    env, ego, road, side, lane, s_ego = _env_and_side_lane()
    others = [o for o in road.vehicles if o is not ego]
    for k, o in enumerate(others):  # everyone else far ahead in the ego's lane: only the car placed below matters
        o.position = road.network.get_lane(ego.lane_index).position(s_ego + 400.0 + 20.0 * k, 0.0)
    near = others[0]
    near.position, near.heading, near.speed = lane.position(s_ego + ego.LENGTH + 7.0, 0.0), lane.heading_at(s_ego), ego.speed + 3.0
    toward = 0.3 if side[2] > ego.lane_index[2] else -0.3  # rad, + = right
    vehicle = highway_vehicle(env)
    assert lane_change_refusal(env, vehicle, toward) == ""  # 7 m behind a faster car: inside RSS
    why = lane_change_refusal(env, vehicle, toward, env.guard.rules)
    assert "feared" in why and "7.0 m" in why  # the road-car rules fear 7 m at EMERGENCY: the guard would stop for it


def test_a_non_highway_env_needs_observe_and_act():
    env = gymnasium.make("Pendulum-v1")
    with pytest.raises(TypeError, match="observe"):
        FearGuardShield(env)
    cues = fg.Cues(lane_confidence=1.0, brightness=128.0, occlusion=0.0, obstacle_range_m=math.inf, qr_staleness_s=0.0)
    clock = iter(range(1, 1000))
    shield = FearGuardShield(
        env, vehicle=fg.VehicleLimits(has_ultrasonic=False, has_qr_localisation=False),
        observe=lambda e, obs, info: fg.Observation(t_s=float(next(clock)), speed_mps=0.0, cues=cues),
        act=lambda action, cmd, e: action * min(1.0, cmd.speed_limit_mps),
    )
    shield.reset(seed=0)
    _, _, _, _, info = shield.step(np.array([1.0], np.float32))
    assert isinstance(info["fearguard"], fg.Command)
