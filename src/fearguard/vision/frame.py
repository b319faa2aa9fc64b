"""One camera frame → the vision cues, the lead vehicle, QR payloads and the baseline steering angle.

The analysis is six small stages, each a function over plain values:

    prepare (BGR, undistort, working size, road region, grey/HLS, exposure)
      → lanes (detect, track) → lead and occlusion → confidence → QR → steering

``analyze_frame`` is the stateless form (one frame, no history); ``FramePipeline`` is the stateful form.
Both run the same stages; they differ only in the ``Trackers`` they hand them (``vision/trackers.py``:
Kalman tracks, lane memory and the confidence median, or pass-through stand-ins). A supervisor wrapping
``HoughLaneSteering`` analyses each frame once with the steering's pipeline and hands that analysis to
the steering (``perception.FrameSteering``). Frames are analysed at a fixed working width
(``lanes.WORK_WIDTH_PX``); results in pixels are reported in the frame's own pixels.
"""

from __future__ import annotations

import math
import time
from collections.abc import Callable, Mapping
from dataclasses import dataclass, field
from functools import lru_cache

import cv2
import numpy as np

from fearguard.camera import CameraModel
from fearguard.lane import GUIDANCE, MARKINGS
from fearguard.observation import Lead, LeadBox
from fearguard.vision.bend import Bend, trace_bend
from fearguard.vision.confidence import LaneEvidence, agreement, lane_confidence
from fearguard.vision.exposure import Exposure, road_exposure
from fearguard.vision.ground_lanes import GroundLanes, GroundLaneSpec, aim_point, ground_lanes_in_image
from fearguard.vision.lane_tracker import TrackedLanes
from fearguard.vision.lanes import (
    PITCHED_DEG,
    LaneLine,
    RoadRegion,
    assumed_horizon_v_px,
    detect_lanes,
    far_shift_px,
    lane_width_rows,
    marking_view,
    region_mask,
    region_toward,
    road_region,
    work_size,
)
from fearguard.vision.lead import detect_lead, lead_from_box
from fearguard.vision.obstacle import Obstacle, RoutePath, lane_hidden_beyond, search_lane
from fearguard.vision.occlusion import default_lines, hidden_markings, road_appearance, road_reference, surface_maps
from fearguard.vision.qr import detect_qr
from fearguard.vision.steering import aim_point_u, lookahead_row, steering_from_aim
from fearguard.vision.trackers import Trackers

QR_EVERY_N_FRAMES = 3  # [frames] the pipeline scans for QR boards on every 3rd frame: a board stays in view for many
# frames, staleness keeps a 0.15 s resolution at 20 Hz, and the scan (~1.8 ms, ~5.5 ms with a board) costs a third
MIN_FRAME_PX = 16  # [px] frames smaller than this on a side cannot show a road
_NAN = float("nan")
UNKNOWN_EXPOSURE = Exposure(_NAN, _NAN, _NAN)


@dataclass(frozen=True)
class FrameAnalysis:
    """One frame's measurements. NaN cues mean unknown (a bad frame); ``reasons`` says why."""

    lane_confidence: float
    brightness: float
    occlusion: float
    lead: Lead | None
    qr_payloads: tuple[str, ...]
    steering_deg: float | None
    exposure: Exposure = UNKNOWN_EXPOSURE
    evidence: LaneEvidence | None = None
    left: LaneLine | None = None  # boundaries in working pixels (detected, or tracked when stateful)
    right: LaneLine | None = None
    region: RoadRegion | None = None
    scale: float = 1.0  # frame pixels per working pixel
    lead_box: LeadBox | None = None  # in frame pixels
    road_reference: float = _NAN  # grey level of the road just ahead
    reasons: tuple[str, ...] = ()
    timings_ms: Mapping[str, float] = field(default_factory=dict)
    obstacle: Obstacle | None = None  # anything standing in the ego lane, with its ground-plane range (vision/obstacle.py)
    searched_m: float = 0.0  # [m] how far ahead the object search found the lane free of objects or looked (0: no search)
    stop_line_m: float | None = None  # [m] ground range to a painted band across the ego lane (a stop line), if one is seen
    ground: GroundLanes | None = None  # the bending lane in the ground plane, when the pipeline fits one (vision/ground_lanes.py)
    curves_px: tuple[np.ndarray | None, np.ndarray | None] | None = None  # its boundaries as polylines (u, v), frame pixels
    t_s: float = _NAN  # [s] when the frame was taken (what a steering that depends on time, e.g. a fault injector, reads)
    horizon_v_px: float | None = None  # [px] frame row of the horizon the road region assumes (lanes.assumed_horizon_v_px)


