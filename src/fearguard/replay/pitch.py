"""Pitch sanity: does the camera model's horizon agree with where the lane lines meet?

On a straight, flat road the two lane boundaries meet at the horizon, so over the first ``PITCH_WINDOW_S`` of a
replay the median row of their vanishing point is the horizon the recording shows. The road region, the ground ranges
and the lane geometry all hang on the horizon the camera model assumes (``lanes.assumed_horizon_v_px``: the pitched
model's, else the dash-cam default); a wrong ``pitch_deg`` in camera.toml (3° instead of −1.5° turned the clean shared
highway into 96 % EMERGENCY) shows up as the two rows lying apart. In angles, through the camera's focal length:

    pitch the lines suggest = atan((cy − v_vanishing) / fy),   assumed pitch = atan((cy − v_horizon) / fy)

When they differ by more than ``PITCH_TOLERANCE_DEG``, replay warns once (``CameraPitchWarning``, a ``warning:`` line)
and the summary's ``pitch_check`` says so. The median over many frames is robust to curves and lane changes in a few
of them; with fewer than ``PITCH_MIN_FRAMES`` frames that show both boundaries the check says nothing.
"""

from __future__ import annotations

import math
import statistics
import warnings
from dataclasses import dataclass
from typing import Any

from fearguard.camera import CameraModel
from fearguard.errors import CameraPitchWarning
from fearguard.vision.frame import FrameAnalysis
from fearguard.vision.lanes import vanishing_point

PITCH_WINDOW_S = 5.0  # [s] the first seconds of a replay whose lane lines are compared with the horizon
PITCH_TOLERANCE_DEG = 3.0  # [deg] a few degrees: a mount's tilt on bumps and a road's grade stay within it
PITCH_MIN_FRAMES = 10  # [frames] with both boundaries found, for a verdict


@dataclass(frozen=True)
class PitchVerdict:
    """What the check found: the pitch assumed, the pitch the lines suggest, how far apart (None: no verdict)."""

    assumed_pitch_deg: float | None
    suggested_pitch_deg: float | None
    off_by_deg: float | None
    frames: int  # frames in the window that showed both boundaries
    warned: bool

    def to_json(self) -> dict[str, Any]:
        return {"assumed_pitch_deg": self.assumed_pitch_deg, "suggested_pitch_deg": self.suggested_pitch_deg,
                "off_by_deg": self.off_by_deg, "frames": self.frames, "window_s": PITCH_WINDOW_S,
                "tolerance_deg": PITCH_TOLERANCE_DEG, "warned": self.warned}


class PitchCheck:
    """Fed each frame's analysis (``add``); decides once, when the window has passed or the replay ends (``finish``)."""

    def __init__(self, camera: CameraModel | None) -> None:
        self._camera = camera
        self._t0_s: float | None = None
        self._rows: list[float] = []
        self._frame_camera: CameraModel | None = None
        self._horizon_v_px: float | None = None
        self.verdict: PitchVerdict | None = None

    def add(self, t_s: float, analysis: FrameAnalysis | None, frame_size: tuple[int, int]) -> None:
        """One frame (its analysis, None when the supervisor had none); past the window the verdict is given."""
        if self.verdict is not None:
            return
        self._t0_s = t_s if self._t0_s is None else self._t0_s
        if t_s - self._t0_s >= PITCH_WINDOW_S:
            self.finish()
            return
        if analysis is None or analysis.left is None or analysis.right is None or analysis.horizon_v_px is None:
            return
        vp = vanishing_point(analysis.left, analysis.right)
        if vp is None or not math.isfinite(vp[1]):
            return
        if self._frame_camera is None:
            width, height = frame_size
            self._frame_camera = (self._camera.scaled_to(width, height) if self._camera is not None
                                  else CameraModel.default(width, height))
        self._horizon_v_px = analysis.horizon_v_px
        self._rows.append(vp[1] * analysis.scale)

    def finish(self) -> PitchVerdict:
        """The verdict (given once; a warning when the lines and the horizon disagree)."""
        if self.verdict is not None:
            return self.verdict
        cam = self._frame_camera
        if cam is None or self._horizon_v_px is None or len(self._rows) < PITCH_MIN_FRAMES:
            self.verdict = PitchVerdict(None, None, None, len(self._rows), False)
            return self.verdict
        assumed = _pitch_deg(cam, self._horizon_v_px)
        suggested = _pitch_deg(cam, statistics.median(self._rows))
        off = suggested - assumed
        warned = abs(off) > PITCH_TOLERANCE_DEG
        self.verdict = PitchVerdict(round(assumed, 2), round(suggested, 2), round(off, 2), len(self._rows), warned)
        if warned:
            warnings.warn(
                f"camera pitch: the lane lines meet {abs(off):.1f}° {'below' if off < 0 else 'above'} the assumed horizon over the "
                f"first {PITCH_WINDOW_S:g} s ({len(self._rows)} frames): the camera model assumes a pitch of {assumed:+.1f}°, the "
                f"lines suggest {suggested:+.1f}°; check camera.toml's pitch_deg (fearguard calibrate --pitch-deg {suggested:.1f})",
                CameraPitchWarning, stacklevel=2,
            )
        return self.verdict


def _pitch_deg(camera: CameraModel, horizon_v_px: float) -> float:
    """The pitch (deg, + = looking down) that puts the horizon at this row."""
    return math.degrees(math.atan2(camera.cy_px - horizon_v_px, camera.fy_px))
