"""Replay a recorded drive open loop: the recording's motion is fixed; fearguard says where and why it would slow.

Frames (video, image folder or Donkey tub) and an optional sensor log aligned by time go through the
wrapped steering estimator (HoughLaneSteering, or the caller's) and the supervisor, frame by frame. Outputs in the
out folder, through ``recorder.Recorder``: ``log.jsonl`` (one flushed line per frame), ``summary.json``,
``timeline.png`` and, if asked, the annotated video (``annotated.mp4``; ``annotated.avi`` without PyAV).
Sensors are what the recording has: the car has an ultrasonic when the sensor log has a range or echo
column (unless ``no_ultrasonic``), QR localisation when asked.

A Donkey tub records only while the car drives (Donkey's ``AUTO_RECORD_ON_THROTTLE``, on by default: no record while
the throttle is 0), so a gap in its clock longer than the supervisor's watchdog allows is a **pause**, not a stalled
camera: the car stood while nothing was recorded. The supervisor starts afresh at the frame after it (as a car that
has been standing), the log gives that frame ``resumed_after_s`` and the summary lists the pauses. Live, the Donkey
part sees every frame of the loop and its watchdog stays the judge of stalls; in a bag or a video a gap is a stall.
"""

from __future__ import annotations

import math
import time
from collections.abc import Callable, Iterator
from dataclasses import dataclass, field, replace
from pathlib import Path
from typing import Any

from fearguard.camera import CameraModel, load_camera
from fearguard.drive.controllers import Guarded
from fearguard.drive.interrupt import StopSignal
from fearguard.drive.loop import run
from fearguard.drive.world import Decision, Outcome, Sensed
from fearguard.fuzzy.loader import load_rules
from fearguard.observation import LeadBox, Observation
from fearguard.outputs.recorder import CommandStats, Recorder
from fearguard.outputs.report import json_value
from fearguard.policy.speed import watchdog_s
from fearguard.replay.bags import BagSource, BagTopics
from fearguard.replay.eyes import EyesCheck
from fearguard.replay.pitch import PitchCheck
from fearguard.replay.read_ahead import read_ahead, usable_cores
from fearguard.replay.recordings import open_recording
from fearguard.replay.sensor_log import Readings, load_sensor_log
from fearguard.replay.sources import Frame, SourceError, parse_position
from fearguard.supervisor import FearGuard
from fearguard.track.profile import load_track
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
    vehicle: VehicleLimits = field(default_factory=VehicleLimits)  # its range sensor and QR are what the recording has (below)
    steer: Callable[[Any], float] | None = None  # the wrapped steering function, frame -> degrees (None: HoughLaneSteering)
    read_ahead: bool | None = None  # decode the next frames on another core (read_ahead.py); None: when there is one
    mcap: bool = False  # also write run.mcap for Foxglove (outputs/mcap.py)
    topics: BagTopics = field(default_factory=BagTopics)  # a ROS bag's topics (replay/bags.py); None fields: picked
    track: str | None = None  # a track profile from `fearguard learn` (None: no familiarity cue)
    markings: str | None = None  # the built-in lane model's markings (lane.MARKINGS); None: the track profile's, else light
    guidance: str | None = None  # ... and the track's guidance (lane.GUIDANCE); None: the track profile's, else two lines


@dataclass(frozen=True)
class ReplayResult:
    summary: dict[str, Any]  # summary.json as written
    out_dir: Path
    interrupted: bool
    stats: CommandStats | None = None  # the supervisor's commands over the replay, typed
    video_path: Path | None = None
    stopped_by: str | None = None


