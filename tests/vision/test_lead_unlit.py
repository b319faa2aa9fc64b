"""A vehicle whose tail lights are not seen is a lead once it is seen moving along the road; a dark patch never is.

MetaDrive's SUV renders its lamps dark grey: the lead search (dark underside + tail-light red) never boxed it, the
object search found it 6 m ahead, and the car made an EMERGENCY STOP behind a car doing 8.3 m/s (seed 18, 74 % of the
expert's progress). A lamp-less box now becomes a lead when its ground range, with the car's own speed added, shows
it moving along the road at half the car's speed or more, beyond the fit's noise (vision/lead.py). A shadow, a tar
patch or a pothole stands still on the ground. Drawn here on the lanes of ``test_bend`` (OpenCV polygons through a
pinhole camera, not any simulator's renderer): the vehicle of ``test_lead_far_ahead`` with grey lamps, five body
colours, many cameras, speeds and gaps; dark patches of many sizes, placed anywhere in the lane.
"""

from __future__ import annotations

import math
from dataclasses import replace

import cv2
import numpy as np
from hypothesis import assume, given, settings
from hypothesis import strategies as st
from tests.vision.test_bend import PAINTS, _boundary, camera, curved_lane
from tests.vision.test_lead_far_ahead import BODIES, true_bearing_deg, with_vehicle

from fearguard.observation import LeadBox
from fearguard.vision.bend import Bend
from fearguard.vision.frame import FramePipeline, _in_bent_lane
from fearguard.vision.lanes import LaneLine
from fearguard.vision.lead import (
    LOST_AFTER_S,
    MOTION_WINDOW_S,
    RANGE_NOISE_SHARE,
    LeadTracker,
    moving_over_ground,
)

FPS = 10.0  # MetaDrive's step
RIGID_PX_M = 500.0  # [px·m] a 1.8 m wide car through a 280 px lens: its box width × its range
GREY_LAMPS = (45, 48, 50)  # BGR: MetaDrive's SUV lamps are dark grey (hue 0-10, saturation <= 74, lightness <= 25 %)
roads = dict(
    fov=st.floats(60.0, 90.0), height=st.floats(1.2, 1.6), pitch=st.floats(1.0, 5.0),
    radius=st.sampled_from([500.0, -500.0, 1000.0, math.inf]), lane=st.floats(3.0, 3.8), paint=st.sampled_from(sorted(PAINTS)),
    grey=st.integers(80, 140), seed=st.integers(0, 1000),
)


def drive(cam, radius, lane, paint, grey, seed, draw, speeds_mps, seconds: float) -> list:
    """A pipeline fed the road for ``seconds`` at FPS with ``draw(frame, t)`` over it and the car's speed
    ``speeds_mps`` (None: unknown); the analysis of every frame."""
    p = FramePipeline(cam, FPS)
    out = []
    for i in range(int(seconds * FPS)):
        t = i / FPS
        frame = draw(curved_lane(cam, radius, lane, PAINTS[paint], grey, False, seed + i), t)
        out.append(p.process(frame, t, speed_mps=speeds_mps))
    return out


@settings(max_examples=20, deadline=None, derandomize=True)
@given(**roads, own=st.floats(5.0, 30.0), share=st.floats(0.7, 1.1), ahead=st.floats(10.0, 22.0), width=st.floats(1.6, 2.0),
       body=st.sampled_from(sorted(BODIES)))
def test_a_lampless_vehicle_moving_ahead_becomes_the_lead(fov, height, pitch, radius, lane, paint, grey, seed, own, share,
                                                          ahead, width, body) -> None:
    """A vehicle with grey lamps in the ego lane 10-22 m ahead, moving at 0.7-1.1 × the car's 5-30 m/s: boxed as the lead
    within 2 s at its bearing (1.5°); with the car's speed unknown it is never boxed (no motion can be told)."""
    cam = camera(fov, height, pitch)
    assume(cam.fx_px * width / ahead >= 14.0)
    gap = lambda t: ahead + (share - 1.0) * own * t  # noqa: E731
    assume(gap(2.0) >= 7.0)

    def draw(frame, t):
        return with_vehicle(frame, cam, radius, gap(t), 0.0, width, BODIES[body], lamps=GREY_LAMPS)

    seen = drive(cam, radius, lane, paint, grey, seed, draw, own, 2.0)
    last = seen[-1]
    assert last.lead is not None, [a.lead_box for a in seen[-3:]]
    assert abs(last.lead.bearing_deg - true_bearing_deg(cam, radius, gap(1.9), 0.0)) <= 1.5
    assert all(a.lead is None for a in drive(cam, radius, lane, paint, grey, seed, draw, None, 2.0))


