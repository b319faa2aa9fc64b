"""Annotated frames for videos: the lanes and lead box perception saw, a fear gauge, mode, speed limit, reasons."""

from __future__ import annotations

import cv2
import numpy as np

from fearguard.policy import Mode
from fearguard.supervisor import Command
from fearguard.vision.frame import FrameAnalysis

MODE_COLOUR = {Mode.NORMAL: (60, 180, 60), Mode.CAUTION: (0, 190, 255), Mode.EMERGENCY: (40, 40, 230)}  # BGR


def annotate(frame: np.ndarray, cmd: Command | None, analysis: FrameAnalysis | None, extra: str = "", reasons: int = 2) -> np.ndarray:
    """A copy of the frame (BGR uint8) with what the supervisor saw and decided drawn on it."""
    out = frame.copy() if frame.ndim == 3 else cv2.cvtColor(frame, cv2.COLOR_GRAY2BGR)
    h, w = out.shape[:2]
    k = max(1.0, w / 640.0)  # line and text scale
    if analysis is not None and analysis.region is not None:
        r, s = analysis.region, analysis.scale
        for line, colour in ((analysis.left, (0, 0, 255)), (analysis.right, (0, 255, 0))):
            if line is not None:
                p0 = (int(line.u_at(r.top_v_px) * s), int(r.top_v_px * s))
                p1 = (int(line.u_at(r.bottom_v_px) * s), int(r.bottom_v_px * s))
                cv2.line(out, p0, p1, colour, max(1, int(2 * k)), cv2.LINE_AA)
        if analysis.lead_box is not None:
            b = analysis.lead_box
            cv2.rectangle(out, (int(b.x_px), int(b.y_px)), (int(b.x_px + b.w_px), int(b.y_px + b.h_px)), (255, 160, 0), max(1, int(2 * k)))
    if cmd is None:
        _text(out, f"unsupervised {extra}", (int(8 * k), int(22 * k)), k, (255, 255, 255))
        return out
    # fear gauge: a bar along the left edge, green → red
    bar_h = int(0.5 * h)
    x0, y0 = int(8 * k), int(40 * k)
    cv2.rectangle(out, (x0, y0), (x0 + int(14 * k), y0 + bar_h), (40, 40, 40), -1)
    filled = int(bar_h * min(1.0, max(0.0, cmd.fear)))
    colour = (0, int(255 * (1 - cmd.fear)), int(255 * cmd.fear))
    cv2.rectangle(out, (x0, y0 + bar_h - filled), (x0 + int(14 * k), y0 + bar_h), colour, -1)
    header = f"{cmd.mode.name} {cmd.strategy.name}  fear {cmd.fear:.2f} {cmd.fear_level.name}  limit {cmd.speed_limit_mps:.2f} m/s {extra}"
    _text(out, header, (int(8 * k), int(22 * k)), k, MODE_COLOUR[cmd.mode])
    for i, reason in enumerate(cmd.reasons[:reasons]):
        _text(out, reason[:90], (int(30 * k), h - int((10 + 18 * (reasons - 1 - i)) * k)), 0.8 * k, (255, 255, 255))
    return out


def _text(img: np.ndarray, text: str, org: tuple[int, int], k: float, colour: tuple[int, int, int]) -> None:
    cv2.putText(img, text, org, cv2.FONT_HERSHEY_SIMPLEX, 0.5 * k, (0, 0, 0), max(2, int(3 * k)), cv2.LINE_AA)
    cv2.putText(img, text, org, cv2.FONT_HERSHEY_SIMPLEX, 0.5 * k, colour, max(1, int(k)), cv2.LINE_AA)


class VideoOut:
    """An MP4 writer that opens on the first frame (its size) and closes cleanly on any exit."""

    def __init__(self, path: str, fps: float) -> None:
        self.path, self.fps = path, fps if fps > 0 else 20.0
        self._writer: cv2.VideoWriter | None = None

    def write(self, frame: np.ndarray) -> None:
        if self._writer is None:
            h, w = frame.shape[:2]
            self._writer = cv2.VideoWriter(self.path, cv2.VideoWriter_fourcc(*"mp4v"), self.fps, (w, h))
        self._writer.write(frame)

    def close(self) -> None:
        if self._writer is not None:
            self._writer.release()
            self._writer = None
