"""One closed-loop drive in gym-duckietown: the robot's camera → fearguard → the robot, measured by the simulator.

Controllers:
- ``guarded``: ``FearGuard(HoughLaneSteering(camera))`` with the Duckiebot preset; the robot drives
  min(cruise, speed limit) along the pure-pursuit arc to the commanded steering bearing.
- ``unguarded``: the same lane steering alone at cruise (a fault keeps the last angle).
- ``expert``: the simulator's ground-truth pure pursuit (lane centre 0.25 m ahead) at cruise, the upper bound.
Every step: frame (with sensor noise) and, with ``range_sensor="tof"``, a time-of-flight reading from
the ground truth → the controller → the DuckietownEnv action → the simulator's truth. An obstacle
(duck, cone, Duckiebot) can stand on the lane centre ``ahead_m`` ahead of the start; it is taken away
once the robot has stood still ``remove_after_s``. The drive ends at its duration or at the
simulator's "invalid pose" (a wheel off the drivable tiles, or contact). Outputs: log.jsonl (one
flushed line per step), summary.json, timeline.png, drive.png, and annotated.mp4 if asked.
"""

from __future__ import annotations

import math
import time
from collections.abc import Callable
from dataclasses import asdict, dataclass, replace
from pathlib import Path
from typing import Any

import numpy as np

from fearguard.drive.controllers import Guarded, Unguarded
from fearguard.drive.loop import run
from fearguard.drive.world import Controller, Decision, Outcome, Sensed
from fearguard.fuzzy.loader import bundled_rules_path, load_rules
from fearguard.outputs.recorder import Recorder
from fearguard.outputs.report import json_value
from fearguard.supervisor import Command, FearGuard, Observation
from fearguard.vision.ground_lanes import GroundLaneSpec
from fearguard.vision.lane_steering import HoughLaneSteering
from fearguard.vision.navigated import NavigatedSteering
from fearguard.worlds.duckietown.metrics import STOPPED_SPEED_MPS, Sample, route_completion, summarize_drive
from fearguard.worlds.duckietown.preset import (
    FRAME_RATE_HZ,
    curvature_action,
    duckiebot_camera,
    duckiebot_limits,
    duckietown_lane,
    steering_action,
)
from fearguard.worlds.duckietown.world import DuckietownWorld, Truth

CONTROLLERS = ("guarded", "unguarded", "expert")
OBSTACLES = ("duck", "cone", "duckiebot")
RANGE_SENSORS = ("none", "tof")
LANE_MODELS = ("preset", "camera")
EXPERT_LOOKAHEAD_M = 0.25  # [m] the simulator's own pure-pursuit teacher follows the lane centre this far ahead
RULES_FILE = "duckiebot.toml"


@dataclass(frozen=True)
class DriveOptions:
    """One drive; every field has the default a plain ``fearguard duckietown MAP --out DIR`` uses."""

    map_name: str = "loop_empty"
    seconds: float = 60.0
    controller: str = "guarded"
    cruise_mps: float = 0.2
    obstacle: str | None = None
    ahead_m: float = 1.0
    remove_after_s: float = 3.0  # [s] standing still this long in front of the obstacle: it is taken away
    range_sensor: str = "none"
    domain_rand: bool = False
    seed: int = 0
    width_px: int = 320
    height_px: int = 240
    rules: str | None = None  # default: the bundled Duckiebot rules
    start_tile: tuple[int, int] | None = None
    video: bool = False
    plots: bool = True
    mcap: bool = False  # run.mcap for Foxglove (outputs/mcap.py)
    route: bool = True  # the intersection navigation's route through junctions (world.route_bearing_deg), as MetaDrive's
    lane: str = "preset"  # the lane model: "preset" (duckietown_lane(): Duckietown's lane and paint) or "camera" (what a
    #   camera alone knows, GroundLaneSpec.for_camera: sizes scaled by its height, the lane width measured from the picture)

    def __post_init__(self) -> None:
        if self.controller not in CONTROLLERS:
            raise ValueError(f"controller {self.controller!r}: choose one of {', '.join(CONTROLLERS)}")
        if self.obstacle is not None and self.obstacle not in OBSTACLES:
            raise ValueError(f"obstacle {self.obstacle!r}: choose one of {', '.join(OBSTACLES)}")
        if self.range_sensor not in RANGE_SENSORS:
            raise ValueError(f"range sensor {self.range_sensor!r}: choose one of {', '.join(RANGE_SENSORS)}")
        if self.lane not in LANE_MODELS:
            raise ValueError(f"lane model {self.lane!r}: choose one of {', '.join(LANE_MODELS)}")
        for name in ("seconds", "cruise_mps", "ahead_m"):
            value = getattr(self, name)
            if not (math.isfinite(value) and value > 0):
                raise ValueError(f"{name} must be a positive number, got {value!r}")


