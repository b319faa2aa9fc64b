"""One closed-loop drive in MetaDrive: the car's camera → fearguard → the car, measured by the simulator's truth.

Temporary: the one-loop refactor (issue 32) replaces this loop by its ``run(world, controller, recorder, stop)``;
the loop body stays thin and ``MetaDriveWorld`` does the work (sense, act, truth).

Controllers:
- ``guarded``: ``FearGuard(HoughLaneSteering(camera))`` with the road-car rules and MetaDrive's car limits; the car
  drives min(cruise, speed limit) along the pure-pursuit arc to the commanded aim-point bearing;
- ``unguarded``: the same lane steering alone at cruise (a fault keeps the last angle);
- ``expert``: MetaDrive's own IDM policy (its lane keeping on the map's lanes, car following, lane changes) at the same
  cruise: the upper bound; it does not need the camera, which is then not rendered (unless a video is asked for).
Outputs: log.jsonl (one flushed line per step), summary.json, timeline.png (guarded), annotated.mp4 with ``video``.
"""

from __future__ import annotations

import math
import time
from collections.abc import Callable
from dataclasses import asdict, dataclass, fields
from pathlib import Path
from typing import Any

import numpy as np

from fearguard.fuzzy.loader import bundled_rules_path, load_rules
from fearguard.interrupt import StopSignal
from fearguard.recorder import Recorder
from fearguard.report import json_value
from fearguard.sim.loop import _unsupervised_steering
from fearguard.supervisor import Command, FearGuard
from fearguard.vision.lane_steering import HoughLaneSteering
from fearguard.worlds.metadrive.metrics import Sample, stopped_car_outcome, summarize_drive, supervisor_times
from fearguard.worlds.metadrive.preset import CAR_LENGTH_M, CRUISE_MPS, STEP_S, metadrive_limits
from fearguard.worlds.metadrive.world import DEFAULT_MAP, MetaDriveWorld, Scenario, Truth, require_positive

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
    lead: str | None = None
    lead_ahead_m: float = 60.0
    lead_speed_mps: float = 5.0
    width_px: int = 320
    height_px: int = 240
    rules: str | None = None  # default: the bundled road-car rules
    video: bool = False
    plots: bool = True

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


