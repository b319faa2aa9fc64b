"""One recorder for every driver: what a run leaves behind, written as it goes.

A driver is anything that produces frames and asks the supervisor: ``fearguard replay`` (recordings),
the built-in closed loop (``sim/loop.py``), or a third-party world such as gym-duckietown. Each uses
only this API::

    from fearguard.outputs.recorder import Recorder

    with Recorder(out_dir, fps=20.0, video=True) as rec:         # opens log.jsonl now, the video on frame 1
        for k, obs in enumerate(world):
            cmd = guard.step(obs)                                 # None for a run without a supervisor
            rec.frame(k, obs.t_s, cmd, image=obs.frame_bgr,       # image: only needed with video=True
                      analysis=None, caption=f"v {v:.2f} m/s",    # what the overlay draws (lanes, lead box)
                      speed_mps=v, fields={"x_m": x})             # extra log fields (JSON values)
            if stop:                                              # fearguard.drive.interrupt.StopSignal
                break
    stats = rec.stats                                             # CommandStats: typed, built in memory
    rec.write_summary({"frames": rec.frames, **stats.to_json()})  # summary.json, written atomically
    rec.plot_timeline("title")                                     # timeline.png from the in-memory trace

Per frame, the video frame is written before the log line, and the log line is flushed: a run killed
at any moment (even SIGKILL) leaves a log whose lines all parse, with consecutive frame numbers, and
a video holding at least every logged frame but the last (see ``video.py`` for the formats).
``out_dir=None`` records nothing on disk (the suite's runs) but still builds the stats and the trace.

The summary of the supervisor's commands (``CommandStats``: share of time per fear level and mode,
EMERGENCY episodes, stretches of elevated fear) is accumulated frame by frame from the Commands, not
read back from the log. ``summary.json`` is written to a temporary file and renamed, so it is never
half-written. The log uses DESIGN.md's names (see ``report.command_record``).
"""

from __future__ import annotations

import json
import math
import os
from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from pathlib import Path
from types import TracebackType
from typing import TYPE_CHECKING, Any

import numpy as np

from fearguard.cues import CUE_NAMES
from fearguard.fear import LEVEL_ORDER
from fearguard.outputs.report import JsonlLog, command_record, json_value
from fearguard.outputs.timeline import Trace, plot_timeline
from fearguard.outputs.video import VideoSink, open_video
from fearguard.policy import MODE_ORDER
from fearguard.supervisor import Command

if TYPE_CHECKING:
    from fearguard.fuzzy.rulebase import RuleBase
    from fearguard.outputs.mcap import McapSink

LOG_NAME = "log.jsonl"
SUMMARY_NAME = "summary.json"
VIDEO_STEM = "annotated"  # + .mp4 (H.264) or .avi (MJPG), see video.py
ELEVATED_LEVEL = "MEDIUM"  # fear at or above this level counts as elevated
EPISODE_REASONS = 4  # reasons kept from the first frame of an EMERGENCY episode
ELEVATED_WHY = 2  # rule texts kept from the peak of an elevated stretch


@dataclass(frozen=True)
class Episode:
    """A contiguous stretch in EMERGENCY: when, why (causes and strategies by frame count), the lowest limit."""

    start_frame: int
    start_t_s: float
    end_frame: int
    end_t_s: float
    causes: Mapping[str, int]
    strategies: Mapping[str, int]
    min_speed_limit_mps: float
    first_reasons: tuple[str, ...]

    @property
    def cause(self) -> str:
        """The cause of most of its frames (the first seen on a tie)."""
        return max(self.causes, key=lambda c: self.causes[c])

    def to_json(self) -> dict[str, Any]:
        return json_value({
            "start_frame": self.start_frame, "start_t_s": self.start_t_s, "causes": dict(self.causes),
            "strategies": dict(self.strategies), "min_speed_limit_mps": self.min_speed_limit_mps, "end_frame": self.end_frame,
            "end_t_s": self.end_t_s, "first_reasons": list(self.first_reasons), "cause": self.cause,
        })


@dataclass(frozen=True)
class Elevated:
    """A stretch with fear at or above MEDIUM: when, how high, the causes, and the cues and rules at the peak."""

    start_t_s: float
    end_t_s: float
    peak_fear: float
    causes: Mapping[str, int]
    peak_t_s: float | None  # None when fear never rose above 0 in the stretch
    cue_at_peak: Mapping[str, Any]  # JSON values of the five cues at the peak
    why: tuple[str, ...] | None

    def to_json(self) -> dict[str, Any]:
        out: dict[str, Any] = {"start_t_s": self.start_t_s, "peak_fear": self.peak_fear, "causes": dict(self.causes),
                               "cue_at_peak": dict(self.cue_at_peak), "end_t_s": self.end_t_s}
        if self.peak_t_s is not None:
            out.update(peak_t_s=self.peak_t_s, why=list(self.why or ()))
        return json_value(out)