def invalid_frame_reason(frame: object) -> str | None:
    """Why a frame cannot be analysed, or None if it is a usable uint8 image."""
    if not isinstance(frame, np.ndarray):
        return f"frame is {type(frame).__name__}, not an image array"
    if frame.dtype != np.uint8:
        return f"frame dtype {frame.dtype}, expected uint8"
    if frame.ndim not in (2, 3) or (frame.ndim == 3 and frame.shape[2] not in (1, 3, 4)):
        return f"frame shape {frame.shape}, expected H×W, H×W×3 (BGR) or H×W×4"
    if min(frame.shape[:2]) < MIN_FRAME_PX:
        return f"frame {frame.shape[1]}×{frame.shape[0]} px is too small"
    return None


def unknown_analysis(reason: str) -> FrameAnalysis:
    """The result for a frame that could not be analysed: every vision cue unknown (worst)."""
    return FrameAnalysis(lane_confidence=_NAN, brightness=_NAN, occlusion=_NAN, lead=None, qr_payloads=(), steering_deg=None,
                         reasons=(reason,))


class FramePipeline:
    """Stateful frame analysis: lane and lead trackers, lane memory. Every call analyses its frame afresh.

    There is no cache: a caller that refills one buffer every frame (``cap.read(buf)``, ring buffers,
    ``np.copyto``) gets that frame's measurements. The camera is fixed at construction. ``trackers``
    (a factory, also used on reset) defaults to the tracking ones; ``Trackers.pass_through`` gives a
    pipeline that agrees with ``analyze_frame`` frame by frame.
    """

    def __init__(
        self, camera: CameraModel | None = None, fps: float = 20.0, *, trackers: Callable[[], Trackers] = Trackers.tracking,
        ground: GroundLaneSpec | None = None, aim_m: float | None = None, markings: str = "light", guidance: str = "two_lines",
    ) -> None:
        if markings not in MARKINGS:
            raise ValueError(f"markings must be one of {', '.join(MARKINGS)}, got {markings!r}")
        if guidance not in GUIDANCE:
            raise ValueError(f"guidance must be one of {', '.join(GUIDANCE)}, got {guidance!r}")
        if markings != "light" and ground is not None:
            raise ValueError("the ground-plane lane model reads light paint only: give dark markings without a ground spec")
        self._markings, self._guidance = markings, guidance
        self._camera = camera
        mounted = camera is not None and camera.mount_height_m is not None  # only a known height places ground distances
        self._ground = ground if mounted else None
        self._aim_m = aim_m if mounted else None
        self.period_s = 1.0 / fps if fps > 0 else 0.05
        self._new_trackers = trackers
        self.trackers = trackers()
        self._frames = 0

    @property
    def ground(self) -> GroundLaneSpec | None:
        """The road the bending ground-plane lane model is fitted for (None: straight image lines), with the lane width
        measured so far when the spec measures it."""
        return self.trackers.ground.spec_now(self._ground) if self._ground is not None else None

    @property
    def aim_m(self) -> float | None:
        """How far ahead of the camera the steering aims (None: ``steering.LOOKAHEAD`` of the road region; a camera
        without a mount height cannot place a distance)."""
        return self._aim_m

    @property
    def camera(self) -> CameraModel | None:
        """The camera model every frame is analysed with (None: an uncalibrated default for the frame size)."""
        return self._camera

    @property
    def markings(self) -> str:
        """The track's markings the lanes are found by (``lane.MARKINGS``): light paint or tape, or dark tape."""
        return self._markings

    @property
    def guidance(self) -> str:
        """What the track guides the car by (``lane.GUIDANCE``): the lane's two boundaries, or one line."""
        return self._guidance

    def reset(self) -> None:
        """Forget the trackers, the lane memory and the frame count (the camera stays)."""
        self.trackers = self._new_trackers()
        self._frames = 0

    def process(
        self, frame: object, t_s: float | None = None, lead_box: LeadBox | None = None, *, scan_qr: bool = False,
        speed_mps: float | None = None, path: RoutePath | None = None,
    ) -> FrameAnalysis:
        """Analyse one frame at time t_s (None: the frame count × the period).

        ``speed_mps``: the car's own speed, when known: a vehicle without visible tail lights is told from a shadow by
        moving along the road (vision/lead.py); None: only vehicles with tail lights are boxed. ``path``: where the
        car's route steers it (a map's), searched for objects when no lane boundary is seen (vision/obstacle.py).

        ``scan_qr``: look for QR boards — on every QR_EVERY_N_FRAMES-th frame analysed (the caller that
        needs payloads, perception on a car with QR localisation, asks; the steering alone does not).
        """
        self._frames += 1
        t = t_s if t_s is not None and math.isfinite(t_s) else self._frames * self.period_s
        qr = scan_qr and (self._frames - 1) % QR_EVERY_N_FRAMES == 0
        return _analyze(frame, self._camera, self.trackers, t, lead_box, qr=qr, ground=self._ground, speed_mps=speed_mps,
                        aim_m=self._aim_m, path=path, markings=self._markings, guidance=self._guidance)


