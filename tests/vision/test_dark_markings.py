"""Dark tape (black, dark blue, dark red, dark green on a paler floor) is found as light paint is, with ``markings="dark"``.

The frames are drawn here with varied floors, tape colours, tape widths and lane positions (seeded): a track in
perspective, two tape lines meeting at a vanishing point above the road region, floor grain as noise.
"""

from __future__ import annotations

import cv2
import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from fearguard.lane import MARKINGS
from fearguard.vision.frame import FramePipeline
from fearguard.vision.lane_steering import HoughLaneSteering
from fearguard.vision.lanes import marking_view

W, H = 320, 240
FLOORS = ((150, 160, 165), (110, 170, 200), (150, 190, 150), (200, 185, 170))  # BGR: grey mat, wood, pale green, pale blue
DARK_TAPES = ((20, 20, 20), (90, 30, 20), (25, 25, 100), (30, 70, 25))  # black, dark blue, dark red, dark green


def track_frame(floor: tuple[int, int, int], tape: tuple[int, int, int], width_px: int, centre_px: float, seed: int) -> np.ndarray:
    """A floor with two tape lines from the bottom corners of a lane to a vanishing point at 45 % of the height."""
    rng = np.random.default_rng(seed)
    img = np.empty((H, W, 3), np.uint8)
    img[:] = floor
    img = np.clip(img.astype(np.int16) + rng.normal(0, 4, img.shape).astype(np.int16), 0, 255).astype(np.uint8)
    vp = (centre_px, 0.45 * H)
    for bottom_u in (centre_px - 0.36 * W, centre_px + 0.36 * W):
        far = (vp[0] + 0.3 * (bottom_u - vp[0]), vp[1] + 0.3 * (H - vp[1]))  # the tape ends before the vanishing point
        cv2.line(img, (round(bottom_u), H), (round(far[0]), round(far[1])), tape, width_px, cv2.LINE_AA)
    return img


def settled(pipeline_markings: str, frame: np.ndarray, frames: int = 8) -> float:
    p = FramePipeline(None, 20.0, markings=pipeline_markings)
    a = None
    for _ in range(frames):
        a = p.process(frame)
    assert a is not None
    return a.lane_confidence


@settings(max_examples=12, deadline=None, derandomize=True)
@given(floor=st.sampled_from(FLOORS), tape=st.sampled_from(DARK_TAPES), width=st.integers(3, 9),
       centre=st.floats(0.42 * W, 0.58 * W), seed=st.integers(0, 1000))
def test_dark_tape_is_a_lane_with_dark_markings_and_not_with_light_ones(floor, tape, width, centre, seed) -> None:
    frame = track_frame(floor, tape, width, centre, seed)
    assert settled("dark", frame) >= 0.6
    assert settled("light", frame) <= 0.2


@pytest.mark.parametrize("floor", [(40, 40, 45), (60, 50, 45)])
def test_white_tape_on_a_dark_floor_is_no_lane_with_dark_markings(floor) -> None:
    """The floor between two light lines is wide, not a dark line: the wrong markings do not invent a lane."""
    frame = track_frame(floor, (235, 235, 235), 6, W / 2, 3)
    assert settled("light", frame) >= 0.6
    assert settled("dark", frame) <= 0.2


def test_light_markings_read_the_picture_as_it_is_and_dark_ones_only_the_road_rows_inverted() -> None:
    hls = np.random.default_rng(0).integers(0, 256, (40, 30, 3), dtype=np.uint8)
    assert marking_view(hls, 10, 29, "light") is hls
    dark = marking_view(hls, 10, 29, "dark")
    assert np.array_equal(dark[10:30, :, 1], 255 - hls[10:30, :, 1])
    assert not dark[10:30, :, 2].any()
    assert np.array_equal(dark[10:30, :, 0], hls[10:30, :, 0])
    assert np.array_equal(dark[:10], hls[:10]) and np.array_equal(dark[30:], hls[30:])


def test_the_markings_are_one_of_the_known_kinds() -> None:
    assert MARKINGS == ("light", "dark")
    with pytest.raises(ValueError, match="markings"):
        HoughLaneSteering(markings="black")
    with pytest.raises(ValueError, match="markings"):
        marking_view(np.zeros((4, 4, 3), np.uint8), 0, 3, "grey")
    assert HoughLaneSteering(markings="dark").pipeline.markings == "dark"


SATURATED_FLOORS = ((110, 170, 200), (60, 120, 190), (40, 110, 215))  # BGR: wood, a darker wood, an orange tarp


@pytest.mark.parametrize("floor", SATURATED_FLOORS)
def test_a_saturated_floor_is_the_road_and_an_object_on_it_still_hides_the_lane(floor) -> None:
    """A wood floor or an orange tarp is as saturated as car paint; it is the road, not an object over the whole lane.
    A box on it — blue, white, black — still is one."""
    frame = track_frame(floor, DARK_TAPES[0], 5, W / 2, 1)
    p = FramePipeline(None, 20.0, markings="dark")
    for _ in range(8):
        a = p.process(frame)
    assert a.occlusion <= 0.2 and a.lane_confidence >= 0.6
    for box in ((230, 130, 40), (240, 240, 240), (15, 15, 15)):
        boxed = frame.copy()
        cv2.rectangle(boxed, (W // 2 - 40, round(0.62 * H)), (W // 2 + 40, round(0.9 * H)), box, -1)
        b = p.process(boxed)
        assert b.occlusion >= 0.3 or b.lane_confidence <= 0.5, box
