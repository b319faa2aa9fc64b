"""Perception on the real recorded data (../shared/data): lanes, confidence, brightness, occlusion, steering."""

from __future__ import annotations

from pathlib import Path

import cv2
import numpy as np
import pytest
from tests.perturb import darkened, over_exposed, with_vehicle

import fearguard as fg
from fearguard.vision.frame import FramePipeline


@pytest.fixture(scope="module")
def stills(shared_data: Path) -> dict[str, np.ndarray]:
    paths = sorted((shared_data / "road" / "images").glob("*.jpg"))
    assert len(paths) == 14, f"expected the 14 road stills, found {len(paths)}"
    return {p.name: cv2.imread(str(p)) for p in paths}


@pytest.fixture(scope="module")
def untouched(stills):
    return {name: fg.analyze_frame(img) for name, img in stills.items()}


def both_found(a) -> bool:
    return a.evidence is not None and a.evidence.support_left > 0 and a.evidence.support_right > 0


def test_both_boundaries_found_on_at_least_12_of_14_stills(untouched):
    found = [name for name, a in untouched.items() if both_found(a)]
    assert len(found) >= 12, f"both boundaries on {len(found)}/14: missing {sorted(set(untouched) - set(found))}"


def test_untouched_stills_have_high_confidence_and_plausible_cues(untouched):
    for name, a in untouched.items():
        assert a.lane_confidence >= 0.6, (name, a.evidence)
        assert 40 < a.brightness < 200, (name, a.brightness)
        assert a.occlusion <= 0.1, (name, a.occlusion)
        assert a.steering_deg is not None and abs(a.steering_deg) < 5, (name, a.steering_deg)


def test_over_exposure_washes_the_lane_out(stills, untouched):
    for name, img in stills.items():
        a = fg.analyze_frame(over_exposed(img))
        assert a.lane_confidence < 0.3, (name, a.evidence)
        assert a.brightness > untouched[name].brightness + 50, name
        assert a.exposure.saturated_share > 0.5, name


def test_darkness_hides_the_lane(stills, untouched):
    for name, img in stills.items():
        a = fg.analyze_frame(darkened(img))
        assert a.lane_confidence < 0.3, (name, a.evidence)
        assert a.brightness < untouched[name].brightness / 4, name


def test_an_occluding_vehicle_raises_occlusion_and_lowers_confidence(stills, untouched):
    """Below 0.3 on 13 of 14 stills; on pale concrete (test1) it falls from 0.99 to about 0.4 (known, in the docs)."""
    results = {name: fg.analyze_frame(with_vehicle(img)) for name, img in stills.items()}
    for name, a in results.items():
        assert a.lane_confidence < 0.5, (name, a.evidence)
        assert a.occlusion >= untouched[name].occlusion + 0.3, (name, a.occlusion)
    low = [name for name, a in results.items() if a.lane_confidence < 0.3]
    assert len(low) >= 13, sorted(set(results) - set(low))


def test_a_white_vehicle_lowers_confidence_on_most_stills(stills, untouched):
    """Known weakness: a white box wider than the lane on pale concrete (test1, test4, test5) looks like road
    by brightness and its underside blob is too wide for a vehicle in the lane; confidence still falls."""
    results = {name: fg.analyze_frame(with_vehicle(img, colour=(200, 200, 205))) for name, img in stills.items()}
    low = [name for name, a in results.items() if a.lane_confidence < 0.3]
    assert len(low) >= 9, f"white vehicle lowered confidence below 0.3 on {len(low)}/14: {sorted(set(stills) - set(low))}"
    assert all(a.lane_confidence < untouched[name].lane_confidence for name, a in results.items())


def test_the_occluding_vehicle_is_found_as_a_lead_straight_ahead(stills):
    img = stills["solidWhiteRight.jpg"]
    a = fg.analyze_frame(with_vehicle(img, box=(0.4, 0.62, 0.6, 0.75)))
    assert a.lead is not None and abs(a.lead.bearing_deg) < 3.0
    assert a.lead.range_m is None  # no camera mounting height: no ground-plane range
    cam = fg.CameraModel.default(img.shape[1], img.shape[0], mount_height_m=1.2, pitch_deg=0.0)
    b = fg.analyze_frame(with_vehicle(img, box=(0.4, 0.62, 0.6, 0.75)), camera=cam)
    assert b.lead is not None and b.lead.range_m is not None and 3.0 < b.lead.range_m < 30.0


def _replay(path: Path, every: int = 1) -> tuple[float, np.ndarray]:
    cap = cv2.VideoCapture(str(path))
    pipe = FramePipeline()
    both, angles, n = 0, [], 0
    while True:
        ok, frame = cap.read()
        if not ok:
            break
        a = pipe.process(frame, t_s=n / 25.0)
        n += 1
        both += both_found(a)
        angles.append(a.steering_deg if a.steering_deg is not None else np.nan)
    assert n > 100, f"{path.name}: only {n} frames decoded"
    return both / n, np.asarray(angles)


@pytest.mark.parametrize("name", ["solidWhiteRight.mp4", "solidYellowLeft.mp4"])
def test_videos_lanes_found_and_steering_smooth(shared_data: Path, name: str):
    share, angles = _replay(shared_data / "road" / "video" / name)
    assert share >= 0.95, f"{name}: both boundaries on {share:.1%} of frames"
    assert not np.isnan(angles).any()
    assert np.diff(angles).std() <= 2.0, f"{name}: steering change std {np.diff(angles).std():.2f} deg"