def analyze_frame(frame_bgr: object, camera: CameraModel | None = None) -> FrameAnalysis:
    """One frame's stateless measurements (docs/architecture.md): lane_confidence, brightness, occlusion, lead, qr_payloads,
    steering_deg."""
    try:
        return _analyze(frame_bgr, camera, Trackers.pass_through(), 0.0, None, qr=True)
    except Exception as exc:  # a measurement must never take the caller down: unknown is the answer
        return unknown_analysis(f"frame analysis failed: {type(exc).__name__}: {exc}")


# -- the stages ---------------------------------------------------------------------------------
@dataclass(frozen=True)
class Prepared:
    """A frame ready to measure: frame-size BGR (undistorted when calibrated), working-size grey and HLS on the road rows."""

    bgr: np.ndarray  # frame pixels (QR is read at full resolution; the overlay draws on them)
    camera: CameraModel  # at the frame's size
    scale: float  # frame pixels per working pixel
    region: RoadRegion  # in working pixels
    mask: np.ndarray  # the road region (read-only)
    gray: np.ndarray
    hls: np.ndarray
    exposure: Exposure  # of the road region
    marks: np.ndarray  # the HLS image the marking finder reads (``lanes.marking_view``: ``hls`` itself for light markings)
    work: np.ndarray | None = None  # working-size BGR of the road rows, 0 elsewhere (the ground model judges paint colour on it)


@dataclass(frozen=True)
class Lanes:
    """The ego lane's boundaries this frame: what to steer by and the evidence for the confidence."""

    left: LaneLine | None  # detected, with the tracked geometry when tracking (or the coasting track)
    right: LaneLine | None
    seen_left: LaneLine | None  # the evidence: detections the tracker accepted (an outlier is a miss)
    seen_right: LaneLine | None
    agreement_left: float  # [0..1] detection vs the track's prediction (1 without a track)
    agreement_right: float
    features: np.ndarray  # marking pixels (working size)
    paint_integral: np.ndarray  # integral image of the marking pixels over the road rows (the ridge tables'; occlusion's too)
    aim_row_px: float  # the look-ahead row the steering aims at
    lane_width_px: float  # lane width at that row (measured, remembered or the default)
    ground: GroundLanes | None = None  # the ground-plane boundaries, when the lane model bends
    out_of_view: tuple[bool, bool] = (False, False)  # a missing side the lane model places outside the picture
    expected: tuple[tuple[np.ndarray, np.ndarray], ...] | None = None  # the bending boundaries as image points (occlusion's)
    curves_px: tuple[np.ndarray | None, np.ndarray | None] | None = None  # ... as polylines in working pixels (the overlay's)
    interior: np.ndarray | None = None  # ... the lane between them, over the road rows (the road model's, the object search's)
    hls_white: np.ndarray | None = None  # the road rows' HLS under white light, when the ground model measured a tinted one
    white: np.ndarray | None = None  # ... its white (edge-line) paint over the road rows (the object search's)
    bend: Bend | None = None  # the boundaries traced round a bend (vision/bend.py): the aim point lies on them
    held_support: tuple[float, float] | None = None  # the accepted detections' supports as their tracks hold them (lane_tracker)
    paired: tuple[bool, bool] = (True, True)  # each side's track was once one side of a lane seen well (a line alone guides only then)


