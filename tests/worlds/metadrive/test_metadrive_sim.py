"""fearguard in the real MetaDrive simulator (skipped where it is not installed: `bash .ci/metadrive.sh`).

Short and few: a MetaDrive reset takes 10-25 s and a rendered step 0.25-3 s on 2 shared cores; the suite and
docs/metadrive.md measure the long drives. Worlds without a camera (``render=False``) reset in a few seconds.
"""

from __future__ import annotations

import json
import math
from pathlib import Path

import cv2
import numpy as np
import pytest

pytest.importorskip("metadrive", reason="MetaDrive is not installed (bash .ci/metadrive.sh)")

from fearguard.drive.world import Decision, Sensed
from fearguard.worlds.metadrive.drive import DriveOptions, Expert, drive
from fearguard.worlds.metadrive.world import MetaDriveWorld, Scenario, Truth


@pytest.fixture
def world() -> MetaDriveWorld:
    """Seed 1, no traffic, 320×240: the ego on the left lane of a straight first block, the yellow line on its left.

    One per test: MetaDrive allows one engine per process, so a world is closed before the next one opens."""
    w = MetaDriveWorld(Scenario(seed=1, traffic_density=0.0))
    yield w
    w.close()


def test_the_frame_is_a_road_whose_yellow_line_lies_where_the_camera_model_puts_it(world: MetaDriveWorld) -> None:
    """The camera model (60° horizontal FOV, 2.095 m up, pitched 0.6° up) projects the lane's left boundary — the
    yellow centre line, half a lane width left of the ego — onto the yellow paint MetaDrive rendered, row by row.
    The truth at the start is sane too (one world for both: a reset costs 10-25 s)."""
    sensed = world.sense()
    assert isinstance(sensed, Sensed) and sensed.index == 0 and sensed.t_s == 0.0
    image, truth = sensed.image, world.truth()
    _truth_at_the_start_is_sane(world)
    assert image is not None and image.shape == (240, 320, 3) and image.dtype == np.uint8 and sensed.observation.frame is image
    assert sensed.observation.ultrasonic_range_m is None  # no radar unless asked
    hsv = cv2.cvtColor(image, cv2.COLOR_BGR2HSV)
    sky, road = image[:40].reshape(-1, 3).mean(axis=0), hsv[200:, 100:220].reshape(-1, 3)
    assert sky[0] > sky[2]  # blue above
    assert np.median(road[:, 1]) < 40 and 60 < np.median(road[:, 2]) < 200  # grey asphalt below
    yellow = (hsv[..., 0] >= 15) & (hsv[..., 0] <= 40) & (hsv[..., 1] >= 100) & (hsv[..., 2] >= 100)
    camera, checked = world.camera, 0
    for distance_m in (6.0, 8.0, 11.0, 15.0):
        u, v, _ = camera.project_ground(np.array([distance_m]), np.array([truth.lane_width_m / 2 - truth.lane_offset_m]))
        row = round(float(v[0]))
        found = np.flatnonzero(yellow[row])
        assert found.size, f"no yellow paint on row {row} ({distance_m} m ahead)"
        assert abs(float(np.median(found)) - float(u[0])) < 4.0, (distance_m, row, found, u)
        checked += 1
    assert checked == 4


def _truth_at_the_start_is_sane(world: MetaDriveWorld) -> None:
    t = world.truth()
    assert isinstance(t, Truth) and t.t_s == 0.0 and t.speed_mps < 0.5
    assert abs(t.lane_offset_m) < 0.05 and abs(t.heading_error_deg) < 1.0 and t.lane_index == 0
    assert t.lane_width_m == pytest.approx(3.5) and t.route_m > 200.0 and 0.0 <= t.route_completion < 0.05
    assert not (t.out_of_road or t.crashed or t.on_solid_line or t.over_centre_line or t.arrived)
    assert math.isinf(t.gap_m) and math.isinf(t.ttc_s)  # no traffic
    assert world.fps == pytest.approx(10.0) and not world.done


def _drive(w: MetaDriveWorld, steps: int, decision: Decision) -> None:
    """``steps`` steps of the World protocol with one decision (what drive.loop.run does, without a recorder)."""
    for _ in range(steps):
        sensed = w.sense()
        assert sensed is not None
        w.act(sensed, decision)


@pytest.mark.parametrize("bearing_deg", [8.0, -8.0])
def test_a_left_command_turns_left_and_a_right_one_right(bearing_deg: float) -> None:
    w = MetaDriveWorld(Scenario(seed=1, traffic_density=0.0, render=False))
    try:
        _drive(w, 20, Decision(0.0, 8.0))  # 2 s to speed, straight
        before = w.truth()
        _drive(w, 10, Decision(bearing_deg, 8.0))  # 1 s on the command
        after = w.truth()
    finally:
        w.close()
    assert before.speed_mps > 3.0 and not after.out_of_road
    assert math.copysign(1, after.heading_error_deg - before.heading_error_deg) == math.copysign(1, bearing_deg)
    assert math.copysign(1, after.lane_offset_m - before.lane_offset_m) == math.copysign(1, bearing_deg)  # + = left


def test_the_same_seed_gives_the_same_drive() -> None:
    def run() -> list[tuple[float, ...]]:
        w = MetaDriveWorld(Scenario(seed=2, traffic_density=0.1, render=False), seconds=3.0)
        expert = Expert(w, 10.0)
        try:
            out = []
            while (sensed := w.sense()) is not None:  # the World protocol: None once the 3 s are driven
                assert sensed.image is None  # no camera for the expert
                w.act(sensed, expert.decide(sensed))
                t = w.truth()
                out.append((t.x_m, t.y_m, t.speed_mps, t.gap_m, t.route_m))
            return out
        finally:
            w.close()

    first = run()
    assert len(first) == 30 and first[-1][2] > 3.0 and first == run()


