"""Did the camera's lane model see the road at all? Advice, in a replay and in the Donkey part, when it hardly did.

A model car's camera replayed with no camera file and no learnt track usually reads lane confidence 0 on frame after
frame (issue 33's table: clean frames calm on 0 % of most model-car sources) — the road region without a camera model
is a dash-cam's (the road from 62 to 93 % of the picture's height, narrowing toward the middle) and a low, wide
camera sees its track elsewhere — and the replay then says only "EMERGENCY 94 %", the Donkey car only stands. Over a
replay (or the Donkey part's first ``integrations.donkey.EYES_LOOPS`` supervised loops) this counts the frames on which
the lane was seen at all (``lane_confidence`` at least the rule file's ``recovery_min_confidence``, the confidence from
which a creep steers by the lane seen now: one owner for "seen") and the frames the road picture held the car in
EMERGENCY. When the lane was seen on fewer than ``SEEN_SHARE_MIN`` of the
frames, the road caused most of the EMERGENCY, and no track profile was given, the advice names what would help — a
profile learnt from the user's own driving (``fearguard learn``, docs/learning.md) and, without a camera file, the
camera's pose — in the words of where it is read (``Remedies``: the command line's options, or the Donkey config's
keys). It changes nothing in what the supervisor does.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import numpy as np

from fearguard.fear import Cause
from fearguard.policy.config import Mode
from fearguard.supervisor import Command
from fearguard.vision.lanes import BOTTOM_FRACTION, TOP_FRACTION

SEEN_SHARE_MIN = 0.2  # [-] of the frames: the lane seen on fewer than this is a recording the camera's lane model cannot read
ROAD_EMERGENCY_SHARE_MIN = 0.5  # [-] of the frames: ... when the road picture held the car in EMERGENCY on at least this many
_BINS = 100  # lane confidences counted in hundredths (constant memory over any length of recording)


@dataclass(frozen=True)
class Remedies:
    """How the user gives the supervisor a track profile and a camera, where the advice is read."""

    track: str  # how a learnt profile is given, after `fearguard learn RECORDING --out track.npz`
    camera: str  # how the camera's pose is given
    markings: str | None = None  # how dark markings are asked for (None: only through a learnt profile, which learns them)


CLI = Remedies(track="then `--track track.npz`", camera="`--camera camera.toml`, `fearguard calibrate`", markings="`--markings dark`")
DONKEY = Remedies(track="then FEARGUARD_TRACK = \"track.npz\" in myconfig.py",
                  camera="FEARGUARD_CAMERA: a camera preset's name or a camera.toml from `fearguard calibrate`")


@dataclass(frozen=True)
class EyesVerdict:
    """What the camera saw of the lane; ``advice`` when it hardly saw it (None otherwise)."""

    frames: int  # frames with a lane confidence
    lane_seen_share: float | None  # of those frames: lane confidence >= the seen threshold (None: no frame)
    lane_confidence_median: float | None  # to the hundredth
    road_emergency_share: float | None  # of the supervised frames: EMERGENCY with the road picture its cause
    seen_threshold: float
    advice: str | None

    def to_json(self) -> dict[str, Any]:
        return {"frames": self.frames, "lane_seen_share": self.lane_seen_share, "lane_confidence_median": self.lane_confidence_median,
                "road_emergency_share": self.road_emergency_share, "seen_threshold": self.seen_threshold, "advice": self.advice}


class EyesCheck:
    """Fed each frame's Command (``add``); ``finish`` gives the verdict. ``camera``/``track``: whether the supervisor had
    a camera model and a track profile (the advice names what is missing, in the words of ``remedies``)."""

    def __init__(self, seen_threshold: float, camera: bool, track: bool, remedies: Remedies = CLI, markings: str = "light") -> None:
        self.seen_threshold, self._camera, self._track, self._remedies = seen_threshold, camera, track, remedies
        self._markings = markings  # the markings the lane model looked for (lane.MARKINGS)
        self._counts = np.zeros(_BINS + 1, np.int64)  # lane confidence in hundredths
        self._supervised = 0
        self._road_emergency = 0
        self._seen = 0

    @property
    def supervised(self) -> int:
        """Commands counted so far (frames the supervisor answered)."""
        return self._supervised

    def add(self, command: Command | None) -> None:
        if command is None:
            return
        self._supervised += 1
        if command.mode is Mode.EMERGENCY and command.cause is Cause.ROAD:
            self._road_emergency += 1
        confidence = command.cues.lane_confidence
        if confidence == confidence:  # NaN (no picture) is no reading of the lane
            self._counts[round(min(1.0, max(0.0, confidence)) * _BINS)] += 1
            self._seen += confidence >= self.seen_threshold

    def finish(self) -> EyesVerdict:
        n = int(self._counts.sum())
        if n == 0:
            return EyesVerdict(0, None, None, None, self.seen_threshold, None)
        seen = self._seen / n
        median = float(np.searchsorted(np.cumsum(self._counts), 0.5 * n)) / _BINS
        road = self._road_emergency / self._supervised if self._supervised else 0.0
        advice = None
        if seen < SEEN_SHARE_MIN and road >= ROAD_EMERGENCY_SHARE_MIN and not self._track:
            advice = (f"the lane was seen (lane confidence >= {self.seen_threshold:g}) on {100 * seen:.0f} % of frames "
                      f"(median {median:.2f}) and the road picture held the car in EMERGENCY on {100 * road:.0f} %: "
                      + _what_helps(self._camera, self._remedies, self._markings))
        return EyesVerdict(n, seen, median, road, self.seen_threshold, advice)


def _what_helps(camera: bool, remedies: Remedies, markings: str = "light") -> str:
    learn = (f"learn this track from a recording of normal driving (`fearguard learn RECORDING --out track.npz`, "
             f"{remedies.track}; docs/learning.md)")
    dark = (f"; a track taped in black or dark tape: {remedies.markings} (the lane model looked for light paint)"
            if markings == "light" and remedies.markings else "")
    if camera:
        return f"this track's guidance is not what the camera's lane model looks for; {learn}{dark}"
    return (f"without a camera model the lane model looks where a dash-cam sees the road ({100 * TOP_FRACTION:.0f}-"
            f"{100 * BOTTOM_FRACTION:.0f} % of the picture's height, narrowing toward the middle); {learn}, or give the camera's "
            f"pose ({remedies.camera}){dark}")