@dataclass(frozen=True)
class LeadAndOcclusion:
    """The vehicle ahead (box in frame pixels, bearing and range) and the hidden share of the expected markings."""

    box: LeadBox | None
    lead: Lead | None
    occlusion: float  # [0..1] the cue (occlusion.HiddenMarkings.occlusion, or the lane hidden beyond an object)
    hidden_share: float  # [0..1] of both boundaries' expected samples hidden (or the lane beyond an object): what the lane
    #   confidence discounts
    road_reference: float  # grey level of the road just ahead
    obstacle: Obstacle | None = None  # anything standing in the ego lane (needs the camera's mounting height)
    searched_m: float = 0.0  # [m] how far ahead the object search looked along the lane (0: it did not run)
    stop_line_m: float | None = None  # [m] a painted band across the ego lane (vision/obstacle.py: search_lane)


def prepare(frame: np.ndarray, camera: CameraModel | None, markings: str = "light") -> Prepared:
    """BGR at the frame's size (undistorted when a camera is given), then grey/HLS of the road rows at the working size,
    and the HLS view the marking finder reads for the track's ``markings`` (``lane.MARKINGS``)."""
    bgr = _as_bgr(frame)
    fh, fw = bgr.shape[:2]
    cam = _frame_camera(camera, fw, fh)
    if camera is not None:
        bgr = cam.undistort(bgr)
    ww, wh = work_size(fw, fh)
    region, mask = _region_and_mask(ww, wh, camera)
    band = slice(region.top_v_px, region.bottom_v_px + 1)  # the mask is empty outside the road rows
    work = reduce_rows(bgr, ww, wh, band)
    gray, hls = _band_conversions(work, region)
    return Prepared(bgr=bgr, camera=cam, scale=fw / ww, region=region, mask=mask, gray=gray, hls=hls,
                    exposure=road_exposure(gray[band], mask[band]), work=work,
                    marks=marking_view(hls, region.top_v_px, region.bottom_v_px, markings))


def find_lanes(p: Prepared, trackers: Trackers, t_s: float, ground: GroundLaneSpec | None = None, aim_m: float | None = None) -> Lanes:
    """Detect both boundaries (the tracks as priors), remember the lane width, fold the detections into the tracks.
    With a ground spec: the bending ground-plane model, its boundaries drawn into the image as their near chords.
    ``aim_m``: the steering aims at the lane centre this far ahead of a mounted camera (``steering.lookahead_row``)."""
    region = p.region
    v_aim = lookahead_row(region, p.camera, aim_m)
    if ground is not None:
        fit = ground_lanes_in_image(p.hls, p.mask, region, p.camera, ground, trackers.ground.priors(t_s), p.work)
        if fit is not None:
            trackers.ground.remember(t_s, fit.lanes)
            width_px = trackers.memory.remember_width(fit.left, fit.right, v_aim, region.width_px)
            return Lanes(left=fit.left, right=fit.right, seen_left=fit.left, seen_right=fit.right, agreement_left=fit.agreement[0],
                         agreement_right=fit.agreement[1], features=fit.features, paint_integral=fit.paint_integral, aim_row_px=v_aim,
                         lane_width_px=width_px, ground=fit.lanes, out_of_view=fit.out_of_view, expected=fit.expected,
                         curves_px=fit.curves_px, interior=fit.interior, hls_white=fit.hls_white, white=fit.white,
                         held_support=fit.lanes.held)
    shift = far_shift_px(trackers.memory.far_centre_u_px, region)
    mask = region_toward(region, shift) if shift else p.mask  # the far edge where last frame's lane went
    det = detect_lanes(p.marks, region, mask, trackers.lanes.current(region))
    width_px = trackers.memory.remember_width(det.left, det.right, v_aim, region.width_px)
    tracked = trackers.lanes.update(t_s, region, det.left, det.right)
    left = det.left if tracked.left is None or det.left is None else _with_track(det.left, tracked.left)
    right = det.right if tracked.right is None or det.right is None else _with_track(det.right, tracked.right)
    left, right = coasting_sides(left, right, tracked)
    rows = np.arange(region.top_v_px, region.bottom_v_px + 1)
    bend, far = None, None
    if p.camera.pitch_deg < PITCHED_DEG:  # a road camera: a model car's low, steep view of a tight track is not traced
        widths = lane_width_rows(rows, (left, right), region)
        bend = trace_bend(det.maps, region, left, right, widths, _horizon_v_px(p))
        # the next frame's road region follows the lane: mounted cameras only (on uncalibrated dash-cam footage it did
        # not help: docs/perception.md, "The road region follows the lane"); a model car's region is already wide
        if p.camera.mount_height_m is not None:
            far = aim_point_u(left, right, rows[0], widths[0])
    trackers.memory.remember_far_centre(far)
    return Lanes(
        left=left, right=right,
        seen_left=det.left if tracked.left_accepted else None, seen_right=det.right if tracked.right_accepted else None,
        held_support=(tracked.left_support, tracked.right_support), paired=tracked.paired,
        agreement_left=agreement(det.left, tracked.predicted_left, region, width_px),
        agreement_right=agreement(det.right, tracked.predicted_right, region, width_px),
        features=det.features, paint_integral=det.maps.paint_integral, aim_row_px=v_aim, lane_width_px=width_px, bend=bend,
        curves_px=_bend_polylines(bend, rows) if bend is not None else None,
    )