@dataclass(frozen=True)
class CommandStats:
    """What the supervisor did over a run, from its Commands (all zero/empty for a run without one)."""

    frames: int  # frames recorded (with or without a Command)
    supervised_frames: int  # frames with a Command
    fear_level_share: Mapping[str, float]
    mode_share: Mapping[str, float]
    emergency_episodes: tuple[Episode, ...]
    elevated_fear: tuple[Elevated, ...]
    fear_mean: float | None
    fear_max: float | None

    def to_json(self) -> dict[str, Any]:
        """The summary keys ``fearguard replay`` writes (only ``frames`` for a run without a supervisor)."""
        if self.supervised_frames == 0:
            return {"frames": self.frames}
        return json_value({
            "frames": self.frames, "fear_level_share": dict(self.fear_level_share), "mode_share": dict(self.mode_share),
            "emergency_episodes": [e.to_json() for e in self.emergency_episodes],
            "elevated_fear": [s.to_json() for s in self.elevated_fear], "fear_mean": self.fear_mean, "fear_max": self.fear_max,
        })


class _Stats:
    """Running counts behind CommandStats (one pass, constant work per frame)."""

    def __init__(self) -> None:
        self.frames = 0
        self.levels = dict.fromkeys(LEVEL_ORDER, 0)
        self.modes = dict.fromkeys(MODE_ORDER, 0)
        self.supervised = 0
        self.fear_sum = 0.0
        self.fear_max = -math.inf
        self.episodes: list[Episode] = []
        self.elevated: list[Elevated] = []
        self._episode: dict[str, Any] | None = None
        self._stretch: dict[str, Any] | None = None

    def add(self, frame: int, t_s: float, cmd: Command | None) -> None:
        self.frames += 1
        if cmd is None:
            self._end_episode()
            self._end_stretch()
            return
        self.supervised += 1
        level, mode = cmd.fear_level.name, cmd.mode.name
        self.levels[level] = self.levels.get(level, 0) + 1
        self.modes[mode] = self.modes.get(mode, 0) + 1
        self.fear_sum += cmd.fear
        self.fear_max = max(self.fear_max, cmd.fear)
        cause = cmd.cause.value if cmd.cause is not None else "fault"
        if mode == "EMERGENCY":
            self._in_episode(frame, t_s, cmd, cause)
        else:
            self._end_episode()
        if LEVEL_ORDER.index(level) >= LEVEL_ORDER.index(ELEVATED_LEVEL):
            self._in_stretch(t_s, cmd, cause)
        else:
            self._end_stretch()

    def _in_episode(self, frame: int, t_s: float, cmd: Command, cause: str) -> None:
        ep = self._episode
        if ep is None:
            ep = self._episode = {"start_frame": frame, "start_t_s": t_s, "causes": {}, "strategies": {},
                                  "min_speed_limit_mps": math.inf, "first_reasons": tuple(cmd.reasons[:EPISODE_REASONS])}
        ep["end_frame"], ep["end_t_s"] = frame, t_s
        ep["causes"][cause] = ep["causes"].get(cause, 0) + 1
        ep["strategies"][cmd.strategy.name] = ep["strategies"].get(cmd.strategy.name, 0) + 1
        ep["min_speed_limit_mps"] = min(ep["min_speed_limit_mps"], cmd.speed_limit_mps)

    def _end_episode(self) -> None:
        if self._episode is not None:
            self.episodes.append(Episode(**self._episode))
            self._episode = None

    def _in_stretch(self, t_s: float, cmd: Command, cause: str) -> None:
        st = self._stretch
        if st is None:
            st = self._stretch = {"start_t_s": t_s, "peak_fear": 0.0, "causes": {}, "peak_t_s": None, "cue_at_peak": {}, "why": None}
        st["end_t_s"] = t_s
        st["causes"][cause] = st["causes"].get(cause, 0) + 1
        if cmd.fear > st["peak_fear"]:
            st["peak_fear"], st["peak_t_s"] = cmd.fear, t_s
            st["cue_at_peak"] = {name: json_value(v) for name, v in zip(CUE_NAMES, cmd.cues.values(), strict=True)}
            st["why"] = tuple(x for x in cmd.reasons if x.startswith("rule "))[:ELEVATED_WHY]

    def _end_stretch(self) -> None:
        if self._stretch is not None:
            self.elevated.append(Elevated(**self._stretch))
            self._stretch = None

    def snapshot(self) -> CommandStats:
        """The stats so far (open stretches included as they stand)."""
        episodes = [*self.episodes, *([Episode(**self._episode)] if self._episode else [])]
        elevated = [*self.elevated, *([Elevated(**self._stretch)] if self._stretch else [])]
        n = max(1, self.supervised)
        return CommandStats(
            frames=self.frames, supervised_frames=self.supervised,
            fear_level_share={k: v / n for k, v in self.levels.items()}, mode_share={k: v / n for k, v in self.modes.items()},
            emergency_episodes=tuple(episodes), elevated_fear=tuple(elevated),
            fear_mean=self.fear_sum / self.supervised if self.supervised else None,
            fear_max=self.fear_max if self.supervised else None,
        )