def dark_patch(cam, radius, s_m, lateral_m, width_m, length_m, shade):
    """A dark quadrilateral lying on the ground (a shadow, tar, a pothole) from ``s_m`` to ``s_m + length_m`` ahead."""
    def draw(frame, s_now):
        pts = []
        for s, lat in ((s_now, -0.5), (s_now, 0.5), (s_now + length_m, 0.5), (s_now + length_m, -0.5)):
            x, y = _boundary(radius, lateral_m + lat * width_m, np.array([s]))
            u, v, _ = cam.project_ground(x, y)
            pts.append((u[0], v[0]))
        out = frame.copy()
        cv2.fillPoly(out, [np.int32(np.round(np.array(pts) * 4))], (shade, shade, shade + 2), shift=2)
        return out
    return draw


@settings(max_examples=25, deadline=None, derandomize=True)
@given(**roads, own=st.floats(0.0, 35.0), ahead=st.floats(8.0, 40.0), lateral=st.floats(-0.3, 0.3), width=st.floats(0.8, 2.4),
       length=st.floats(0.3, 3.0), shade=st.integers(10, 45))
def test_a_dark_patch_on_the_road_is_never_the_lead(fov, height, pitch, radius, lane, paint, grey, seed, own, ahead, lateral,
                                                     width, length, shade) -> None:
    """A dark patch of 0.8-2.4 × 0.3-3 m lying still on the road ahead, the car at 0-35 m/s: never a lead, on any frame
    of 2 s, however vehicle-like its underside."""
    cam = camera(fov, height, pitch)
    patch = dark_patch(cam, radius, 0.0, lateral * lane, width, length, shade)
    seen = drive(cam, radius, lane, paint, grey, seed, lambda frame, t: patch(frame, ahead - own * t), own, 2.0)
    assert all(a.lead is None for a in seen)


@settings(max_examples=200, deadline=None, derandomize=True)
@given(own=st.floats(0.0, 40.0), start=st.floats(3.0, 60.0), fps=st.sampled_from([10.0, 20.0, 30.0]),
       noise=st.floats(0.0, 1.0), seed=st.integers(0, 10_000))
def test_ranges_closing_at_the_cars_speed_are_not_moving(own, start, fps, noise, seed) -> None:
    """Ranges of a thing standing on the ground — closing at exactly the car's speed, with noise up to the floor the fit
    assumes (RANGE_NOISE_SHARE of the range) — never read as moving."""
    t = np.arange(0.0, MOTION_WINDOW_S + 1e-9, 1.0 / fps)
    r = start + own * (t[-1] - t)  # it ends ``start`` metres ahead
    rng = np.random.default_rng(seed)
    r = r * (1.0 + noise * RANGE_NOISE_SHARE * rng.uniform(-1.0, 1.0, len(t)))
    assert not moving_over_ground(np.column_stack([t, r, np.full_like(t, own), RIGID_PX_M / r]))


@settings(max_examples=200, deadline=None, derandomize=True)
@given(own=st.floats(3.0, 40.0), share=st.floats(0.85, 1.5), start=st.floats(5.0, 25.0), fps=st.sampled_from([10.0, 20.0, 30.0]))
def test_a_car_ahead_doing_most_of_the_cars_speed_is_moving(own, share, start, fps) -> None:
    """Clean ranges of a car 5-25 m ahead moving at 0.85-1.5 × the car's 3-40 m/s over the window: moving, whenever the
    car covers 40 % of the gap in a second or more (slower, or farther, and a box's range noise could hide a standing
    thing's closing: 3 m/s behind a car 17 m ahead is not told in one second)."""
    t = np.arange(0.0, MOTION_WINDOW_S + 1e-9, 1.0 / fps)
    r = start + (share - 1.0) * own * t
    assume((r > 1.0).all() and own >= 0.4 * start)
    assert moving_over_ground(np.column_stack([t, r, np.full_like(t, own), RIGID_PX_M / r]))


def _box(u: float, v_bottom: float, w: float) -> LeadBox:
    return LeadBox(u - w / 2, v_bottom - 0.8 * w, w, 0.8 * w)


def test_a_lamp_less_box_elsewhere_does_not_replace_a_confirmed_lead() -> None:
    """A confirmed lead (tail lights) keeps its track when a lamp-less box appears somewhere else for a frame; the
    track coasts and is reported as before."""
    tr = LeadTracker()
    for i in range(4):
        assert (tr.update(i * 0.1, _box(160, 150, 40), lit=True, range_m=15.0, speed_mps=10.0) is not None) == (i >= 1)
    kept = tr.update(0.4, _box(60, 200, 30), lit=False, range_m=6.0, speed_mps=10.0)
    assert kept is not None and abs(kept.x_px + kept.w_px / 2 - 160) < 5


def test_a_lamp_less_track_without_speed_or_range_is_never_confirmed() -> None:
    for kw in (dict(range_m=15.0, speed_mps=None), dict(range_m=None, speed_mps=10.0), dict(range_m=math.nan, speed_mps=10.0)):
        tr = LeadTracker()
        assert all(tr.update(i * 0.1, _box(160, 150, 40), lit=False, **kw) is None for i in range(30))