def coasting_sides(left: LaneLine | None, right: LaneLine | None, tracked: TrackedLanes) -> tuple[LaneLine | None, LaneLine | None]:
    """The boundaries to steer by: this frame's detections; a side missed this frame, with the other side found, by its
    track coasting through the miss (it keeps the aim point steady) — if that track was once a side of the lane seen
    well (``paired``). A track begun on a stray ridge (the speckle of glare at support 0.05, grass at the verge) is no
    side of the lane: coasting, it held a model car's aim half way to it, and the creep through low sun turned away from
    the one line it could see."""
    if left is None and right is not None and tracked.left is not None and tracked.paired[0]:
        left = tracked.left
    if right is None and left is not None and tracked.right is not None and tracked.paired[1]:
        right = tracked.right
    return left, right


def _bend_polylines(bend: Bend, rows: np.ndarray) -> tuple[np.ndarray | None, np.ndarray | None]:
    """Each traced boundary as an image polyline (n, 2: u, v) in working pixels over the rows its ridges span."""
    v = rows[(rows >= bend.rows[0]) & (rows <= bend.rows[1])].astype(np.float64)
    return tuple(None if side is None else np.column_stack([bend.u_at(side, v), v]) for side in (bend.left, bend.right))


def find_lead_and_occlusion(p: Prepared, lanes: Lanes, trackers: Trackers, t_s: float, given: LeadBox | None,
                            speed_mps: float | None = None, path: RoutePath | None = None) -> LeadAndOcclusion:
    """The lead box (a usable ``given`` one from an external detector, else detected and tracked — ``speed_mps``, the car's
    own, confirms a lamp-less box that moves along the road), the occlusion, and the object search: along the lane seen,
    or — no boundary seen — along the route's ``path`` when there is one, else the straight lane prior."""
    hls = lanes.hls_white if lanes.hls_white is not None else p.hls  # colours as under white light
    expected_l, expected_r = default_lines(p.region)
    expected_l, expected_r = lanes.left or expected_l, lanes.right or expected_r
    reference = road_reference(p.gray, p.region, expected_l, expected_r)
    external = given if isinstance(given, LeadBox) and given.usable else None
    box = external
    if external is None:
        found = detect_lead(p.gray, hls, p.region, expected_l, expected_r, reference, p.bgr)
        if found is not None and not found.lit and lanes.bend is not None and not _in_bent_lane(lanes.bend, found.box, expected_l,
                                                                                                 expected_r):
            found = None  # a lamp-less box beside the traced bend: on a bend the straight lines take in the outer lanes far ahead
        if found is None:
            box = trackers.leads.update(t_s, None)
        else:
            seen_box = found.box.scaled(p.scale)
            box = trackers.leads.update(t_s, seen_box, lit=found.lit, range_m=lead_from_box(seen_box, p.camera).range_m,
                                        speed_mps=speed_mps)
    boxes = (box.scaled(1.0 / p.scale).as_int(),) if box is not None else ()
    surface = surface_maps(p.gray, hls, lanes.features, p.region, lanes.paint_integral)
    measured = road_appearance(p.gray, hls, p.region, expected_l, expected_r, surface, interior=lanes.interior)
    road = trackers.road.reference(measured)
    hidden = hidden_markings(p.gray, hls, lanes.features, p.region, expected_l, expected_r, road, boxes, surface,
                             curves=lanes.expected)
    beyond = 0.0
    if p.camera.mount_height_m is None and _seen_well(lanes):
        # without a range, an object in the lane seen hides the lane beyond it (docs/perception.md, "occlusion")
        beyond = lane_hidden_beyond(p.gray, surface, road, p.region, lanes.left, lanes.right, boxes)
    hidden_share = max(hidden.share, beyond)
    trackers.road.learn(measured, hidden_share)
    obstacle, searched_m, stop_line_m = None, 0.0, None
    # a range needs the mounting height (without it the search is skipped). The bending lane model searches its own
    # interior, round the curve (the straight chords between its boundaries cut across the verge there), and on the
    # tiled floors it serves a smoother tile is no object; with no lane to search (no boundary seen; the bending model with
    # no interior: a boundary whose offset by a lane width it cannot place), the route's path (a junction's crossing)
    routed = path is not None and lanes.interior is None and (lanes.ground is not None or (lanes.left is None and lanes.right is None))
    # a lane seen on one side only is a guess on the other (the seen one a lane width over: at a junction it takes in the
    # crossing road's stop line beside the car's way): with a route, it is searched only where the route takes the car
    one_side = not routed and path is not None and (lanes.left is None) != (lanes.right is None)
    if p.camera.mount_height_m is not None and (lanes.ground is None or lanes.interior is not None or routed):
        searched_m = search_depth_m(p.camera, p.region, p.scale)
        bounds = None
        if path is not None:
            aim_v = lanes.aim_row_px * p.scale  # the route's steering aims at this row's ground: beyond it its arc is a guess
            bounds = path.bounds_px(p.camera, p.region, p.scale, p.camera.ground_range_m(aim_v) or 0.0)
            if routed:
                searched_m = min(searched_m, p.camera.range_ahead_m(aim_v) or 0.0)
        found_in_lane = search_lane(surface, road, p.region, expected_l, expected_r, p.camera, p.scale, interior=lanes.interior,
                                    smooth_objects=lanes.ground is None, edge_paint=lanes.white,
                                    bounds=bounds if routed else None, within=bounds if one_side else None)
        obstacle, stop_line_m = found_in_lane.obstacle, found_in_lane.stop_line_m
    obstacle = trackers.obstacles.update(obstacle)
    lead = lead_from_box(box, p.camera) if box is not None else None
    return LeadAndOcclusion(box=box, lead=lead, occlusion=max(hidden.occlusion, beyond), hidden_share=hidden_share,
                            road_reference=reference, obstacle=obstacle, searched_m=searched_m, stop_line_m=stop_line_m)


