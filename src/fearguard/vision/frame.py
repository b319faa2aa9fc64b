"""One camera frame → the vision cues, the lead vehicle, QR payloads and the baseline steering angle.

``analyze_frame`` is the stateless form (one frame, no history). ``FramePipeline`` is the same
computation with trackers (lane boundaries, lead vehicle) and the lane memory of the steering; a
supervisor wrapping ``HoughLaneSteering`` analyses each frame once with the steering's pipeline and
hands that analysis to the steering (``perception.FrameSteering``).
Frames are analysed at a fixed working width (``lanes.WORK_WIDTH_PX``); results in pixels are
reported in the frame's own pixels.
"""

from __future__ import annotations

import math
import time
from collections import deque
from collections.abc import Mapping
from dataclasses import dataclass, field
from functools import lru_cache

import cv2
import numpy as np

from fearguard.camera import CameraModel
from fearguard.observation import Lead
from fearguard.vision.confidence import LaneEvidence, agreement, lane_confidence
from fearguard.vision.exposure import Exposure, road_exposure
from fearguard.vision.lane_tracker import LaneTracker
from fearguard.vision.lanes import LaneLine, RoadRegion, detect_lanes, region_mask, road_region, work_size
from fearguard.vision.lead import LeadBox, LeadTracker, detect_lead, lead_from_box
from fearguard.vision.occlusion import default_lines, occlusion, road_reference
from fearguard.vision.qr import detect_qr
from fearguard.vision.steering import LaneMemory, aim_point_u, lookahead_row, steering_from_aim

QR_EVERY_N_FRAMES = 3  # [frames] the pipeline scans for QR boards on every 3rd frame: a board stays in view for many
# frames, staleness keeps a 0.15 s resolution at 20 Hz, and the scan (~1.8 ms, ~5.5 ms with a board) costs a third
CONFIDENCE_MEDIAN_FRAMES = 3  # [frames] lane_confidence over time is the median of this many frames (50 ms lag at 20 Hz)
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
    return FrameAnalysis(_NAN, _NAN, _NAN, None, (), None, reasons=(reason,))


def _as_bgr(frame: np.ndarray) -> np.ndarray:
    if frame.ndim == 2 or frame.shape[2] == 1:
        return cv2.cvtColor(frame.reshape(frame.shape[:2]), cv2.COLOR_GRAY2BGR)
    if frame.shape[2] == 4:
        return cv2.cvtColor(frame, cv2.COLOR_BGRA2BGR)
    return frame


class FramePipeline:
    """Stateful frame analysis: lane and lead trackers, lane memory. Every call analyses its frame afresh.

    There is no cache: a caller that refills one buffer every frame (``cap.read(buf)``, ring buffers,
    ``np.copyto``) gets that frame's measurements. The camera is fixed at construction.
    """

    def __init__(self, camera: CameraModel | None = None, fps: float = 20.0) -> None:
        self._camera = camera
        self.period_s = 1.0 / fps if fps > 0 else 0.05
        self.lanes = LaneTracker()
        self.leads = LeadTracker()
        self.memory = LaneMemory()
        self._frames = 0
        self._confidences: deque[float] = deque(maxlen=CONFIDENCE_MEDIAN_FRAMES)

    @property
    def camera(self) -> CameraModel | None:
        """The camera model every frame is analysed with (None: an uncalibrated default for the frame size)."""
        return self._camera

    def steady_confidence(self, confidence: float) -> float:
        """Median of the last CONFIDENCE_MEDIAN_FRAMES confidences: one odd frame neither alarms nor reassures."""
        self._confidences.append(confidence)
        return float(np.median(self._confidences))

    def reset(self) -> None:
        """Forget the trackers, the lane memory and the frame count (the camera stays)."""
        self.lanes = LaneTracker()
        self.leads = LeadTracker()
        self.memory = LaneMemory()
        self._frames = 0
        self._confidences.clear()

    def process(
        self, frame: object, t_s: float | None = None, lead_box: LeadBox | None = None, *, scan_qr: bool = False
    ) -> FrameAnalysis:
        """Analyse one frame at time t_s (None: the frame count × the period).

        ``scan_qr``: look for QR boards — on every QR_EVERY_N_FRAMES-th frame analysed (the caller that
        needs payloads, perception on a car with QR localisation, asks; the steering alone does not).
        """
        self._frames += 1
        t = t_s if t_s is not None and math.isfinite(t_s) else self._frames * self.period_s
        qr = scan_qr and (self._frames - 1) % QR_EVERY_N_FRAMES == 0
        return _analyze(frame, self._camera, self, t, lead_box, qr)


def analyze_frame(frame_bgr: object, camera: CameraModel | None = None) -> FrameAnalysis:
    """One frame's stateless measurements (DESIGN.md): lane_confidence, brightness, occlusion, lead, qr_payloads, steering_deg."""
    try:
        return _analyze(frame_bgr, camera, None, 0.0, None, True)
    except Exception as exc:  # a measurement must never take the caller down: unknown is the answer
        return unknown_analysis(f"frame analysis failed: {type(exc).__name__}: {exc}")


