"""The bending lane model through gaps in the paint and past what only looks like paint (ground_lanes: ``coast``,
``_expected_lanes``, ``_resolved``, ``_edge_of_wide_paint``).

Pictures are projected pixel by pixel from the ground plane (``test_lane_model_for_camera.floor``) through cameras of
several heights, lane widths and tape colours; the pure parts (``coast``, the fit of a short dash) are checked on
boundaries built by hand. The closed-loop proof is the simulator's markings_end, sparse_dashes and
occluding_traffic_follow_lead with the bending model (docs/perception.md, "Not the default yet")."""

from __future__ import annotations

import math

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from tests.vision.test_lane_model_for_camera import HEIGHT_M, MAT, WHITE, YELLOW, H, W, camera_at, floor, ground_of_pixels

from fearguard.camera import CameraModel
from fearguard.vision import ground_lanes as gl
from fearguard.vision.frame import FramePipeline

ORIGIN = (np.zeros(1), np.zeros(1))


def _pipe(height_m: float) -> tuple[FramePipeline, object]:
    cam = camera_at(height_m)
    return FramePipeline(cam, 30.0, ground=gl.GroundLaneSpec.for_camera(cam)), cam


def _line(y_m: float, support: float = 1.0) -> gl.GroundBoundary:
    """A straight boundary along the heading y_m to the left, seen from 0.1 to 0.5 m."""
    return gl.GroundBoundary(0.0, 0.0, 1.0, -y_m, (0.1, y_m), (0.5, y_m), support, 40)


SPEC = gl.GroundLaneSpec(lane_width_m=0.3)


@pytest.mark.parametrize("height_m", [HEIGHT_M, 0.15, 0.4])
@pytest.mark.parametrize("lane_widths", [2.2, 3.0])
def test_where_the_paint_ends_on_a_plain_floor_nothing_is_hidden(height_m: float, lane_widths: float) -> None:
    """A crossing without tape: the lane the car was in (and, on a fresh start, a default lane) lies on plain floor, so
    the occlusion is low and the confidence falls because no paint is seen — not because something hides it (with no
    boundary expected at all, every such frame read fully occluded)."""
    lane_m = lane_widths * height_m
    taped, cam = _pipe(height_m)
    for k in range(6):
        taped.process(floor(cam, lane_m, tape_m=0.1 * height_m, seed=k), t_s=k / 30)
    plain = floor(cam, lane_m, left=None, right=None, seed=7)
    late = None
    for k in range(6, 40):  # past the hold: nothing of the lane is seen any more
        late = taped.process(plain, t_s=k / 30)
    fresh, _ = _pipe(height_m)
    first = fresh.process(plain, t_s=0.0)
    for a in (late, first):
        assert a is not None and a.occlusion <= 0.1
        assert a.lane_confidence <= 0.1


@pytest.mark.parametrize("height_m", [HEIGHT_M, 0.15])
@pytest.mark.parametrize("colour", [WHITE, YELLOW])
def test_a_side_missed_between_two_dashes_is_held_then_let_go(height_m: float, colour: tuple[int, int, int]) -> None:
    """The left line missing for a few frames (between two dashes) while the right one is seen: the left is held a lane
    width over from the right, the confidence stays up; missing longer than SUPPORT_HOLD_S it is let go, and the
    confidence is what one line gives (at most a half)."""
    lane_m = 2.5 * height_m
    pipe, cam = _pipe(height_m)
    for k in range(8):
        pipe.process(floor(cam, lane_m, left=colour, tape_m=0.1 * height_m, seed=k), t_s=k / 30)
    gap = floor(cam, lane_m, left=None, tape_m=0.1 * height_m, seed=20)
    held = pipe.process(gap, t_s=8 / 30)
    g = held.ground
    assert g is not None and g.coasted == (True, False) and g.left is not None and g.right is not None
    width = -float(g.left.distance(np.array([g.right.start[0]]), np.array([g.right.start[1]]))[0])
    assert width == pytest.approx(pipe.ground.lane_width_m, rel=0.02)  # the right one a lane width over
    assert held.lane_confidence >= 0.6
    late = None
    for k in range(9, 9 + int(gl.SUPPORT_HOLD_S * 30) + 2):
        late = pipe.process(gap, t_s=k / 30)
    assert late is not None and late.ground is not None and not late.ground.coasted[0]
    assert late.lane_confidence <= 0.5


def test_coast_holds_both_sides_as_last_seen_when_neither_is_found_and_fades() -> None:
    before = gl.GroundLanes(_line(0.15), _line(-0.15), 1.0, 0, held=(1.0, 0.8), unseen_s=(0.15, 0.3))
    now = gl.coast(gl.GroundLanes(None, None, 1.0, 0), before, SPEC)
    assert now.coasted == (True, True)
    assert now.left is not None and now.right is not None
    assert -float(now.left.distance(*ORIGIN)[0]) == pytest.approx(0.15)
    assert now.left.support == 0.0 and now.right.support == 0.0  # nothing of them seen now
    assert now.held == pytest.approx((1.0 * (1 - 0.15 / gl.SUPPORT_HOLD_S), 0.8 * (1 - 0.3 / gl.SUPPORT_HOLD_S)))


