"""Text on frames that stays readable from 160×120 to 1280×720: measured boxes, wrapped lines, one stroke.

Why by hand: OpenCV only measures and draws single lines (``cv2.getTextSize``/``cv2.putText``); it does
not wrap, fit or keep boxes apart. Two facts shape this module:

- Since OpenCV 5 a glyph's advance depends on the stroke thickness, so a thick black "outline" drawn
  under thinner coloured text drifts out of step. Text is therefore drawn once, at one thickness, on
  a dark panel measured with that same thickness: measurement and drawing cannot disagree.
- The font scale follows the frame height (``FONT_PX_PER_FRAME_PX``) with a floor that keeps Hershey
  glyphs legible; a line wider than the frame is wrapped at word boundaries, and a word wider than
  the frame is cut with an ellipsis.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass, replace
from functools import lru_cache

import cv2
import numpy as np

FONT = cv2.FONT_HERSHEY_SIMPLEX
FONT_PX_PER_FRAME_PX = 1.0 / 30.0  # [px/px] cap height of the text per frame height (16 px at 480 rows)
MIN_FONT_SCALE = 0.3  # [-] smallest Hershey scale that stays legible (cap height ~7 px, 160×120 frames)
PANEL_ALPHA = 0.85  # [-] opacity of the dark panel behind text: dark enough for 4.5:1 on a white sky after H.264 (issue 37)
ELLIPSIS = ".."
SEPARATOR = " | "  # between phrases on one line (Hershey fonts draw ASCII only)
INK_PROBE = "|Hgjpqy()[]{}$@"  # the tallest and deepest glyphs an overlay line can hold


@dataclass(frozen=True)
class TextBox:
    """One line of text placed on a frame: the panel rectangle it owns, in frame pixels."""

    text: str
    x_px: int
    y_px: int  # top of the panel
    w_px: int
    h_px: int
    baseline_px: int  # y of the text baseline
    scale: float
    thickness_px: int
    colour_bgr: tuple[int, int, int]
    pad_px: int = 0  # [px] inner margin between the panel edge and the glyphs

    def shifted(self, dy_px: int) -> TextBox:
        return replace(self, y_px=self.y_px + dy_px, baseline_px=self.baseline_px + dy_px)

    def overlaps(self, other: TextBox) -> bool:
        return not (
            self.x_px + self.w_px <= other.x_px
            or other.x_px + other.w_px <= self.x_px
            or self.y_px + self.h_px <= other.y_px
            or other.y_px + other.h_px <= self.y_px
        )


@dataclass(frozen=True)
class TextStyle:
    """Font scale, stroke and padding for one frame size."""

    scale: float
    thickness_px: int
    pad_px: int

    @classmethod
    def for_frame(cls, width_px: int, height_px: int, relative: float = 1.0) -> TextStyle:
        """The style for a frame: text height proportional to the frame, never below legibility."""
        cap_px = max(1.0, height_px * FONT_PX_PER_FRAME_PX * relative)
        unit_cap = cv2.getTextSize("H", FONT, 1.0, 1)[0][1]  # cap height at scale 1
        scale = max(MIN_FONT_SCALE * relative, cap_px / unit_cap)
        thickness = max(1, round(scale * 1.6))
        return cls(scale, thickness, max(1, round(scale * 4)))

    def size(self, text: str) -> tuple[int, int, int]:
        """(width, height above baseline, depth below baseline) of a line, measured at the drawing thickness; the
        height and depth are at least the ink of the tallest and deepest glyphs (``_ink_extent``)."""
        (w, h), base = cv2.getTextSize(text, FONT, self.scale, self.thickness_px)
        above, below = _ink_extent(self.scale, self.thickness_px)
        return w, max(h, above), max(base, below)

    def line_height_px(self) -> int:
        _, h, base = self.size("Hg")
        return h + base + 2 * self.pad_px


@lru_cache(maxsize=64)
def _ink_extent(scale: float, thickness_px: int) -> tuple[int, int]:
    """Rows of ink above and below the baseline when INK_PROBE is drawn (anti-aliased) at this scale and stroke.

    ``cv2.getTextSize`` reports the cap height, and OpenCV 4.x draws ``|`` and brackets a few pixels above it (5.x
    measures them): measuring the drawn ink holds the boxes to what is painted on every release.
    """
    (w, h), base = cv2.getTextSize(INK_PROBE, FONT, scale, thickness_px)
    margin = 2 * (h + base + thickness_px) + 4
    canvas = np.zeros((2 * margin, w + 2 * margin), np.uint8)
    cv2.putText(canvas, INK_PROBE, (margin, margin), FONT, scale, 255, thickness_px, cv2.LINE_AA)
    rows = np.flatnonzero(canvas.max(axis=1))
    if rows.size == 0:
        return h, base
    return margin - int(rows[0]), int(rows[-1]) - margin + 1


def fit_lines(text: str, style: TextStyle, max_width_px: int) -> list[str]:
    """The text wrapped at spaces into lines no wider than max_width_px (a too-long word is cut)."""
    inner = max(1, max_width_px - 2 * style.pad_px)
    lines: list[str] = []
    current = ""
    for word in text.split():
        trial = f"{current} {word}" if current else word
        if style.size(trial)[0] <= inner:
            current = trial
            continue
        if current:
            lines.append(current)
        current = _cut(word, style, inner)
    if current:
        lines.append(current)
    return lines


def flow(phrases: Sequence[str], style: TextStyle, max_width_px: int) -> list[str]:
    """Phrases kept whole where they fit, joined by SEPARATOR into lines no wider than max_width_px."""
    inner = max(1, max_width_px - 2 * style.pad_px)
    lines: list[str] = []
    for phrase in (p for p in phrases if p):
        trial = f"{lines[-1]}{SEPARATOR}{phrase}" if lines else phrase
        if lines and style.size(trial)[0] <= inner:
            lines[-1] = trial
        else:
            lines.extend(fit_lines(phrase, style, max_width_px))
    return lines


def _cut(word: str, style: TextStyle, inner_px: int) -> str:
    if style.size(word)[0] <= inner_px:
        return word
    while word and style.size(word + ELLIPSIS)[0] > inner_px:
        word = word[:-1]
    return word + ELLIPSIS if word else ""


def stack(
    lines: Sequence[tuple[str, tuple[int, int, int]]], style: TextStyle, x_px: int, top_px: int, max_width_px: int,
    max_lines: int | None = None,
) -> list[TextBox]:
    """Lines (text, colour) wrapped to max_width_px and stacked downward from top_px, one box per line."""
    boxes: list[TextBox] = []
    y = top_px
    lh = style.line_height_px()
    for text, colour in lines:
        for part in fit_lines(text, style, max_width_px):
            if max_lines is not None and len(boxes) >= max_lines:
                return boxes
            w, h, _ = style.size(part)
            boxes.append(TextBox(
                text=part, x_px=x_px, y_px=y, w_px=w + 2 * style.pad_px, h_px=lh, baseline_px=y + style.pad_px + h,
                scale=style.scale, thickness_px=style.thickness_px, colour_bgr=colour, pad_px=style.pad_px,
            ))
            y += lh
    return boxes


def stack_up(
    lines: Sequence[tuple[str, tuple[int, int, int]]], style: TextStyle, x_px: int, bottom_px: int, max_width_px: int,
    max_lines: int,
) -> list[TextBox]:
    """Like ``stack`` but ending at bottom_px (for reasons along the lower edge); keeps the first lines."""
    boxes = stack(lines, style, x_px, 0, max_width_px, max_lines)
    shift = bottom_px - len(boxes) * style.line_height_px()
    return [b.shifted(shift) for b in boxes]


def draw(img: np.ndarray, boxes: Sequence[TextBox]) -> None:
    """Dark translucent panels, then the text at the thickness it was measured with (in place)."""
    if not boxes:
        return
    h, w = img.shape[:2]
    panel = img.copy()
    for b in boxes:
        cv2.rectangle(panel, (b.x_px, b.y_px), (min(w - 1, b.x_px + b.w_px - 1), min(h - 1, b.y_px + b.h_px - 1)), (0, 0, 0), -1)
    cv2.addWeighted(panel, PANEL_ALPHA, img, 1.0 - PANEL_ALPHA, 0.0, dst=img)
    for b in boxes:
        cv2.putText(img, b.text, (b.x_px + b.pad_px, b.baseline_px), FONT, b.scale, b.colour_bgr, b.thickness_px, cv2.LINE_AA)