def _analyze(
    frame: object, camera: CameraModel | None, state: FramePipeline | None, t_s: float, lead_box: LeadBox | None, qr: bool
) -> FrameAnalysis:
    bad = invalid_frame_reason(frame)
    if bad is not None:
        return unknown_analysis(f"camera: {bad}: vision cues unknown (worst)")
    assert isinstance(frame, np.ndarray)  # narrowed by invalid_frame_reason (for type checkers)
    clock = time.perf_counter
    t0 = clock()
    bgr = _as_bgr(frame)
    fh, fw = bgr.shape[:2]
    cam = (camera.scaled_to(fw, fh) if camera is not None else CameraModel.default(fw, fh))
    if camera is not None:
        bgr = cam.undistort(bgr)
    ww, wh = work_size(fw, fh)
    work = bgr if (ww, wh) == (fw, fh) else cv2.resize(bgr, (ww, wh), interpolation=cv2.INTER_AREA)
    scale = fw / ww
    region, mask = _region_and_mask(ww, wh, camera)
    gray, hls = _band_conversions(work, region)
    t1 = clock()
    exposure = road_exposure(gray, mask)
    priors = state.lanes.current(region) if state is not None else (None, None)
    det = detect_lanes(hls, region, mask, priors)
    t2 = clock()
    left, right = det.left, det.right
    agree_l = agree_r = 1.0
    memory = state.memory if state is not None else LaneMemory()
    v_aim = lookahead_row(region)
    width_px = memory.remember_width(left, right, v_aim, ww)
    seen_left, seen_right = det.left, det.right  # the evidence: detections the tracker accepted (an outlier is a miss)
    if state is not None:
        tracked = state.lanes.update(t_s, region, left, right)
        seen_left = det.left if tracked.left_accepted else None
        seen_right = det.right if tracked.right_accepted else None
        agree_l = agreement(left, tracked.predicted_left, region, width_px)
        agree_r = agreement(right, tracked.predicted_right, region, width_px)
        left = left if tracked.left is None or left is None else _with_track(left, tracked.left)
        right = right if tracked.right is None or right is None else _with_track(right, tracked.right)
        if left is None and tracked.left is not None and right is not None:
            left = tracked.left  # coasting track of a boundary missed this frame (keeps the aim point steady)
        if right is None and tracked.right is not None and left is not None:
            right = tracked.right
    t3 = clock()
    exp_l, exp_r = default_lines(region)
    exp_l, exp_r = left or exp_l, right or exp_r
    reference = road_reference(gray, region, exp_l, exp_r)
    box_work = detect_lead(gray, hls, region, exp_l, exp_r, reference)
    detected_box = box_work.scaled(scale) if box_work is not None else None
    external = lead_box if isinstance(lead_box, LeadBox) and lead_box.usable else None
    box = external or detected_box
    if state is not None and external is None:
        box = state.leads.update(t_s, detected_box)
    boxes = (box.scaled(1.0 / scale).as_int(),) if box is not None else ()
    occ = occlusion(gray, hls, det.features, region, exp_l, exp_r, reference, boxes)
    lead = lead_from_box(box, cam) if box is not None else None
    clipped = exposure.saturated_share + exposure.black_share
    evidence = lane_confidence(seen_left, seen_right, region, agree_l, agree_r, occ, clipped)
    t4 = clock()
    payloads = tuple(m.payload for m in detect_qr(bgr)) if qr else ()
    t5 = clock()
    u_aim = aim_point_u(left, right, v_aim, width_px)
    steering = steering_from_aim(u_aim, scale, cam) if u_aim is not None else memory.last_steering_deg
    memory.last_steering_deg = steering
    reasons = []
    if not math.isfinite(exposure.brightness):
        reasons.append("camera: road region empty: brightness unknown")
    timings = {"prepare": (t1 - t0) * 1e3, "lanes": (t2 - t1) * 1e3, "confidence": (t3 - t2) * 1e3,
               "lead_occlusion": (t4 - t3) * 1e3, "qr": (t5 - t4) * 1e3, "steering": (clock() - t5) * 1e3}
    confidence = evidence.confidence if state is None else state.steady_confidence(evidence.confidence)
    return FrameAnalysis(
        confidence, exposure.brightness, occ, lead, payloads, steering, exposure, evidence, left, right, region,
        scale, box, reference, tuple(reasons), timings,
    )


@lru_cache(maxsize=8)
def _region_and_mask(width_px: int, height_px: int, camera: CameraModel | None) -> tuple[RoadRegion, np.ndarray]:
    """Road region and its mask for a working size and camera: the same every frame, so built once (read-only)."""
    region = road_region(width_px, height_px, camera)
    mask = region_mask(region)
    mask.flags.writeable = False
    return region, mask


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
