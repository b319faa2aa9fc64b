"""The annotated-video overlay stays readable at every frame size: text inside the frame, boxes apart, glyphs in their boxes."""

from __future__ import annotations

import cv2
import numpy as np
import pytest

import fearguard as fg
from fearguard.outputs import text_layout
from fearguard.outputs.overlay import annotate, overlay_boxes
from fearguard.outputs.text_layout import TextStyle

SIZES = [(160, 120), (320, 240), (640, 480), (1280, 720)]


def _emergency_command() -> fg.Command:
    guard = fg.FearGuard(lambda f: 0.0, vehicle=fg.VehicleLimits(has_ultrasonic=False, has_qr_localisation=False))
    cmd = None
    for i in range(5):
        cmd = guard.step(fg.Observation(t_s=i * 0.05, speed_mps=1.0, cues=fg.Cues(0.1, 10.0, 0.9, 3.0, 0.5)))
    assert cmd is not None and cmd.mode is fg.Mode.EMERGENCY
    return cmd


@pytest.mark.parametrize(("width", "height"), SIZES)
def test_every_text_box_lies_inside_the_frame_and_no_two_overlap(width: int, height: int) -> None:
    boxes = overlay_boxes(width, height, _emergency_command(), "t 12.3 s", reasons=2)
    assert len(boxes) >= 2
    for b in boxes:
        assert 0 <= b.x_px and b.x_px + b.w_px <= width, b
        assert 0 <= b.y_px and b.y_px + b.h_px <= height, b
    for i, a in enumerate(boxes):
        for b in boxes[i + 1:]:
            assert not a.overlaps(b), (a, b)


@pytest.mark.parametrize(("width", "height"), SIZES)
def test_fear_and_limit_are_always_shown_in_full(width: int, height: int) -> None:
    cmd = _emergency_command()
    text = " ".join(b.text for b in overlay_boxes(width, height, cmd, "t 12.3 s"))
    assert f"fear {cmd.fear:.2f}" in text
    assert f"limit {cmd.speed_limit_mps:.2f} m/s" in text
    assert "EMERGENCY STOP" in text


@pytest.mark.parametrize(("width", "height"), SIZES)
def test_drawn_glyphs_stay_inside_their_measured_box(width: int, height: int) -> None:
    """Measured and drawn with one thickness (OpenCV 5 changes advances with thickness): no ink outside a box."""
    for box in overlay_boxes(width, height, _emergency_command(), "t 12.3 s"):
        canvas = np.zeros((height, width, 3), np.uint8)
        text_layout.draw(canvas, [box])
        ink = np.argwhere(canvas.max(axis=2) > 0)
        assert ink.size, box
        (y0, x0), (y1, x1) = ink.min(axis=0), ink.max(axis=0)
        assert x0 >= box.x_px and x1 < box.x_px + box.w_px, (box, x0, x1)
        assert y0 >= box.y_px and y1 < box.y_px + box.h_px, (box, y0, y1)


def test_text_grows_with_the_frame_but_never_below_legibility() -> None:
    scales = [TextStyle.for_frame(w, h).scale for w, h in SIZES]
    assert scales == sorted(scales)
    assert scales[0] >= text_layout.MIN_FONT_SCALE
    cap_px = [cv2.getTextSize("H", text_layout.FONT, s, 1)[0][1] for s in scales]
    assert cap_px[0] >= 6  # readable at Donkey's 160×120


def test_a_word_wider_than_the_frame_is_cut_with_an_ellipsis() -> None:
    style = TextStyle.for_frame(160, 120)
    lines = text_layout.fit_lines("x" * 200, style, 160)
    assert len(lines) == 1 and lines[0].endswith(text_layout.ELLIPSIS)
    assert style.size(lines[0])[0] <= 160 - 2 * style.pad_px


def test_phrases_stay_whole_when_the_frame_is_wide_and_wrap_when_narrow() -> None:
    phrases = ["EMERGENCY STOP", "fear 0.92 VERY_HIGH", "limit 0.00 m/s"]
    wide = text_layout.flow(phrases, TextStyle.for_frame(1280, 720), 1260)
    narrow = text_layout.flow(phrases, TextStyle.for_frame(160, 120), 156)
    assert wide == [text_layout.SEPARATOR.join(phrases)]
    assert len(narrow) >= 2 and all(p in " ".join(narrow) for p in ("EMERGENCY", "0.92", "m/s"))


@pytest.mark.parametrize(("width", "height"), SIZES)
def test_annotate_returns_a_frame_of_the_same_size_with_the_overlay_drawn(width: int, height: int) -> None:
    frame = np.full((height, width, 3), 128, np.uint8)
    out = annotate(frame, _emergency_command(), None, "t 1.0 s")
    assert out.shape == frame.shape and not np.array_equal(out, frame)
    assert np.array_equal(frame, np.full((height, width, 3), 128, np.uint8))  # the input is not drawn on
    unsupervised = annotate(frame, None, None, "v 1.50 m/s")
    assert unsupervised.shape == frame.shape and not np.array_equal(unsupervised, frame)