def replay(source_path: str | Path, out_dir: str | Path, options: ReplayOptions = ReplayOptions(),
           on_frame: Callable[[int, int | None], None] | None = None, stop: StopSignal | None = None) -> ReplayResult:
    """Run the supervisor over a recording; files in out_dir.

    ``stop`` (``interrupt.stop_on_signals``) or a KeyboardInterrupt ends the replay after the current
    frame, with everything written so far and a summary that says ``interrupted``.
    """
    if not (isinstance(options.every, int) and options.every >= 1):
        raise SourceError(str(source_path), "every", f"must be a whole number >= 1, got {options.every!r}")
    out = Path(out_dir)
    out.mkdir(parents=True, exist_ok=True)
    source = open_recording(source_path, options.fps, options.topics)
    log_data: Readings | None = load_sensor_log(options.sensor_log, options.strict) if options.sensor_log else source.sensors
    camera: CameraModel | None = load_camera(options.camera) if options.camera else None
    has_us = log_data is not None and not options.no_ultrasonic and bool({"ultrasonic_range_m", "echo_s"} & set(log_data.columns))
    vehicle = replace(options.vehicle, has_ultrasonic=has_us, has_qr_localisation=options.qr_localisation)
    track = load_track(options.track) if options.track else None
    if (options.markings is not None or options.guidance is not None) and options.steer is not None:
        raise ValueError("markings and guidance are the built-in lane model's; your own steering finds its own")
    markings = options.markings or (track.markings if track is not None else "light")
    guidance = options.guidance or (track.guidance if track is not None else "two_lines")
    steer = options.steer if options.steer is not None else HoughLaneSteering(camera=camera, fps=source.fps, markings=markings,
                                                                              guidance=guidance)
    guard = FearGuard(steer, rules=load_rules(options.rules), vehicle=vehicle, camera=camera, track=track)
    start = parse_position(options.start, source.fps) if options.start else 0
    stop_at = parse_position(options.stop, source.fps) if options.stop else None
    _check_span(source_path, source.expected_frames, source.fps, start, stop_at, options)
    expected = _expected(source.expected_frames, start, stop_at, options.every)
    frames = source.iter_frames(start, stop_at, options.every)
    ahead = options.read_ahead if options.read_ahead is not None else usable_cores() > 1
    pitch = PitchCheck(camera)
    eyes = EyesCheck(guard.rules.policy.recovery_min_confidence, camera=camera is not None, track=track is not None,
                     markings=markings if options.steer is None else "custom")
    pause_s = watchdog_s(options.every / source.fps, guard.rules.policy) if source.kind == "tub" else None
    world = RecordingWorld(read_ahead(frames) if ahead else frames, source.fps / options.every, log_data, options.speed_mps, pitch,
                           pause_s, eyes)
    began = time.perf_counter()
    recorder = Recorder(out, fps=world.fps, video=options.video, mcap=options.mcap)
    ran = run(world, Guarded(guard), recorder, stop=stop, on_frame=on_frame, total=expected)  # closing the world stops the reader
    interrupted = ran.interrupted
    elapsed = time.perf_counter() - began
    done = recorder.frames
    stats = recorder.stats
    summary = stats.to_json()
    summary.update(
        source=str(source_path), kind=source.kind, fps=source.fps, expected_frames=source.expected_frames,
        selected_frames=expected, processed_frames=done, processing_fps=done / elapsed if elapsed > 0 else None, interrupted=interrupted,
        skipped=[{"frame": s.index, "reason": s.reason} for s in source.skipped], stopped_early=source.stopped_early,
        recording_pauses=[{"frame": index, "paused_s": gap} for index, gap in world.pauses],
        source_notes=list(source.notes), log_field_units=dict(source.log_field_units),
        vehicle={"has_ultrasonic": has_us, "has_qr_localisation": options.qr_localisation},
        sensor_log_issues=[{"line": i.line, "problem": i.problem} for i in log_data.issues] if log_data else [],
    )
    if stop:
        summary["stopped_by"] = stop.name
    if recorder.video_path is not None:
        summary["video"] = {"path": str(recorder.video_path), "frames": done, "rescaled_frames": recorder.video_frames_rescaled}
    if recorder.mcap_path is not None:
        summary["mcap"] = {"path": str(recorder.mcap_path), "frames": done}
    summary["pitch_check"] = pitch.finish().to_json()
    summary["eyes_check"] = eyes.finish().to_json()
    if isinstance(source, BagSource):
        summary["bag_topics"] = dict(source.topics_used)
    summary = json_value(summary)
    recorder.write_summary(summary)
    if options.plots and not stop:
        recorder.plot_timeline(title=f"fearguard replay: {Path(source_path).name}", rules=guard.rules)
    if stop and not interrupted:  # every frame was replayed; the signal came while the files were written
        interrupted = True
        summary.update(interrupted=True, stopped_by=stop.name)
        recorder.write_summary(summary)
    return ReplayResult(summary, out, interrupted, stats, recorder.video_path, stop.name if stop else None)