def test_a_short_guarded_drive_moves_forward_and_writes_its_log(tmp_path: Path) -> None:
    result = drive(DriveOptions(seed=1, seconds=2.0), tmp_path)
    s = result.summary
    lines = [json.loads(line) for line in (tmp_path / "log.jsonl").read_text().splitlines()]
    assert len(lines) == s["steps"] == 20 and not result.interrupted
    assert {"lane_confidence", "brightness", "fear", "mode", "strategy", "speed_limit_mps", "steer", "throttle",
            "lane_offset_m", "progress_m", "gap_m"} <= set(lines[0])
    assert lines[-1]["progress_m"] > lines[0]["progress_m"] and lines[-1]["speed_mps"] > 0.2  # forward; the limit rises at 1.5 m/s²
    assert s["crashes"] == 0 and s["out_of_road"] == 0 and s["guarded"] and s["lane_offset_max_m"] < 0.5
    assert json.loads((tmp_path / "summary.json").read_text())["controller"] == "guarded"
    assert (tmp_path / "timeline.png").stat().st_size > 0
    assert s["timing"]["controller_ms_median"] > 0 and s["timing"]["simulator_ms_median"] > 0
    assert [line["frame"] for line in lines] == list(range(20))  # the one loop's record: one line per step, in order


def test_a_stopped_car_stands_in_the_lane_where_it_was_asked_for() -> None:
    """The broken-down car 35 m ahead in the ego's lane: the truth's gap is 35 m, it stays put while the ego closes in."""
    w = MetaDriveWorld(Scenario(seed=0, traffic_density=0.0, render=False, lead="stopped", lead_ahead_m=35.0))
    try:
        start = w.truth()
        _drive(w, 20, Decision(0.0, 5.0))
        after = w.truth()
    finally:
        w.close()
    assert start.gap_m == pytest.approx(35.0, abs=0.1) and start.lead_speed_mps == pytest.approx(0.0, abs=0.01)
    assert after.gap_m == pytest.approx(35.0 - (after.progress_m - start.progress_m), abs=0.5) and after.gap_m < 32.0
    assert abs(after.lead_speed_mps) < 0.01 and not after.crashed


def test_a_drive_runs_in_a_dask_worker_as_metadrive_suite_jobs_runs_it(tmp_path: Path) -> None:
    """`metadrive-suite --jobs N` runs each drive in a worker process of a real Dask LocalCluster, on a worker thread:
    Panda3D's per-frame SIGINT handler (main thread only) once failed every such drive at its reset, and a process that
    had driven before could start no worker at all (MetaDrive's PYTHONUTF8=on, which Python rejects in a child)."""
    import os

    from fearguard.drive.cluster import DaskExecutor
    from fearguard.worlds.metadrive.suite import plan, run_suite

    MetaDriveWorld(Scenario(seed=1, traffic_density=0.0)).close()  # this process has driven before (a rendered world)
    assert os.environ.get("PYTHONUTF8") in (None, "0", "1")

    specs = plan([1], 0.5, (), (), out_dir=tmp_path, controllers=("guarded",))
    _, interrupted = run_suite(tmp_path, specs, executor=DaskExecutor(jobs=1))
    rows = [json.loads(line) for line in (tmp_path / "runs.jsonl").read_text().splitlines()]
    assert not interrupted and [r["controller"] for r in rows] == ["expert", "guarded"]  # a failed drive raises here
    assert all(r["progress_m"] > 0 and r["crashes"] == 0 for r in rows)


def test_the_route_steering_turns_the_way_the_expert_turns_through_a_junction() -> None:
    """The navigation's route (``route_steering_deg``) on MetaDrive's own lanes: ~0 on the straight first block, and
    the same way as the expert's wheel where it turns (the 4-way junction of SXCS seed 3 turns left, the next curve)."""
    w = MetaDriveWorld(Scenario(map_blocks="SXCS", seed=3, traffic_density=0.0, render=False), seconds=20.0)
    try:
        expert, rows = Expert(w, 10.0), []
        while (sensed := w.sense()) is not None:
            decision = expert.decide(sensed)
            w.act(sensed, decision)
            rows.append((sensed.t_s, sensed.observation.route_steering_deg, decision.action.steer))
    finally:
        w.close()
    assert all(route is not None for _, route, _ in rows)
    assert all(abs(route) < 1.0 for t, route, _ in rows if t < 8.0)
    turning = [(route, steer) for _, route, steer in rows if abs(steer) > 0.15]  # the expert's wheel beyond 6 deg
    assert len(turning) >= 5
    assert sum(np.sign(route) == np.sign(steer) for route, steer in turning) >= 0.8 * len(turning)


def test_a_guarded_car_crosses_a_junction_on_its_route_without_stopping(tmp_path: Path) -> None:
    """SXCS seed 3, no traffic: at the 4-way junction the markings end and the route turns left; the car follows the
    route in CAUTION (no EMERGENCY) and drives on beyond it (without the route it stopped at the entry: 39 %)."""
    result = drive(DriveOptions(map_blocks="SXCS", seed=3, traffic_density=0.0, seconds=21.0, plots=False), tmp_path)
    s = result.summary
    lines = [json.loads(line) for line in (tmp_path / "log.jsonl").read_text().splitlines()]
    assert s["crashes"] == 0 and s["out_of_road"] == 0
    assert not any(line["mode"] == "EMERGENCY" for line in lines)
    assert any("following the route" in r for line in lines for r in line["reasons"])
    assert s["progress_m"] > 145.0  # the junction spans ~95-131 m of the route (the expert turns there from 11 to 14.5 s)