class Recorder:
    """Writes one run's files as it goes: the flushed log, the optional annotated video; keeps stats and a trace."""

    def __init__(self, out_dir: str | Path | None, *, fps: float, video: bool = False, video_kind: str | None = None,
                 mcap: bool = False) -> None:
        """Open ``out_dir/log.jsonl`` (``out_dir`` None: nothing on disk); the video opens on the first frame; ``mcap``:
        also ``run.mcap`` for Foxglove (outputs/mcap.py)."""
        self.out_dir = None if out_dir is None else Path(out_dir)
        self.fps = fps
        self.trace = Trace()
        self._stats = _Stats()
        self._log = JsonlLog(self.out_dir / LOG_NAME) if self.out_dir is not None else None
        self._video: VideoSink | None = None
        self._mcap: McapSink | None = None
        if video and self.out_dir is not None:
            self._video = open_video(self.out_dir / VIDEO_STEM, fps, video_kind)
        if mcap and self.out_dir is not None:
            from fearguard.outputs.mcap import MCAP_NAME, McapSink  # the optional mcap package, only for runs that ask

            self._mcap = McapSink(self.out_dir / MCAP_NAME)

    @property
    def frames(self) -> int:
        """Frames recorded so far."""
        return self._stats.frames

    @property
    def log_path(self) -> Path | None:
        return self._log.path if self._log is not None else None

    @property
    def video_path(self) -> Path | None:
        return self._video.path if self._video is not None else None

    @property
    def mcap_path(self) -> Path | None:
        return self._mcap.path if self._mcap is not None else None

    @property
    def annotates(self) -> bool:
        """Whether frames are drawn on (a video or run.mcap is written): a driver passes its frame analysis only then."""
        return self._video is not None or self._mcap is not None

    @property
    def video_frames_rescaled(self) -> int:
        """Frames of another size than the first, scaled into the video (none dropped)."""
        return self._video.rescaled if self._video is not None else 0

    @property
    def stats(self) -> CommandStats:
        return self._stats.snapshot()

    def frame(self, frame: int, t_s: float, cmd: Command | None, *, image: np.ndarray | None = None, analysis: Any = None,
              caption: str = "", speed_mps: float | None = None, fields: Mapping[str, Any] | None = None,
              stamp_ns: int | None = None) -> None:
        """Record one frame: the video frame and run.mcap's messages first (when written), then the log line.

        ``stamp_ns``: the recording's own time of this frame for run.mcap (default ``t_s`` in ns)."""
        annotated = None
        if self.annotates and image is not None:
            from fearguard.outputs.overlay import annotate  # OpenCV drawing, only for runs with a video or run.mcap

            annotated = annotate(image, cmd, analysis, caption)
        if self._video is not None and annotated is not None:
            self._video.write(annotated)
        if self._mcap is not None:
            self._mcap.write(stamp_ns if stamp_ns is not None else round(t_s * 1e9), cmd, annotated)
        if self._log is not None:
            self._log.write(command_record(frame, t_s, cmd, **(fields or {})))
        self._stats.add(frame, t_s, cmd)
        self.trace.add(t_s, cmd, speed_mps)

    def close(self) -> None:
        """Close the log, the video and run.mcap (safe to call twice)."""
        try:
            if self._log is not None:
                self._log.close()
        finally:
            try:
                if self._video is not None:
                    self._video.close()
            finally:
                if self._mcap is not None:
                    self._mcap.close()

    def __enter__(self) -> Recorder:
        return self

    def __exit__(self, exc_type: type[BaseException] | None, exc: BaseException | None, tb: TracebackType | None) -> None:
        self.close()

    def write_summary(self, summary: Mapping[str, Any]) -> Path | None:
        """``out_dir/summary.json`` (JSON values, no NaN), written to a temporary file and renamed into place."""
        if self.out_dir is None:
            return None
        return write_json(self.out_dir / SUMMARY_NAME, summary)

    def plot_timeline(self, title: str = "", with_speed: bool = False, rules: RuleBase | None = None) -> Path | None:
        """``out_dir/timeline.png`` from the trace (None when nothing is on disk or no frame was recorded); ``rules``: the
        supervisor's, whose thresholds the plot draws."""
        if self.out_dir is None or not self.trace.t_s:
            return None
        return plot_timeline(self.trace, self.out_dir / "timeline.png", title=title, with_speed=with_speed, rules=rules)


def write_json(path: str | Path, value: Mapping[str, Any] | Sequence[Any]) -> Path:
    """Write JSON (NaN → null, ±inf → "inf") atomically: a temporary file in the same folder, then a rename."""
    path = Path(path)
    tmp = path.with_name(f".{path.name}.tmp")
    tmp.write_text(json.dumps(json_value(value), indent=2, allow_nan=False) + "\n", encoding="utf-8")
    os.replace(tmp, path)
    return path