SEEN_WELL_SUPPORT = 0.5  # [-] both boundaries' marking support at least this: the lane is seen, and its interior is where it is


def _seen_well(lanes: Lanes) -> bool:
    """Both boundaries detected this frame with marking support ≥ SEEN_WELL_SUPPORT (held over a dash gap, lane_tracker)."""
    if lanes.seen_left is None or lanes.seen_right is None:
        return False
    support = lanes.held_support or (lanes.seen_left.support, lanes.seen_right.support)
    return min(support) >= SEEN_WELL_SUPPORT


def _in_bent_lane(bend: Bend, box: LeadBox, left: LaneLine, right: LaneLine) -> bool:
    """Whether a box's bottom centre (working pixels) lies in the lane as the traced bend has it: between its curves, or
    within half the straight lines' lane width of the one curve traced."""
    u, v = box.x_px + 0.5 * box.w_px, box.y_px + box.h_px - 1
    half = 0.5 * float(right.u_at(v) - left.u_at(v))
    lo = bend.u_at(bend.left, v) if bend.left is not None else bend.u_at(bend.right, v) - 2 * half
    hi = bend.u_at(bend.right, v) if bend.right is not None else lo + 2 * half
    return bool(lo <= u <= hi)


SEARCH_DEPTH_MAX_M = 50.0  # [m] the object search vouches for no more than this (a far row's pixels are a few centimetres of
#   a small object at most; rows near the horizon read as very far)


def search_depth_m(camera: CameraModel, region: RoadRegion, scale: float) -> float:
    """How far ahead of the car's front the object search looked: the flat-ground range of the road region's top row,
    capped."""
    far = camera.range_ahead_m(region.top_v_px * scale)
    return min(far, SEARCH_DEPTH_MAX_M) if far is not None and math.isfinite(far) and far > 0 else SEARCH_DEPTH_MAX_M


def judge_confidence(p: Prepared, lanes: Lanes, occlusion_share: float, guidance: str = "two_lines") -> LaneEvidence:
    """lane_confidence of this frame from the accepted detections, their agreement, occlusion and clipped pixels, for the
    track's ``guidance`` (``lane.GUIDANCE``)."""
    clipped = p.exposure.saturated_share + p.exposure.black_share
    return lane_confidence(lanes.seen_left, lanes.seen_right, p.region, lanes.agreement_left, lanes.agreement_right,
                           occlusion_share, clipped, p.exposure.signal_to_noise,
                           geometry=lanes.ground.geometry if lanes.ground is not None else None, out_of_view=lanes.out_of_view,
                           held=lanes.held_support, paired=lanes.paired, guidance=guidance)


