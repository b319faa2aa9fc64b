"""Issue 11 on the real stills: occluders of any colour, garbage frames, clean frames (../shared/data).

An occluder appears in front of a car that has been watching the clean road (the road appearance model learns from
recent frames, as on the road); fear is read after 3 frames with it (the confidence is a 3-frame median).
"""

from __future__ import annotations

import copy
from pathlib import Path

import cv2
import numpy as np
import pytest
from tests.perturb import OCCLUDER_BOXES, OCCLUDER_COLOURS, garbage_frames, watched, with_box

import fearguard as fg

WARM_FRAMES = 5
OCCLUDED_FRAMES = 3


@pytest.fixture(scope="module")
def stills(shared_data: Path) -> dict[str, np.ndarray]:
    paths = sorted((shared_data / "road" / "images").glob("*.jpg"))
    assert len(paths) == 14, f"expected the 14 road stills, found {len(paths)}"
    return {p.name: cv2.imread(str(p)) for p in paths}


def _guard() -> fg.FearGuard:
    return fg.FearGuard(fg.HoughLaneSteering(), vehicle=fg.VehicleLimits(has_ultrasonic=False, has_qr_localisation=False))


@pytest.fixture(scope="module")
def warmed(stills):
    """Per still: a supervisor that watched it for WARM_FRAMES frames, and its command then."""
    out = {}
    for name, img in stills.items():
        guard = _guard()
        out[name] = (guard, watched(guard, [img] * WARM_FRAMES))
    return out


def test_clean_stills_are_seen_clearly(warmed, stills):
    """Occlusion ≤ 0.05 and confidence ≥ 0.6 on every still; tracked, ≥ 0.6 on 12 of 14 and ≥ 0.45 on all (test1:
    a faint dashed line on pale concrete; test4: shadow edges beside the yellow line on pale concrete)."""
    tracked_clear = 0
    for name, (_, cmd) in warmed.items():
        still = fg.analyze_frame(stills[name])
        assert cmd.cues.occlusion <= 0.05 and still.occlusion <= 0.05, name
        assert still.lane_confidence >= 0.6, name
        assert cmd.cues.lane_confidence >= 0.45, name
        tracked_clear += cmd.cues.lane_confidence >= 0.6
    assert tracked_clear >= 12


@pytest.mark.slow
def test_occluders_of_any_colour_raise_occlusion_and_fear(warmed, stills):
    """5 colours × 3 placements × 14 stills: occlusion ≥ 0.3 and fear ≥ clean + 0.2 in ≥ 90 % of the cases."""
    failures, cases = [], 0
    for name, (guard, clean) in warmed.items():
        for box_name, box in OCCLUDER_BOXES.items():
            for colour_name, colour in OCCLUDER_COLOURS.items():
                occluded = with_box(stills[name], box, colour)
                cmd = watched(copy.deepcopy(guard), [occluded] * OCCLUDED_FRAMES, WARM_FRAMES)
                cases += 1
                if not (cmd.cues.occlusion >= 0.3 and cmd.fear >= clean.fear + 0.2):
                    failures.append(f"{name} {box_name} {colour_name}: occlusion {cmd.cues.occlusion:.2f}, "
                                    f"fear {cmd.fear:.2f} (clean {clean.fear:.2f})")
    assert cases == 14 * len(OCCLUDER_BOXES) * len(OCCLUDER_COLOURS)
    assert len(failures) <= 0.1 * cases, "\n".join(failures)


def test_garbage_frames_give_no_confidence(shared_data: Path):
    """Noise, random textures and the 20 chessboard photos: lane_confidence < 0.3 in every case, stateless and tracked."""
    frames = garbage_frames()
    frames.update({p.name: cv2.imread(str(p)) for p in sorted((shared_data / "camera_cal").glob("*.jpg"))})
    assert len(frames) == 34
    high = []
    for name, frame in frames.items():
        alone = fg.analyze_frame(frame).lane_confidence
        tracked = watched(_guard(), [frame] * 4).cues.lane_confidence
        if not (alone < 0.3 and tracked < 0.3):
            high.append(f"{name}: {alone:.2f} alone, {tracked:.2f} tracked")
    assert not high, "\n".join(high)


IN_LANE_BOXES = {  # (u0, v0, u1, v1) shares of the frame: inside the ego lane of these dash-cam stills, over no boundary
    "small": (0.44, 0.70, 0.56, 0.76),  # 12 % of the picture, a third of the lane there: a cone, a child, a tyre
    "medium": (0.40, 0.72, 0.60, 0.80),
}


def test_something_in_the_lane_that_hides_no_boundary_hides_the_lane_beyond_it(warmed, stills):
    """Issue 33: anything in the lane counts as occlusion, however small — here without a camera model, so there is
    no range: the lane beyond it is not seen (``obstacle.lane_hidden_beyond``). 2 sizes × 4 colours × 14 stills:
    occlusion ≥ 0.3 and fear ≥ clean + 0.2 in ≥ 85 % of the cases. Not the grey box: of the asphalt's own grey, it
    differs from the road only by being smooth, and so does sunlit or wet smooth asphalt (docs/perception.md)."""
    failures, cases = [], 0
    colours = {k: v for k, v in OCCLUDER_COLOURS.items() if k != "grey"}
    for name, (guard, clean) in warmed.items():
        for box_name, box in IN_LANE_BOXES.items():
            for colour_name, colour in colours.items():
                cmd = watched(copy.deepcopy(guard), [with_box(stills[name], box, colour)] * OCCLUDED_FRAMES, WARM_FRAMES)
                cases += 1
                if not (cmd.cues.occlusion >= 0.3 and cmd.fear >= clean.fear + 0.2):
                    failures.append(f"{name} {box_name} {colour_name}: occlusion {cmd.cues.occlusion:.2f}, "
                                    f"fear {cmd.fear:.2f} (clean {clean.fear:.2f})")
    assert len(failures) <= 0.15 * cases, "\n".join(failures)
