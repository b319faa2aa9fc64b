"""One closed-loop drive in MetaDrive: the car's camera → fearguard → the car, measured by the simulator's truth.

The one driver loop drives it (``drive.loop.run``): ``MetaDriveWorld`` is the world, the controller one of
- ``guarded``: ``FearGuard(HoughLaneSteering(camera, aim_m=AIM_M))`` (aiming 9 m ahead: ``preset.AIM_M``) with the
  road-car rules and MetaDrive's car limits; the car
  drives min(cruise, speed limit) along the pure-pursuit arc to the commanded aim-point bearing (``drive.controllers``);
- ``unguarded``: the same lane steering alone at cruise (a fault keeps the last angle);
- ``expert``: MetaDrive's own IDM policy (lane keeping on the map's lanes, car following, lane changes) at the same
  cruise: the upper bound (``Expert`` below, beside the world as Duckietown's is); it does not need the camera, which
  is then not rendered (unless a video is asked for).
Outputs: log.jsonl (one flushed line per step), summary.json, timeline.png (guarded), annotated.mp4 with ``video``,
run.mcap with ``mcap``.
"""

from __future__ import annotations

import math
import time
from collections.abc import Callable
from dataclasses import asdict, dataclass, fields
from pathlib import Path
from typing import Any

import numpy as np

from fearguard.drive.controllers import Guarded, Unguarded
from fearguard.drive.interrupt import StopSignal
from fearguard.drive.loop import run
from fearguard.drive.world import Controller, Decision, Sensed
from fearguard.fuzzy.loader import bundled_rules_path, load_rules
from fearguard.outputs.recorder import Recorder
from fearguard.outputs.report import json_value
from fearguard.perception import FrameSteering
from fearguard.supervisor import FearGuard
from fearguard.vision.lane_steering import HoughLaneSteering
from fearguard.vision.navigated import NavigatedSteering
from fearguard.worlds.metadrive.metrics import stopped_car_outcome, summarize_drive, supervisor_times
from fearguard.worlds.metadrive.preset import AIM_M, CAR_LENGTH_M, CRUISE_MPS, STEP_S, metadrive_limits
from fearguard.worlds.metadrive.world import DEFAULT_MAP, MetaDriveWorld, Scenario, require_positive

CONTROLLERS = ("guarded", "unguarded", "expert")
RULES_FILE = "road_car.toml"


@dataclass(frozen=True)
class DriveOptions:
    """One drive; every field has the default a plain ``fearguard metadrive --out DIR`` uses."""

    map_blocks: str = DEFAULT_MAP
    lanes: int = 3
    traffic_density: float = 0.05
    lighting: str = "day"
    seed: int = 0
    seconds: float = 30.0
    controller: str = "guarded"
    cruise_mps: float = CRUISE_MPS
    range_sensor: str = "none"
    route: bool = True  # the navigation's route steering in every observation (policy.route follows it where the markings end)
    lead: str | None = None
    lead_ahead_m: float = 35.0
    lead_speed_mps: float = 5.0
    width_px: int = 320
    height_px: int = 240
    rules: str | None = None  # default: the bundled road-car rules
    video: bool = False
    plots: bool = True
    mcap: bool = False  # run.mcap for Foxglove (outputs/mcap.py; the ros extra)

    def __post_init__(self) -> None:
        if self.controller not in CONTROLLERS:
            raise ValueError(f"controller {self.controller!r}: choose one of {', '.join(CONTROLLERS)}")
        require_positive(self, ("seconds", "cruise_mps"))
        self.scenario()  # the world's own checks (map letters, lighting, lead, lanes, density, camera size)

    def scenario(self) -> Scenario:
        """The world this drive opens (the expert skips the camera unless a video is asked for)."""
        names = {f.name for f in fields(Scenario)} & {f.name for f in fields(self)}
        return Scenario(**{n: getattr(self, n) for n in names}, render=self.controller != "expert" or self.video)


@dataclass(frozen=True)
class DriveResult:
    summary: dict[str, Any]
    out_dir: Path | None
    interrupted: bool
    video_path: Path | None = None


class Expert:
    """MetaDrive's own IDM policy at cruise (its lanes from the map, not from the camera): the upper bound."""

    name = "expert"

    def __init__(self, world: MetaDriveWorld, cruise_mps: float) -> None:
        self.world, self.cruise_mps = world, cruise_mps

    def decide(self, sensed: Sensed) -> Decision:
        action = self.world.expert_action(self.cruise_mps)
        return Decision(math.nan, self.cruise_mps, action=action)  # no aim-point bearing: the log's steer is its own