def read_qr(p: Prepared) -> tuple[str, ...]:
    """Payloads of the QR boards in the frame (full resolution)."""
    return tuple(m.payload for m in detect_qr(p.bgr))


def steer(p: Prepared, lanes: Lanes, trackers: Trackers, ground: GroundLaneSpec | None = None) -> float | None:
    """Bearing of the lane centre at the look-ahead row (the ground model's: its aim point); no boundary: the held
    angle (None without history)."""
    if lanes.ground is not None and ground is not None:
        aim = aim_point(lanes.ground, ground)  # on a tight curve it may lie beyond the picture's edge: the model bends there
        if aim is None:
            return trackers.memory.hold(None)
        limit = ground.max_bearing_deg
        return trackers.memory.hold(max(-limit, min(limit, math.degrees(math.atan2(aim[1], aim[0])))))
    u_aim = aim_point_u(lanes.left, lanes.right, lanes.aim_row_px, lanes.lane_width_px)
    if lanes.bend is not None and u_aim is not None:
        u_aim = bent_aim_u(lanes.bend, lanes.aim_row_px, lanes.lane_width_px)
    return trackers.memory.hold(steering_from_aim(u_aim, p.scale, p.camera) if u_aim is not None else None)


def _analyze(
    frame: object, camera: CameraModel | None, trackers: Trackers, t_s: float, lead_box: LeadBox | None, *, qr: bool,
    ground: GroundLaneSpec | None = None, speed_mps: float | None = None, aim_m: float | None = None, path: RoutePath | None = None,
    markings: str = "light", guidance: str = "two_lines",
) -> FrameAnalysis:
    """The stages in order, each timed."""
    bad = invalid_frame_reason(frame)
    if bad is not None or not isinstance(frame, np.ndarray):
        return unknown_analysis(f"camera: {bad}: vision cues unknown (worst)")
    clock = time.perf_counter
    t0 = clock()
    p = prepare(frame, camera, markings)
    t1 = clock()
    if ground is not None:
        ground = trackers.ground.spec_now(ground)  # the lane width measured so far, when the spec measures it
    lanes = find_lanes(p, trackers, t_s, ground, aim_m)
    t2 = clock()
    seen = find_lead_and_occlusion(p, lanes, trackers, t_s, lead_box, speed_mps, path)
    t3 = clock()
    evidence = judge_confidence(p, lanes, seen.hidden_share, guidance)
    confidence = trackers.confidence.update(evidence.confidence)
    t4 = clock()
    payloads = read_qr(p) if qr else ()
    t5 = clock()
    steering = steer(p, lanes, trackers, ground)
    reasons = () if math.isfinite(p.exposure.brightness) else ("camera: road region empty: brightness unknown",)
    timings = {"prepare": (t1 - t0) * 1e3, "lanes": (t2 - t1) * 1e3, "lead_occlusion": (t3 - t2) * 1e3,
               "confidence": (t4 - t3) * 1e3, "qr": (t5 - t4) * 1e3, "steering": (clock() - t5) * 1e3}
    return FrameAnalysis(
        lane_confidence=confidence, brightness=p.exposure.brightness, occlusion=seen.occlusion, lead=seen.lead,
        qr_payloads=payloads, steering_deg=steering, exposure=p.exposure, evidence=evidence, left=lanes.left,
        right=lanes.right, region=p.region, scale=p.scale, lead_box=seen.box, road_reference=seen.road_reference,
        reasons=reasons, timings_ms=timings, obstacle=seen.obstacle, searched_m=seen.searched_m, stop_line_m=seen.stop_line_m,
        ground=lanes.ground,
        curves_px=None if lanes.curves_px is None else tuple(c * p.scale if c is not None else None for c in lanes.curves_px),
        t_s=t_s,
        horizon_v_px=assumed_horizon_v_px(p.bgr.shape[1], p.bgr.shape[0], p.camera),
    )


def _horizon_v_px(p: Prepared) -> float:
    """The horizon row in working pixels: the mounted camera's own (it knows its pitch, 0 included), else where the
    road region assumes it (``lanes.assumed_horizon_v_px``: a dash-cam's default)."""
    if p.camera.mount_height_m is not None:
        return p.camera.horizon_v_px() / p.scale
    return assumed_horizon_v_px(p.region.width_px, p.region.height_px, p.camera)