def test_a_track_that_showed_tail_lights_is_left_to_lit_detections() -> None:
    """Lamp-less boxes never move, keep or replace a track that has shown tail lights: where the lead was, it coasts
    on its own motion and is dropped LOST_AFTER_S after its last lit detection, as when only lit boxes were searched."""
    tr = LeadTracker()
    for i in range(3):
        tr.update(i * 0.1, _box(160, 150, 40), lit=True, range_m=15.0, speed_mps=10.0)
    t, shown = 0.2, []
    while t < 0.2 + LOST_AFTER_S + 0.35:
        t += 0.1
        shown.append(tr.update(t, _box(166, 152, 42), lit=False, range_m=14.0, speed_mps=10.0))
    assert all(b is not None and abs(b.x_px + b.w_px / 2 - 160) < 1.0 for b in shown[:4])
    assert shown[-1] is None


def test_a_moving_lamp_less_track_is_dropped_when_only_something_else_is_seen() -> None:
    """A lamp-less lead seen moving, then gone while a standing dark patch elsewhere keeps being boxed: the patch does
    not replace the lead, and the lead is dropped after LOST_AFTER_S (it does not coast for ever)."""
    tr = LeadTracker()
    t, r = 0.0, 20.0
    while not tr.confirmed:
        assert t < 3.0
        tr.update(t, _box(160, 150, 40), lit=False, range_m=r, speed_mps=10.0)
        t, r = t + 0.1, r - 0.2  # it does 8 m/s ahead of a car doing 10
    last = t
    while t < last + LOST_AFTER_S + 0.3:
        out = tr.update(t, _box(60, 210, 30), lit=False, range_m=5.0, speed_mps=10.0)
        t += 0.1
    assert out is None and not tr.confirmed


def test_one_stray_range_does_not_make_a_standing_thing_move() -> None:
    """A standing thing's ranges (closing at the car's 1.5 m/s) with one detection of something else joined at the start
    (0.13 m: tree_shadows seed 13 made a least-squares slope read +2.4 m/s there): not moving."""
    t = np.arange(10) * 0.1
    r = 2.9 - 1.5 * t
    r[0] = 0.13
    assert not moving_over_ground(np.column_stack([t, r, np.full_like(t, 1.5), RIGID_PX_M / np.maximum(r, 0.5)]))


@settings(max_examples=100, deadline=None, derandomize=True)
@given(own=st.floats(3.0, 30.0), share=st.floats(0.85, 1.2), start=st.floats(5.0, 20.0), wobble=st.floats(0.2, 0.5),
       seed=st.integers(0, 10_000))
def test_a_box_that_changes_size_is_no_vehicle(own, share, start, wobble, seed) -> None:
    """Ranges that move like a car's but a box whose size (range × width) wobbles by 20-50 % — a shadow's blob growing,
    splitting, merging — is not a vehicle moving."""
    t = np.arange(11) * 0.1
    r = start + (share - 1.0) * own * t
    width = RIGID_PX_M / r * (1.0 + wobble * np.random.default_rng(seed).choice([-1.0, 1.0], len(t)))
    assert not moving_over_ground(np.column_stack([t, r, np.full_like(t, own), width]))


boxes = st.lists(st.tuples(st.booleans(), st.booleans(), st.floats(40, 280), st.floats(130, 230), st.floats(8, 80)),
                 min_size=1, max_size=40)


@settings(max_examples=150, deadline=None, derandomize=True)
@given(seen=boxes, speed=st.sampled_from([None, 10.0]))
def test_lit_leads_are_as_when_only_lit_boxes_were_searched(seen, speed) -> None:
    """Whatever lamp-less boxes come between (never seen moving here: no speed, or ranges closing at the car's speed),
    the leads reported are, frame by frame, those of a tracker fed the lit boxes alone."""
    both, lit_only = LeadTracker(), LeadTracker()
    for i, (present, lit, u, v, w) in enumerate(seen):
        box = _box(u, v, w) if present else None
        a = both.update(i * 0.1, box, lit=lit, range_m=50.0 - 10.0 * i * 0.1, speed_mps=speed)
        b = lit_only.update(i * 0.1, box if lit else None)
        assert a == b


def test_ranges_without_time_between_show_no_motion() -> None:
    assert not moving_over_ground(np.array([[1.0, 10.0, 5.0, 50.0]] * 12))


def test_in_the_traced_lane_means_between_its_curves_or_half_a_lane_from_the_one_traced() -> None:
    """The bend check for lamp-less boxes: a straight traced lane 100-200 px wide at every row (k = 0, b = 0)."""
    straight = Bend(horizon_v_px=100.0, k_px2=0.0, left=(0.0, 100.0), right=(0.0, 200.0), rows=(120, 230))
    lines = (LaneLine(0.0, 100.0, 1.0, 1), LaneLine(0.0, 200.0, 1.0, 1))
    for bend in (straight, replace(straight, right=None), replace(straight, left=None)):
        assert _in_bent_lane(bend, _box(150.0, 200.0, 40.0), *lines)
        assert not _in_bent_lane(bend, _box(230.0, 200.0, 40.0), *lines)
        assert not _in_bent_lane(bend, _box(70.0, 200.0, 40.0), *lines)