def controller_for(options: DriveOptions, world: MetaDriveWorld, guard: FearGuard | None, lanes: FrameSteering,
                   max_steering_deg: float) -> Controller:
    """The drive's controller: fearguard, the lane steering alone, or MetaDrive's expert."""
    if guard is not None:
        return Guarded(guard, options.cruise_mps)
    if options.controller == "unguarded":
        cruise = options.cruise_mps
        return Unguarded("unguarded", lanes, lambda _s: cruise, max_steering_deg)
    return Expert(world, options.cruise_mps)


def drive(options: DriveOptions, out_dir: str | Path | None = None, on_step: Callable[[int, int | None], None] | None = None,
          stop: StopSignal | None = None) -> DriveResult:
    """Run one drive; with ``out_dir`` write its files there. Ctrl-C (or ``stop``) ends it cleanly with everything so far."""
    o = options
    out = Path(out_dir) if out_dir is not None else None
    if out is not None:
        out.mkdir(parents=True, exist_ok=True)
    began = time.perf_counter()
    world = MetaDriveWorld(o.scenario(), seconds=o.seconds, aim_m=AIM_M)
    open_s = time.perf_counter() - began
    limits = metadrive_limits(radar=o.range_sensor == "radar", aim_m=world.aim_m)
    camera_lanes = HoughLaneSteering(camera=world.camera, fps=world.fps, aim_m=AIM_M)
    lanes = NavigatedSteering(camera_lanes, lambda: world.route_now, limits.max_steering_deg) if o.route else camera_lanes
    rules = load_rules(o.rules if o.rules is not None else bundled_rules_path(RULES_FILE))
    guard = FearGuard(lanes, rules=rules, vehicle=limits, camera=world.camera) if o.controller == "guarded" else None
    controller = controller_for(o, world, guard, lanes, limits.max_steering_deg)
    recorder = Recorder(out, fps=world.fps, video=o.video, mcap=o.mcap)
    start = world.start
    ran = run(world, controller, recorder, stop=stop, on_frame=on_step, total=world.total)
    summary = summarize_drive(world.samples, STEP_S, start.route_m)
    stats = recorder.stats
    summary.update(supervisor_times(stats, summary["duration_s"]), fear_mean=stats.fear_mean, fear_max=stats.fear_max)
    if o.lead == "stopped":
        summary["stopped_car"] = stopped_car_outcome(world.samples, start.progress_m + o.lead_ahead_m + CAR_LENGTH_M)
    summary.update(
        map=o.map_blocks, controller=o.controller, seed=o.seed, lighting=o.lighting, options=asdict(o), interrupted=ran.interrupted,
        end_reason=world.end_reason, aim_distance_m=world.aim_m, open_s=open_s,
        timing=_timing(list(ran.controller_ms) if o.controller != "expert" else [], world.sim_ms),
        camera=asdict(world.camera), vehicle=asdict(limits), rules=rules.name,
    )
    if recorder.mcap_path is not None:
        summary["mcap"] = {"path": str(recorder.mcap_path), "frames": recorder.frames}
    summary["supervisor"] = stats.to_json() if stats.supervised_frames else None
    summary = json_value(summary)
    recorder.write_summary(summary)
    if o.plots and out is not None and stats.supervised_frames:
        title = f"fearguard in MetaDrive: {o.map_blocks}, seed {o.seed}, {o.lighting}, {o.controller}"
        recorder.plot_timeline(title, with_speed=True, rules=rules)
    return DriveResult(summary, out, ran.interrupted, recorder.video_path)


def _timing(guard_ms: list[float], sim_ms: list[float]) -> dict[str, Any]:
    """Per-step cost (ms: median, p95) of fearguard (perception + supervisor) and of the simulator step (physics +
    rendering), and fearguard's share of a simulator step (medians)."""
    quantiles = {name: np.percentile(values, (50, 95)).tolist() for name, values in (("controller", guard_ms), ("simulator", sim_ms))
                 if values}
    out: dict[str, Any] = {f"{name}_ms_{q}": value for name, (m, p) in quantiles.items() for q, value in (("median", m), ("p95", p))}
    if "controller" in quantiles and "simulator" in quantiles:
        out["controller_share_of_simulator_step"] = quantiles["controller"][0] / quantiles["simulator"][0]
    return out

