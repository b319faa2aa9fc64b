"""Annotated frames for videos and run.mcap: the assumed horizon, the lanes and lead box perception saw, a fear gauge, mode,
speed limit and reasons on dark bands that survive H.264 from 160×120 to 1280×720."""

from __future__ import annotations

from dataclasses import replace

import cv2
import numpy as np

from fearguard.outputs import text_layout
from fearguard.outputs.text_layout import TextBox, TextStyle
from fearguard.policy import Mode
from fearguard.supervisor import Command
from fearguard.vision.frame import FrameAnalysis

MODE_COLOUR = {Mode.NORMAL: (60, 200, 60), Mode.CAUTION: (0, 190, 255), Mode.EMERGENCY: (60, 60, 255)}  # BGR: the mode swatch
# Header text in light tints of the mode colours: H.264 keeps colour (chroma) at a quarter of the pixels (4:2:0), so a
# thin saturated red stroke smears into the band; a light tint carries the glyphs in luma, which every pixel keeps
# (contrast against the dark band ≥ 8:1 before compression; tests/test_overlay_h264.py measures it after).
MODE_TEXT = {Mode.NORMAL: (170, 255, 170), Mode.CAUTION: (130, 230, 255), Mode.EMERGENCY: (170, 170, 255)}  # BGR
WHITE = (255, 255, 255)
HORIZON_BGR = (255, 255, 0)  # cyan: the horizon the road region assumes (camera model or the dash-cam default)
REASON_TEXT_RELATIVE = 0.8  # [-] reasons in slightly smaller text than the header
REASON_SHARE_OF_HEIGHT = 0.3  # [-] at most this much of the frame's height holds reasons
COMPACT_BELOW_PX = 320  # [px] narrower frames get the compact layout: two header lines, one reason line, no caption


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
        _draw_swatch(out, cmd.mode, boxes)
        _draw_gauge(out, cmd.fear, boxes)
    return out


def overlay_boxes(width_px: int, height_px: int, cmd: Command | None, extra: str = "", reasons: int = 2) -> list[TextBox]:
    """Where every piece of text goes on a frame of this size: a header band at the top, reasons along the bottom; under
    COMPACT_BELOW_PX wide the header keeps mode, fear and limit in two lines and one reason line remains."""
    style = TextStyle.for_frame(width_px, height_px)
    margin = max(2, width_px // 80)
    usable = width_px - 2 * margin
    if cmd is None:
        return _bands(text_layout.stack([(line, WHITE) for line in text_layout.flow(["unsupervised", extra], style, usable)],
                                        style, margin, margin, usable), width_px - margin)
    compact = width_px < COMPACT_BELOW_PX
    swatch = _swatch_px(style)
    x = margin + swatch
    colour = MODE_TEXT[cmd.mode]
    if compact:
        phrases = [f"{cmd.mode.name} {cmd.strategy.name}", f"fear {cmd.fear:.2f} limit {cmd.speed_limit_mps:.2f} m/s"]
    else:
        phrases = [f"{cmd.mode.name} {cmd.strategy.name}", f"fear {cmd.fear:.2f} {cmd.fear_level.name}",
                   f"limit {cmd.speed_limit_mps:.2f} m/s", extra]
    header = text_layout.stack([(line, colour) for line in text_layout.flow(phrases, style, width_px - margin - x)], style, x, margin,
                               width_px - margin - x)
    small = TextStyle.for_frame(width_px, height_px, REASON_TEXT_RELATIVE)
    room = max(1, int(REASON_SHARE_OF_HEIGHT * height_px) // small.line_height_px())
    if compact:
        first = text_layout.fit_lines(cmd.reasons[0], small, usable) if cmd.reasons else []
        lines = [(_ended(first, small, usable), WHITE)] if first else []
        footer = text_layout.stack_up(lines, small, margin, height_px - margin, usable, 1)
    else:
        lines = [(r, WHITE) for r in cmd.reasons[:reasons]]
        footer = text_layout.stack_up(lines, small, margin, height_px - margin, usable, min(room, 2 * reasons))
    return _bands(header, width_px - margin) + _bands(footer, width_px - margin)


def _ended(lines: list[str], style: TextStyle, max_width_px: int) -> str:
    """The first line of a wrapped text, marked with an ellipsis when more followed (cut at a word, never mid-word)."""
    if len(lines) == 1:
        return lines[0]
    words = lines[0].split()
    while len(words) > 1 and style.size(" ".join(words) + text_layout.ELLIPSIS)[0] > max_width_px - 2 * style.pad_px:
        words.pop()
    return " ".join(words) + text_layout.ELLIPSIS


def _bands(boxes: list[TextBox], right_px: int) -> list[TextBox]:
    """Each line's dark panel stretched to ``right_px``: one band behind the header (and one behind the reasons), not a
    ragged edge of panels whose corners H.264 smears into the picture."""
    return [replace(b, w_px=max(b.w_px, right_px - b.x_px)) for b in boxes]


def _swatch_px(style: TextStyle) -> int:
    return max(4, style.line_height_px() // 2)


def _draw_swatch(out: np.ndarray, mode: Mode, boxes: list[TextBox]) -> None:
    """The mode colour as a solid block at the header band's left end: large enough to keep its colour through 4:2:0."""
    header = [b for b in boxes if b.y_px < out.shape[0] // 2]
    if not header:
        return
    top, bottom = min(b.y_px for b in header), max(b.y_px + b.h_px for b in header)
    right = min(b.x_px for b in header)
    left = right - _swatch_px(TextStyle(header[0].scale, header[0].thickness_px, header[0].pad_px))
    cv2.rectangle(out, (left, top), (right - 1, bottom - 1), MODE_COLOUR[mode], -1)


def _draw_perception(out: np.ndarray, analysis: FrameAnalysis, k: float) -> None:
    """The assumed horizon, the lane lines and the lead box perception saw."""
    if analysis.horizon_v_px is not None and 0 <= analysis.horizon_v_px < out.shape[0]:
        v = round(analysis.horizon_v_px)
        dash = max(4, out.shape[1] // 40)
        for u in range(0, out.shape[1], 2 * dash):
            cv2.line(out, (u, v), (min(out.shape[1] - 1, u + dash - 1), v), HORIZON_BGR, max(1, int(k)), cv2.LINE_AA)
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