@dataclass(frozen=True)
class DriveResult:
    summary: dict[str, Any]
    out_dir: Path | None
    interrupted: bool
    video_path: Path | None = None  # the annotated video as written (annotated.mp4, or annotated.avi without PyAV)


class DuckietownDrive:
    """gym-duckietown as a ``World``: the robot's camera frame (and a time-of-flight reading) in, an action out — the
    pure-pursuit arc to the commanded steering at the commanded speed, or the expert's own — the simulator's truth of
    every step kept for the metrics and the drive plot. An obstacle is taken away once the robot has stood still
    ``remove_after_s`` in front of it."""

    def __init__(self, options: DriveOptions, world: DuckietownWorld, aim_m: float) -> None:
        self.o, self.world, self.aim_m = options, world, aim_m
        self.fps = FRAME_RATE_HZ
        self.total = math.ceil(options.seconds * FRAME_RATE_HZ)
        self.truth: Truth = world.truth()
        self.samples: list[Sample] = []
        self.path: list[dict[str, Any]] = []  # what drive.png draws, kept as it goes (no world reads its log back)
        self.sim_ms: list[float] = []
        self._k = 0
        self._standing_since: float | None = None
        self.route_now: float | None = None  # the route's steering at the last ``sense`` (the estimator's route, as MetaDrive's)

    def sense(self) -> Sensed | None:
        if self._k >= self.total:
            return None
        o = self.o
        frame = self.world.frame_bgr() if o.controller != "expert" else None
        tof = self.world.tof_range_m() if o.range_sensor == "tof" else None
        self.route_now = self.world.route_bearing_deg(self.aim_m) if o.route and o.controller != "expert" else None
        obs = Observation(t_s=self.truth.t_s, speed_mps=self.truth.speed_mps, frame=frame, ultrasonic_range_m=tof,
                          route_steering_deg=self.route_now)
        return Sensed(self._k, self.truth.t_s, obs, frame)

    def act(self, sensed: Sensed, decision: Decision) -> Outcome:
        action = decision.action if decision.action is not None else steering_action(decision.steering_deg, decision.speed_mps, self.aim_m)
        present = self.world.has_obstacle
        began = time.perf_counter()
        truth = self.truth = self.world.step(action)
        self.sim_ms.append(1e3 * (time.perf_counter() - began))
        cmd = decision.command
        self.samples.append(Sample(truth.t_s, truth.speed_mps, truth.lane_offset_m, truth.progress_m, truth.invalid_pose,
                                   truth.collided, truth.obstacle_gap_m, present, cmd.mode.name if cmd else None,
                                   cmd.strategy.name if cmd else None, cmd.fear if cmd else None, _cause(cmd)))
        fields = dict(
            controller=self.o.controller, speed_target_mps=decision.speed_mps, applied_steering_deg=decision.steering_deg,
            vel=action.vel, omega=action.omega, yaw_rate_rps=action.yaw_rate_rps, speed_mps=truth.speed_mps,
            progress_m=truth.progress_m, lane_offset_m=truth.lane_offset_m, heading_error_deg=truth.heading_error_deg,
            x_m=truth.x_m, y_m=truth.y_m, yaw_rad=truth.yaw_rad, invalid_pose=truth.invalid_pose, collided=truth.collided,
            obstacle_gap_m=truth.obstacle_gap_m, obstacle_present=present, tof_m=sensed.observation.ultrasonic_range_m,
        )
        self.path.append({"t_s": truth.t_s, "x_m": truth.x_m, "y_m": truth.y_m, "lane_offset_m": truth.lane_offset_m,
                          "speed_mps": truth.speed_mps, "mode": cmd.mode.name if cmd else None})
        self._k += 1
        if not truth.invalid_pose:
            self._take_obstacle_away(truth)
        return Outcome(fields, f"v {truth.speed_mps:.2f} m/s", truth.speed_mps, truth.invalid_pose, truth.t_s)

    def _take_obstacle_away(self, truth: Truth) -> None:
        """Once the robot has stood still ``remove_after_s`` in front of the obstacle, it is taken away."""
        if not self.world.has_obstacle:
            return
        still = truth.speed_mps <= STOPPED_SPEED_MPS and truth.t_s > 0.5
        self._standing_since = (self._standing_since if self._standing_since is not None else truth.t_s) if still else None
        if self._standing_since is not None and truth.t_s - self._standing_since >= self.o.remove_after_s:
            self.world.remove_obstacle()

    def close(self) -> None:
        self.world.close()