def drive(options: DriveOptions, out_dir: str | Path | None = None, on_step: Callable[[int, int], None] | None = None,
          stop: StopSignal | None = None) -> DriveResult:
    """Run one drive; with ``out_dir`` write its files there. Ctrl-C (or ``stop``) ends it cleanly with everything so far."""
    o = options
    out = Path(out_dir) if out_dir is not None else None
    if out is not None:
        out.mkdir(parents=True, exist_ok=True)
    began = time.perf_counter()
    world = MetaDriveWorld(o.scenario())
    open_s = time.perf_counter() - began
    limits = metadrive_limits(radar=o.range_sensor == "radar")
    lanes = HoughLaneSteering(camera=world.camera, fps=world.fps)
    rules = load_rules(o.rules if o.rules is not None else bundled_rules_path(RULES_FILE))
    guard = FearGuard(lanes, rules=rules, vehicle=limits, camera=world.camera) if o.controller == "guarded" else None
    recorder = Recorder(out, fps=world.fps, video=o.video)
    total = math.ceil(o.seconds * world.fps)
    samples: list[Sample] = []
    guard_ms: list[float] = []
    sim_ms: list[float] = []
    start = world.truth()
    lead_at_m = start.progress_m + o.lead_ahead_m + CAR_LENGTH_M if o.lead == "stopped" else None
    last_steer, interrupted = 0.0, False
    try:
        for k in range(total):
            obs, image, _ = world.sense()
            cmd: Command | None = None
            t0 = time.perf_counter()
            if guard is not None:
                cmd = guard.step(obs)
                steering, speed = cmd.steering_deg, min(o.cruise_mps, cmd.speed_limit_mps)
            elif o.controller == "unguarded":
                steering, _ = _unsupervised_steering(lanes, image, last_steer, limits.max_steering_deg)
                speed = o.cruise_mps
            else:
                steering, speed = math.nan, o.cruise_mps
            t1 = time.perf_counter()
            action = world.act(steering, speed) if o.controller != "expert" else world.act_expert(speed)
            sim_ms.append(1e3 * (time.perf_counter() - t1))
            if o.controller != "expert":
                guard_ms.append(1e3 * (t1 - t0))
            last_steer = steering
            truth = world.truth()
            samples.append(_sample(truth))
            analysis = cmd.perceived.analysis if cmd is not None and cmd.perceived is not None else None
            recorder.frame(k, obs.t_s, cmd, image=image if o.controller != "expert" or o.video else None, analysis=analysis,
                           caption=f"v {truth.speed_mps:.1f} m/s", speed_mps=truth.speed_mps,
                           fields=_fields(o.controller, steering, speed, action, truth))
            if on_step is not None:
                on_step(k + 1, total)
            if world.done or (stop is not None and stop):
                interrupted = interrupted or bool(stop)
                break
    except KeyboardInterrupt:
        interrupted = True
    finally:
        recorder.close()
        end_reason = world.end_reason
        world.close()
    summary = summarize_drive(samples, STEP_S, start.route_m)
    stats = recorder.stats
    summary.update(supervisor_times(stats, summary["duration_s"]), fear_mean=stats.fear_mean, fear_max=stats.fear_max)
    if lead_at_m is not None:
        summary["stopped_car"] = stopped_car_outcome(samples, lead_at_m)
    summary.update(
        map=o.map_blocks, controller=o.controller, seed=o.seed, lighting=o.lighting, options=asdict(o), interrupted=interrupted,
        end_reason=end_reason, aim_distance_m=world.aim_m, open_s=open_s, timing=_timing(guard_ms, sim_ms),
        camera=asdict(world.camera), vehicle=asdict(limits), rules=rules.name,
    )
    summary["supervisor"] = stats.to_json() if stats.supervised_frames else None
    summary = json_value(summary)
    recorder.write_summary(summary)
    if o.plots and out is not None and stats.supervised_frames:
        title = f"fearguard in MetaDrive: {o.map_blocks}, seed {o.seed}, {o.lighting}, {o.controller}"
        recorder.plot_timeline(title, with_speed=True, rules=rules)
    return DriveResult(summary, out, interrupted, recorder.video_path)


def _sample(truth: Truth) -> Sample:
    return Sample(truth.t_s, truth.speed_mps, truth.lane_offset_m, truth.on_solid_line, truth.out_of_road, truth.crashed_vehicle,
                  truth.crashed_object, truth.crashed_other, truth.progress_m, truth.gap_m, truth.ttc_s)


def _fields(controller: str, steering: float, speed: float, action: Any, t: Truth) -> dict[str, Any]:
    """The log line's world fields: what was applied and the truth after it."""
    return dict(
        controller=controller, speed_target_mps=speed, applied_steering_deg=steering, steer=action.steer, throttle=action.throttle,
        speed_mps=t.speed_mps, progress_m=t.progress_m, route_completion=t.route_completion, lane_offset_m=t.lane_offset_m,
        heading_error_deg=t.heading_error_deg, lane_index=t.lane_index, x_m=t.x_m, y_m=t.y_m, out_of_road=t.out_of_road,
        on_solid_line=t.on_solid_line, crashed_vehicle=t.crashed_vehicle, crashed_object=t.crashed_object, gap_m=t.gap_m,
        lead_speed_mps=t.lead_speed_mps, ttc_s=t.ttc_s,
    )


def _timing(guard_ms: list[float], sim_ms: list[float]) -> dict[str, Any]:
    """Per-step cost (ms: median, p95) of fearguard (perception + supervisor) and of the simulator step (physics +
    rendering), and fearguard's share of a simulator step (medians)."""
    quantiles = {name: np.percentile(values, (50, 95)).tolist() for name, values in (("controller", guard_ms), ("simulator", sim_ms))
                 if values}
    out: dict[str, Any] = {f"{name}_ms_{q}": value for name, (m, p) in quantiles.items() for q, value in (("median", m), ("p95", p))}
    if "controller" in quantiles and "simulator" in quantiles:
        out["controller_share_of_simulator_step"] = quantiles["controller"][0] / quantiles["simulator"][0]
    return out