def bent_aim_u(bend: Bend, v_px: float, lane_width_px: float) -> float:
    """The lane centre at row v on the traced curves: between both, or half a lane width from one."""
    left = bend.u_at(bend.left, v_px) if bend.left is not None else None
    right = bend.u_at(bend.right, v_px) if bend.right is not None else None
    if left is not None and right is not None:
        return float(0.5 * (left + right))
    return float(left + 0.5 * lane_width_px if left is not None else right - 0.5 * lane_width_px)


@lru_cache(maxsize=8)
def _frame_camera(camera: CameraModel | None, width_px: int, height_px: int) -> CameraModel:
    """The camera at the frame's size (the default one without a model): the same every frame, so built once."""
    return camera.scaled_to(width_px, height_px) if camera is not None else CameraModel.default(width_px, height_px)


@lru_cache(maxsize=8)
def _region_and_mask(width_px: int, height_px: int, camera: CameraModel | None) -> tuple[RoadRegion, np.ndarray]:
    """Road region and its mask for a working size and camera: the same every frame, so built once (read-only)."""
    region = road_region(width_px, height_px, camera)
    mask = region_mask(region)
    mask.flags.writeable = False
    return region, mask


def reduce_to(image: np.ndarray, width_px: int, height_px: int) -> np.ndarray:
    """``image`` area-averaged to width × height: halved while the rest of the reduction stays a whole factor, then
    INTER_AREA for what is left. OpenCV's 2× area reduction is vectorised and its 4× is not (720p BGR to the working
    size: ~0.25 ms against ~0.9 ms); the result is within one grey level of a direct INTER_AREA, a quarter level
    brighter on average (each halving rounds half up)."""
    h, w = image.shape[:2]
    if (w, h) == (width_px, height_px):
        return image
    while w % (2 * width_px) == 0 and h % (2 * height_px) == 0:
        w, h = w // 2, h // 2
        image = cv2.resize(image, (w, h), interpolation=cv2.INTER_AREA)
    return image if (w, h) == (width_px, height_px) else cv2.resize(image, (width_px, height_px), interpolation=cv2.INTER_AREA)


def reduce_rows(image: np.ndarray, width_px: int, height_px: int, rows: slice) -> np.ndarray:
    """``reduce_to(image, width_px, height_px)`` on the working rows ``rows`` (a slice with start and stop), 0 on the
    others: every stage reads the road rows only, and reducing them alone is a third of the work on a dash-cam frame.
    When the image is a whole multiple k of the working size each working row is the mean of k whole image rows, so
    reducing the image rows ``k*start .. k*stop`` gives exactly those rows; otherwise the whole image is reduced."""
    h, w = image.shape[:2]
    k = w // width_px
    start, stop, _ = rows.indices(height_px)
    out = np.zeros((height_px, width_px, *image.shape[2:]), image.dtype)
    if stop <= start:
        return out
    if k > 1 and (w, h) == (k * width_px, k * height_px):
        out[start:stop] = reduce_to(image[k * start : k * stop], width_px, stop - start)
    else:
        out[start:stop] = reduce_to(image, width_px, height_px)[start:stop]
    return out


def _as_bgr(frame: np.ndarray) -> np.ndarray:
    if frame.ndim == 2 or frame.shape[2] == 1:
        return cv2.cvtColor(frame.reshape(frame.shape[:2]), cv2.COLOR_GRAY2BGR)
    if frame.shape[2] == 4:
        return cv2.cvtColor(frame, cv2.COLOR_BGRA2BGR)
    return frame


def _band_conversions(work: np.ndarray, region: RoadRegion) -> tuple[np.ndarray, np.ndarray]:
    """Grey and HLS images, computed only on the road region's rows (the rest stays 0): a third of the cost."""
    gray = np.zeros(work.shape[:2], np.uint8)
    hls = np.zeros_like(work)
    band = slice(region.top_v_px, region.bottom_v_px + 1)
    gray[band] = cv2.cvtColor(work[band], cv2.COLOR_BGR2GRAY)
    hls[band] = cv2.cvtColor(work[band], cv2.COLOR_BGR2HLS)
    return gray, hls


def _with_track(measured: LaneLine, tracked: LaneLine) -> LaneLine:
    """The tracked (smoothed) geometry with this frame's evidence."""
    return LaneLine(tracked.slope, tracked.intercept_px, measured.support, measured.segments)