class Expert:
    """The simulator's ground-truth pure pursuit (lane centre ``EXPERT_LOOKAHEAD_M`` ahead) at cruise: the upper bound."""

    name = "expert"

    def __init__(self, world: DuckietownWorld, cruise_mps: float) -> None:
        self.world, self.cruise_mps = world, cruise_mps

    def decide(self, sensed: Sensed) -> Decision:
        action = curvature_action(self.cruise_mps, self.world.expert_curvature(EXPERT_LOOKAHEAD_M))
        return Decision(math.nan, self.cruise_mps, action=action)


def drive(options: DriveOptions, out_dir: str | Path | None = None,
          on_step: Callable[[int, int], None] | None = None) -> DriveResult:
    """Run one drive; with ``out_dir`` write its files there. A Ctrl-C stops cleanly with everything so far."""
    o = options
    out = Path(out_dir) if out_dir is not None else None
    if out is not None:
        out.mkdir(parents=True, exist_ok=True)
    world = DuckietownWorld(o.map_name, width_px=o.width_px, height_px=o.height_px, seed=o.seed, domain_rand=o.domain_rand,
                            start_tile=o.start_tile, render=o.controller != "expert" or o.video)
    camera = duckiebot_camera(o.width_px, o.height_px)
    lane = duckietown_lane() if o.lane == "preset" else GroundLaneSpec.for_camera(camera)
    limits = duckiebot_limits(time_of_flight=o.range_sensor == "tof")
    camera_lanes = HoughLaneSteering(camera=camera, fps=FRAME_RATE_HZ, ground=lane)
    rules = load_rules(o.rules if o.rules is not None else bundled_rules_path(RULES_FILE))
    route_length = world.route_m()  # (metres, a closed loop?)
    obstacle_xz = world.add_obstacle(o.obstacle, o.ahead_m) if o.obstacle is not None else None
    drive_world = DuckietownDrive(o, world, lane.aim_m)
    lanes = NavigatedSteering(camera_lanes, lambda: drive_world.route_now, limits.max_steering_deg) if o.route else camera_lanes
    guard = FearGuard(lanes, rules=rules, vehicle=limits, camera=camera) if o.controller == "guarded" else None
    controller: Controller
    if guard is not None:
        controller = Guarded(guard, o.cruise_mps)
    elif o.controller == "unguarded":
        controller = Unguarded("unguarded", lanes, lambda _s: o.cruise_mps, limits.max_steering_deg)
    else:
        controller = Expert(world, o.cruise_mps)
    recorder = Recorder(out, fps=FRAME_RATE_HZ, video=o.video, mcap=o.mcap)
    ran = run(drive_world, controller, recorder, on_frame=on_step, total=drive_world.total)
    summary = summarize_drive(drive_world.samples, world.dt_s)
    summary.update(route_completion(summary["progress_m"], *route_length))
    summary.update(
        map=o.map_name, controller=o.controller, seed=o.seed, options={**asdict(o), "start_tile": o.start_tile},
        obstacle_xz_m=obstacle_xz, interrupted=ran.interrupted, aim_distance_m=lane.aim_m,
        timing=_timing(list(ran.controller_ms) if o.controller != "expert" else [], drive_world.sim_ms),
        camera=asdict(camera), vehicle=asdict(limits), rules=rules.name,
    )
    if recorder.mcap_path is not None:
        summary["mcap"] = {"path": str(recorder.mcap_path), "frames": recorder.frames}
    title = f"fearguard in Duckietown: {o.map_name}, {o.controller}" + (f", {o.obstacle} {o.ahead_m:g} m ahead" if o.obstacle else "")
    stats = recorder.stats
    summary["supervisor"] = stats.to_json() if stats.supervised_frames else None
    summary = json_value(summary)
    recorder.write_summary(summary)
    if o.plots and out is not None and recorder.frames:
        if stats.supervised_frames:
            recorder.plot_timeline(title, with_speed=True, rules=guard.rules if guard is not None else None)
        plot_drive(drive_world.path, out / "drive.png", title)
    return DriveResult(summary, out, ran.interrupted, recorder.video_path)


