"""Annotated frames for videos: the lanes and lead box perception saw, a fear gauge, mode, speed limit, reasons."""

from __future__ import annotations

import cv2
import numpy as np

from fearguard.outputs import text_layout
from fearguard.outputs.text_layout import TextBox, TextStyle
from fearguard.policy import Mode
from fearguard.supervisor import Command
from fearguard.vision.frame import FrameAnalysis

MODE_COLOUR = {Mode.NORMAL: (60, 200, 60), Mode.CAUTION: (0, 190, 255), Mode.EMERGENCY: (60, 60, 255)}  # BGR
WHITE = (255, 255, 255)
REASON_TEXT_RELATIVE = 0.8  # [-] reasons in slightly smaller text than the header
REASON_SHARE_OF_HEIGHT = 0.3  # [-] at most this much of the frame's height holds reasons


def annotate(frame: np.ndarray, cmd: Command | None, analysis: FrameAnalysis | None, extra: str = "", reasons: int = 2) -> np.ndarray:
    """A copy of the frame (BGR uint8) with what the supervisor saw and decided drawn on it (any size ≥ 160×120)."""
    out = frame.copy() if frame.ndim == 3 else cv2.cvtColor(frame, cv2.COLOR_GRAY2BGR)
    h, w = out.shape[:2]
    k = max(1.0, w / 640.0)  # line scale
    if analysis is not None:
        _draw_perception(out, analysis, k)
    boxes = overlay_boxes(w, h, cmd, extra, reasons)
    text_layout.draw(out, boxes)
    if cmd is not None:
        _draw_gauge(out, cmd.fear, boxes)
    return out


def overlay_boxes(width_px: int, height_px: int, cmd: Command | None, extra: str = "", reasons: int = 2) -> list[TextBox]:
    """Where every piece of text goes on a frame of this size: header at the top, reasons along the bottom."""
    style = TextStyle.for_frame(width_px, height_px)
    margin = max(2, width_px // 80)
    usable = width_px - 2 * margin
    if cmd is None:
        return text_layout.stack([(line, WHITE) for line in text_layout.flow(["unsupervised", extra], style, usable)],
                                 style, margin, margin, usable)
    colour = MODE_COLOUR[cmd.mode]
    phrases = [f"{cmd.mode.name} {cmd.strategy.name}", f"fear {cmd.fear:.2f} {cmd.fear_level.name}",
               f"limit {cmd.speed_limit_mps:.2f} m/s", extra]
    header = text_layout.stack([(line, colour) for line in text_layout.flow(phrases, style, usable)], style, margin, margin, usable)
    small = TextStyle.for_frame(width_px, height_px, REASON_TEXT_RELATIVE)
    room = max(1, int(REASON_SHARE_OF_HEIGHT * height_px) // small.line_height_px())
    lines = [(r, WHITE) for r in cmd.reasons[:reasons]]
    footer = text_layout.stack_up(lines, small, margin, height_px - margin, usable, min(room, 2 * reasons))
    return header + footer


def _draw_perception(out: np.ndarray, analysis: FrameAnalysis, k: float) -> None:
    """The lane lines and the lead box perception saw."""
    if analysis.curves_px is not None:  # a bending lane: its boundaries as they were fitted, not their straight chords
        for curve, colour in zip(analysis.curves_px, ((0, 0, 255), (0, 255, 0)), strict=True):
            if curve is not None:
                cv2.polylines(out, [np.rint(curve).astype(np.int32)], False, colour, max(1, int(2 * k)), cv2.LINE_AA)
    elif analysis.region is not None:
        r, s = analysis.region, analysis.scale
        for line, colour in ((analysis.left, (0, 0, 255)), (analysis.right, (0, 255, 0))):
            if line is not None:
                p0 = (int(line.u_at(r.top_v_px) * s), int(r.top_v_px * s))
                p1 = (int(line.u_at(r.bottom_v_px) * s), int(r.bottom_v_px * s))
                cv2.line(out, p0, p1, colour, max(1, int(2 * k)), cv2.LINE_AA)
    if analysis.lead_box is not None:
        b = analysis.lead_box
        cv2.rectangle(out, (int(b.x_px), int(b.y_px)), (int(b.x_px + b.w_px), int(b.y_px + b.h_px)), (255, 160, 0), max(1, int(2 * k)))


def _draw_gauge(out: np.ndarray, fear: float, boxes: list[TextBox]) -> None:
    """Fear as a bar along the left edge between the header and the reasons, green (0) → red (1)."""
    h, w = out.shape[:2]
    top = max((b.y_px + b.h_px for b in boxes if b.y_px < h // 2), default=0) + 2
    bottom = min((b.y_px for b in boxes if b.y_px >= h // 2), default=h) - 2
    bar_w = max(4, w // 45)
    if bottom - top < 8:
        return
    x0 = max(2, w // 80)
    cv2.rectangle(out, (x0, top), (x0 + bar_w, bottom), (40, 40, 40), -1)
    f = min(1.0, max(0.0, fear))
    filled = int((bottom - top) * f)
    cv2.rectangle(out, (x0, bottom - filled), (x0 + bar_w, bottom), (0, int(255 * (1 - f)), int(255 * f)), -1)