def _check_span(path: str | Path, total: int | None, fps: float, start: int, stop: int | None, options: ReplayOptions) -> None:
    """``--from`` inside the recording (when its length is known), ``--to`` after ``--from``; a speed that is a speed."""
    if total is not None and start >= total:
        raise SourceError(str(path), "--from", f"{options.start!r} is frame {start}, but the recording has {total} frames "
                                               f"({total / fps:.1f} s at {fps:g} fps): start inside it")
    if stop is not None and stop <= start:
        raise SourceError(str(path), "--to", f"{options.stop!r} (frame {stop}) is not after --from (frame {start})")
    speed = options.speed_mps
    if speed is not None and not (isinstance(speed, int | float) and not isinstance(speed, bool) and 0.0 <= speed < math.inf):
        raise SourceError(str(path), "--speed-mps", f"must be a finite speed >= 0, got {speed!r}")


def _expected(total: int | None, start: int, stop: int | None, every: int) -> int | None:
    end = stop if stop is not None else total
    return None if end is None else max(0, math.ceil((min(end, total or end) - start) / every))


class RecordingWorld:
    """A recording as a ``World``: its frames with the sensor readings of their times (a sensor log, or a bag's own
    topics); ``act`` moves nothing (open loop: the recording's motion is fixed) but checks the camera's pitch against
    the lane lines and counts how much of the lane the camera saw (``eyes``). ``pause_s``: a gap longer than this
    between frames is a pause of the recording (``pauses``: frame, seconds), the next frame ``Sensed.resumed_after_s``;
    None: every gap is the car's own (a stall, if long). Closing it stops the reader and closes the source."""

    def __init__(self, frames: Iterator[Frame], fps: float, log: Readings | None, speed_mps: float | None,
                 pitch: PitchCheck | None = None, pause_s: float | None = None, eyes: EyesCheck | None = None) -> None:
        self.frames, self.fps, self.log, self.speed_mps, self.pitch, self.pause_s = frames, fps, log, speed_mps, pitch, pause_s
        self.eyes = eyes
        self.pauses: list[tuple[int, float]] = []
        self._frame: Frame | None = None
        self._last_t_s: float | None = None

    def sense(self) -> Sensed | None:
        frame = self._frame = next(self.frames, None)
        if frame is None:
            return None
        gap = frame.t_s - self._last_t_s if self._last_t_s is not None else 0.0
        self._last_t_s = frame.t_s
        resumed = gap if self.pause_s is not None and gap > self.pause_s else None
        if resumed is not None:
            self.pauses.append((frame.index, resumed))
        obs = _observation(frame.t_s, frame.image_bgr, self.log, self.speed_mps)
        return Sensed(frame.index, frame.t_s, obs, frame.image_bgr, resumed)

    def act(self, sensed: Sensed, decision: Decision) -> Outcome:
        frame = self._frame
        assert frame is not None  # act follows the sense that read it
        if self.pitch is not None:
            self.pitch.add(frame.t_s, decision.analysis, (frame.image_bgr.shape[1], frame.image_bgr.shape[0]))
        if self.eyes is not None:
            self.eyes.add(decision.command)
        resumed = {} if sensed.resumed_after_s is None else {"resumed_after_s": sensed.resumed_after_s}
        return Outcome({"source_frame": frame.source_frame, **resumed, **frame.log_fields}, f"t {sensed.t_s:.1f} s",
                       stamp_ns=frame.stamp_ns)

    def close(self) -> None:
        close = getattr(self.frames, "close", None)
        if close is not None:
            close()


def _observation(t_s: float, image: Any, log: Readings | None, speed_mps: float | None) -> Observation:
    """The Observation for one frame: the frame, and the sensor-log row valid at its time."""
    if log is None:
        return Observation(t_s, speed_mps if speed_mps is not None else math.nan, image)
    s = log.at(t_s)
    speed = s.speed_mps if s.speed_mps is not None else (speed_mps if speed_mps is not None else math.nan)
    box = s.lead_box_px()
    lead = LeadBox(*box) if box is not None else None
    return Observation(t_s, speed, image, None, s.ultrasonic_range_m, s.odometer_m, s.qr_payload, lead, s.echo_s)
