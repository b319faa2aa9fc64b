"""Replay a recorded drive open loop: the recording's motion is fixed; fearguard says where and why it would slow.

Frames (video, image folder or Donkey tub) and an optional sensor log aligned by time go through the
wrapped steering estimator (HoughLaneSteering) and the supervisor, frame by frame. Outputs in the
out folder: ``log.jsonl`` (one flushed line per frame), ``summary.json``, ``timeline.png`` and, if
asked, ``annotated.mp4``. Sensors are what the recording has: the car has an ultrasonic when the
sensor log has a range or echo column (unless ``no_ultrasonic``), QR localisation when asked.
"""

from __future__ import annotations

import json
import math
import time
from collections.abc import Callable
from dataclasses import dataclass, field, replace
from pathlib import Path
from typing import Any

from fearguard.camera import CameraModel, load_camera
from fearguard.fuzzy.loader import load_rules
from fearguard.observation import LeadBox, Observation
from fearguard.overlay import VideoOut, annotate
from fearguard.replay.sensor_log import SensorLog, load_sensor_log
from fearguard.replay.sources import open_source, parse_position
from fearguard.report import JsonlLog, command_record, json_value, plot_timeline, read_jsonl, summarize
from fearguard.supervisor import FearGuard
from fearguard.vehicle import VehicleLimits
from fearguard.vision.lane_steering import HoughLaneSteering


@dataclass(frozen=True)
class ReplayOptions:
    """What to replay and how; every field has the default a plain ``fearguard replay VIDEO --out DIR`` uses."""

    rules: str | None = None
    camera: str | None = None
    sensor_log: str | None = None
    strict: bool = False
    no_ultrasonic: bool = False
    qr_localisation: bool = False
    speed_mps: float | None = None  # the recording's speed when no log gives it (None: unknown, counted as max speed)
    fps: float | None = None
    start: str | None = None
    stop: str | None = None
    every: int = 1
    video: bool = False
    plots: bool = True
    vehicle: VehicleLimits = field(default_factory=VehicleLimits)


@dataclass(frozen=True)
class ReplayResult:
    summary: dict[str, Any]
    out_dir: Path
    interrupted: bool


def replay(source_path: str | Path, out_dir: str | Path, options: ReplayOptions = ReplayOptions(),
           on_frame: Callable[[int, int | None], None] | None = None) -> ReplayResult:
    """Run the supervisor over a recording; files in out_dir; a Ctrl-C stops cleanly with everything written so far."""
    out = Path(out_dir)
    out.mkdir(parents=True, exist_ok=True)
    source = open_source(source_path, options.fps)
    log_data: SensorLog | None = load_sensor_log(options.sensor_log, options.strict) if options.sensor_log else None
    camera: CameraModel | None = load_camera(options.camera) if options.camera else None
    has_us = log_data is not None and not options.no_ultrasonic and bool({"ultrasonic_range_m", "echo_s"} & set(log_data.columns))
    vehicle = replace(options.vehicle, has_ultrasonic=has_us, has_qr_localisation=options.qr_localisation)
    steer = HoughLaneSteering(camera=camera, fps=source.fps)
    guard = FearGuard(steer, rules=load_rules(options.rules), vehicle=vehicle, camera=camera)
    start = parse_position(options.start, source.fps) if options.start else 0
    stop = parse_position(options.stop, source.fps) if options.stop else None
    video = VideoOut(str(out / "annotated.mp4"), source.fps / options.every) if options.video else None
    expected = _expected(source.expected_frames, start, stop, options.every)
    log = JsonlLog(out / "log.jsonl")
    interrupted, done, began = False, 0, time.perf_counter()
    try:
        for frame in source.iter_frames(start, stop, options.every):
            obs = _observation(frame.t_s, frame.image_bgr, log_data, options.speed_mps)
            cmd = guard.step(obs)
            extra: dict[str, Any] = {}
            if "user/angle" in frame.record:
                extra["recorded_angle"] = frame.record.get("user/angle")
                extra["recorded_throttle"] = frame.record.get("user/throttle")
            log.write(command_record(frame.index, frame.t_s, cmd, **extra))
            if video is not None:
                analysis = cmd.perceived.analysis if cmd.perceived is not None else None
                video.write(annotate(frame.image_bgr, cmd, analysis, f"t {frame.t_s:.1f} s"))
            done += 1
            if on_frame is not None:
                on_frame(done, expected)
    except KeyboardInterrupt:
        interrupted = True
    finally:
        log.close()
        if video is not None:
            video.close()
    elapsed = time.perf_counter() - began
    records = read_jsonl(out / "log.jsonl")
    summary = summarize(records)
    summary.update(
        source=str(source_path), kind=source.kind, fps=source.fps, expected_frames=source.expected_frames,
        processed_frames=done, processing_fps=done / elapsed if elapsed > 0 else None, interrupted=interrupted,
        skipped=[{"frame": s.index, "reason": s.reason} for s in source.skipped], stopped_early=source.stopped_early,
        source_notes=list(source.notes), vehicle={"has_ultrasonic": has_us, "has_qr_localisation": options.qr_localisation},
        sensor_log_issues=[{"line": i.line, "problem": i.problem} for i in log_data.issues] if log_data else [],
    )
    summary = json_value(summary)
    (out / "summary.json").write_text(json.dumps(summary, indent=2, allow_nan=False) + "\n", encoding="utf-8")
    if options.plots and records:
        plot_timeline(records, out / "timeline.png", title=f"fearguard replay: {Path(source_path).name}")
    return ReplayResult(summary, out, interrupted)


def _expected(total: int | None, start: int, stop: int | None, every: int) -> int | None:
    end = stop if stop is not None else total
    return None if end is None else max(0, math.ceil((min(end, total or end) - start) / every))


def _observation(t_s: float, image: Any, log: SensorLog | None, speed_mps: float | None) -> Observation:
    """The Observation for one frame: the frame, and the sensor-log row valid at its time."""
    if log is None:
        return Observation(t_s, speed_mps if speed_mps is not None else math.nan, image)
    s = log.at(t_s)
    speed = s.speed_mps if s.speed_mps is not None else (speed_mps if speed_mps is not None else math.nan)
    box = s.lead_box_px()
    lead = LeadBox(*box) if box is not None else None
    return Observation(t_s, speed, image, None, s.ultrasonic_range_m, s.odometer_m, s.qr_payload, lead, s.echo_s)