@settings(max_examples=60, deadline=None)
@given(st.floats(0.0, 1.0), st.floats(-1.0, 2.0), st.floats(0.0, 1.0), st.booleans())
def test_coast_holds_only_a_line_seen_well_and_never_claims_more_than_it_held(held: float, unseen_s: float, now_support: float,
                                                                             other_found: bool) -> None:
    """Whatever the hold: a side is held only when it was seen well (held ≥ COAST_SUPPORT_MIN) within the hold and
    time went forward; its held support never exceeds what it held; a side found keeps its own support at least."""
    before = gl.GroundLanes(_line(0.15), _line(-0.15), 1.0, 0, held=(held, held), unseen_s=(unseen_s, unseen_s))
    right = _line(-0.15, now_support) if other_found else None
    now = gl.coast(gl.GroundLanes(None, right, 1.0, 0), before, SPEC)
    may_hold = held >= gl.COAST_SUPPORT_MIN and 0.0 <= unseen_s < gl.SUPPORT_HOLD_S
    assert now.coasted[0] == may_hold
    assert 0.0 <= now.held[0] <= held
    if other_found:
        assert not now.coasted[1] and now.held[1] >= now_support


def test_a_line_found_elsewhere_than_the_one_held_starts_its_hold_afresh() -> None:
    """A weak fit on another line (a far dash of the next lane) does not inherit the hold of the line seen well before,
    and is not held through the next miss."""
    memory = gl.GroundMemory()
    memory.remember(0.0, gl.GroundLanes(_line(0.15), None, 1.0, 0))
    stray = gl.GroundLanes(_line(0.34, 0.13), None, 1.0, 0, agreement=(0.0, 1.0))
    jumped = gl.coast(stray, memory.priors(0.05), SPEC)
    assert jumped.held[0] == pytest.approx(0.13)
    memory.remember(0.05, jumped)
    assert memory.priors(0.1).held[0] == pytest.approx(0.13)
    missed = gl.coast(gl.GroundLanes(None, None, 1.0, 0), memory.priors(0.1), SPEC)
    assert missed.left is None


@pytest.mark.parametrize("dash_m", [0.08, 0.12, 0.17])
@pytest.mark.parametrize("y_m", [-0.2, -0.25, 0.22])
def test_one_short_dash_with_its_near_end_is_fitted_as_a_line(dash_m: float, y_m: float) -> None:
    """The inner edge of one dash along the heading plus its near end's pixels (an L): a line along the dash, not a
    circle that bends across the lane beyond it."""
    spec = gl.GroundLaneSpec(lane_width_m=0.45, near_m=0.1, far_m=0.7, scale=1.39)
    x0 = 0.3
    along = np.linspace(x0, x0 + dash_m, 30)
    foot = np.full(8, x0)
    side = -1.0 if y_m < 0 else 1.0
    xs = np.concatenate([along, foot])
    ys = np.concatenate([np.full(30, y_m), y_m + side * np.linspace(0.0, 0.025, 8)])
    b = gl.fit_boundary(xs, ys, spec, None)
    assert b is not None
    assert b.curvature_per_m <= 0.05
    # beyond the dash, still beside the car: the near end tilts the line a little (3 cm at the camera, 0.3 m back), a
    # circle through the L crossed the lane
    assert -float(b.distance(*ORIGIN)[0]) * side == pytest.approx(abs(y_m), abs=0.05)


@pytest.mark.parametrize("radius_m", [0.6, 1.0, -0.7])
def test_a_curve_seen_over_half_the_fit_range_keeps_its_curvature(radius_m: float) -> None:
    spec = gl.GroundLaneSpec(lane_width_m=0.236)
    s = np.linspace(0.0, 0.3, 60)
    theta = s / abs(radius_m)
    xs = 0.08 + abs(radius_m) * np.sin(theta)
    ys = math.copysign(1.0, radius_m) * (abs(radius_m) * (1 - np.cos(theta))) - 0.12
    b = gl.fit_boundary(xs, ys, spec, None)
    assert b is not None and b.curvature_per_m == pytest.approx(1.0 / abs(radius_m), rel=0.1)


def sunlit_patch(camera: CameraModel, lane_m: float, patch_m: float, seed: int = 0) -> np.ndarray:
    """A shaded mat (a tree's shadow over everything) with one sunlit patch: from 2 to 3.5 camera heights ahead, from the
    lane's right edge ``patch_m`` to the right — bounded by shade on every side, as the gaps between tree shadows are.
    No tape anywhere."""
    x, y = ground_of_pixels(camera)
    h = float(camera.mount_height_m)
    img = np.clip(np.random.default_rng(seed).normal(MAT * 0.45, 1.5, (H, W, 3)), 0, 255).astype(np.uint8)
    img[~np.isfinite(x)] = (200, 160, 120)
    sun = (x >= 2.0 * h) & (x <= 3.5 * h) & (y <= -lane_m / 2) & (y >= -lane_m / 2 - patch_m)
    img[sun] = np.clip(np.random.default_rng(seed + 1).normal(MAT, 1.5, (int(sun.sum()), 3)), 0, 255).astype(np.uint8)
    return img


@pytest.mark.parametrize("height_m", [HEIGHT_M, 0.15, 0.3])
def test_the_edge_of_a_sunlit_patch_between_shadows_is_no_boundary(height_m: float) -> None:
    """A sunlit patch between tree shadows passes the paint test (brighter than the shade round it by more than tape is
    than a mat); its edge along the lane is not taken for the lane's right boundary, however straight. A patch as
    narrow as tape is (the test can fail: the same picture with tape-wide sun is read as a boundary)."""
    lane_m = 2.5 * height_m
    cam = camera_at(height_m)
    spec = gl.GroundLaneSpec.for_camera(cam)
    got = []
    for patch_m in (1.5 * height_m, 0.2 * height_m):
        a = FramePipeline(cam, 30.0, ground=spec).process(sunlit_patch(cam, lane_m, patch_m), t_s=0.0)
        got.append(a.ground.right if a.ground is not None else None)
    assert got[0] is None
    assert got[1] is not None