def _cause(cmd: Command | None) -> str | None:
    if cmd is None:
        return None
    return cmd.cause.value if cmd.cause is not None else "fault"


def _timing(guard_ms: list[float], sim_ms: list[float]) -> dict[str, Any]:
    """Per-step cost (ms) of the controller and of the simulator step (physics + rendering), and the share."""
    sim = float(np.median(sim_ms)) if sim_ms else math.nan
    out: dict[str, Any] = {"simulator_ms_median": sim, "simulator_ms_mean": float(np.mean(sim_ms)) if sim_ms else math.nan}
    if guard_ms:
        g = float(np.median(guard_ms))
        out.update(controller_ms_median=g, controller_ms_mean=float(np.mean(guard_ms)),
                   controller_ms_p95=float(np.percentile(guard_ms, 95)), controller_share_of_simulator_step=g / sim if sim > 0 else None)
    return out


def plot_drive(records: list[dict[str, Any]], path: Path, title: str) -> Path:
    """The path on the map coloured by mode, and the lane offset with the tape edges (``records``: per step t_s, x_m,
    y_m, lane_offset_m, speed_mps, mode — kept by the world as it drives)."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    from fearguard.worlds.duckietown.preset import WHEEL_OUTER_HALF_TRACK_M as W
    from fearguard.worlds.duckietown.preset import WHITE_INNER_M, WHITE_OUTER_M, YELLOW_INNER_M, YELLOW_OUTER_M

    colours = {"NORMAL": "tab:green", "CAUTION": "tab:orange", "EMERGENCY": "tab:red", None: "tab:blue"}
    fig, (ax0, ax1) = plt.subplots(1, 2, figsize=(13, 5.5), gridspec_kw={"width_ratios": [1, 1.6]})
    x = [r["x_m"] for r in records]
    y = [r["y_m"] for r in records]
    c = [colours.get(r.get("mode"), "tab:blue") for r in records]
    ax0.scatter(x, y, c=c, s=4)
    ax0.plot(x[:1], y[:1], "k^", label="start")
    ax0.set_aspect("equal")
    ax0.set_xlabel("x [m]")
    ax0.set_ylabel("y [m]")
    ax0.set_title("path: green NORMAL, orange CAUTION, red EMERGENCY\n(blue: no supervisor)", fontsize=9)
    t = [r["t_s"] for r in records]
    d = [math.nan if r.get("lane_offset_m") is None else r["lane_offset_m"] for r in records]
    ax1.plot(t, d, color="black", label="lane offset (+ right)")
    for value, colour, label in ((WHITE_OUTER_M - W, "red", "wheel off the road"), (WHITE_INNER_M - W, "grey", "wheel on the white tape"),
                                 (YELLOW_INNER_M + W, "goldenrod", "wheel on the yellow line"),
                                 (YELLOW_OUTER_M + W, "darkred", "wheel in the other lane")):
        ax1.axhline(value, color=colour, linestyle="--", linewidth=1, label=label)
    ax1.set_xlabel("t [s]")
    ax1.set_ylabel("lane offset [m]")
    ax1.legend(loc="upper right", fontsize=8)
    ax2 = ax1.twinx()
    ax2.plot(t, [r["speed_mps"] for r in records], color="tab:blue", alpha=0.5)
    ax2.set_ylabel("speed [m/s]", color="tab:blue")
    fig.suptitle(title)
    fig.tight_layout()
    fig.savefig(path, dpi=90)
    plt.close(fig)
    return path


def with_controller(options: DriveOptions, controller: str) -> DriveOptions:
    """The same drive with another controller (the baselines of a suite row)."""
    return replace(options, controller=controller)
