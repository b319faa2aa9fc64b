"""Perception: an Observation (frame + sensor readings) → the cues, the lead vehicle, and why.

With a track profile (``fearguard learn``) the picture is also read against the car's own recordings
(``track/reading.py``): the familiarity cue, the light and the lane as this track has them.

Stateful (trackers and filters live here), but it never decides anything: policy does. Each
measurement comes from a small module — ``vision/`` for pixels, ``sensors/`` for the ultrasonic and
QR localisation — and every value that matters is put into ``reasons`` as a fact with its number.
A sensor the vehicle lacks (``VehicleLimits``) gives a neutral cue; a sensor it has that fails gives
an unknown (worst) cue.
"""

from __future__ import annotations

import math
import time
from dataclasses import dataclass, field
from typing import Protocol, runtime_checkable

import numpy as np

from fearguard.camera import CameraModel
from fearguard.cues import Cues
from fearguard.errors import describe
from fearguard.lane import LaneGeometry
from fearguard.observation import Lead, LeadBox, Observation
from fearguard.readings import finite_reading, reading
from fearguard.sensors.localisation import LocalisationState, QrLocaliser
from fearguard.sensors.ultrasonic import RangeEstimate, UltrasonicFilter
from fearguard.track.profile import TrackProfile
from fearguard.track.reading import read_as_learnt
from fearguard.vehicle import VehicleLimits
from fearguard.vision.frame import FrameAnalysis, FramePipeline
from fearguard.vision.ground import lane_geometry
from fearguard.vision.obstacle import Obstacle, RoutePath

FROZEN_S = 0.5  # [s] frames byte-identical for longer than this: the camera froze (a real camera always has noise);
#                  shorter repeats are a loop faster than the camera (a 5 fps camera in a 20 Hz loop repeats for 0.15 s):
#                  "no new frame". 10 periods of a 20 fps camera: with 1.0 s the bundled camera_blackout's 1 s freeze at a
#                  curve's entrance was driven through on the stale picture and the car left the lane on 3 of 10 seeds (0 now)
ULTRASONIC_CONE_DEG = 15.0  # [deg] a lead within ±half this bearing is what the ultrasonic sees
SAME_RANGE_SHARE = 0.5  # [-] a vehicle box at least this share of the object search's range (and as far to the side) ranges
#   the object the search found: the search's lowest foreign rows can sit well above the road (MetaDrive seed 23 with
#   traffic 0.15: a car read 19.2 m by the search, 13.8 m by its box, 12.1 m true), never below half the range
_NAN = math.nan
_UNSEEN = FrameAnalysis(lane_confidence=_NAN, brightness=_NAN, occlusion=_NAN, lead=None, qr_payloads=(), steering_deg=None)


@runtime_checkable
class FrameSteering(Protocol):
    """A steering function built on fearguard's own frame analysis (``HoughLaneSteering`` is one).

    The handshake with the supervisor: perception analyses each frame once with ``pipeline`` (its
    camera is the supervisor's camera), then the supervisor asks ``steer_from`` for the angle of that
    same analysis — the cues and the steering describe one frame, with no cache in between. Frames
    perception did not analyse (frozen, missing, cue-level) go through ``__call__`` as usual.
    """

    @property
    def pipeline(self) -> FramePipeline: ...

    def __call__(self, frame: object) -> float: ...

    def steer_from(self, analysis: FrameAnalysis) -> float: ...


@dataclass(frozen=True)
class Perceived:
    """One frame's cues and the facts behind them."""

    cues: Cues
    lead: Lead | None
    alerts: tuple[str, ...]  # readings unknown or rejected: always worth reporting
    facts: tuple[str, ...] = ()  # the measurements behind the cues: reported when fear is up
    analysis: FrameAnalysis | None = None  # this frame's analysis by the pipeline; None when it did not run
    lane: LaneGeometry | None = None  # the ego lane in metres on the ground (needs a camera with its mounting height)
    lane_steering_deg: float | None = None  # the frame pipeline's own steering toward the lane centre (finite), if any
    lane_guide: float = 0.0  # [-] 0..1 how well a boundary found this frame steers that angle (``LaneEvidence.guide``); 0: none
    clear_m: float = 0.0  # [m] how far ahead the path is known clear (range sensor, the camera's object search); 0: unknown
    stop_line_m: float | None = None  # [m] a stop line across the ego lane ahead, as the camera's lane search found it
    range_estimate: RangeEstimate | None = None
    localisation: LocalisationState | None = None
    timings_ms: dict[str, float] = field(default_factory=dict)
    range_shift_m: float = 0.0  # [m] <= 0: the camera's range moved to a nearer reading of the object it ranged last frame
    #   (``CameraRange``): earlier ranges are that much too far, and the jump is no closing speed


@dataclass(frozen=True)
class CameraRange:
    """A camera-only car's range ahead in one frame: the nearer of the object search's and the boxed vehicle's."""

    range_m: float  # [m] inf: nothing seen in the lane
    source: str | None  # "object" (the lane search), "vehicle" (a boxed lead), None: nothing
    shift_m: float = 0.0  # [m] <= 0: see ``Perceived.range_shift_m``


def fuse_camera_ranges(
    object_m: float, object_bearing_deg: float, vehicle_m: float, vehicle_bearing_deg: float, previous: str | None,
    same_lateral_m: float,
) -> CameraRange:
    """The range is always the nearer reading (ties: the object search's) — fusing never moves it. What it adds:
    when the range passes from the object search (last frame) to a vehicle box that reads the same object nearer (this
    frame both see it: the box as far to the side within ``same_lateral_m``, at ``SAME_RANGE_SHARE`` of the search's
    range or more), the history is that much too far (``shift_m``), not a car that closed metres in a frame. The other
    way (the search finds something nearer than the box) may be a new object in front of the vehicle: no shift, its
    speed unknown (worst). Readings: inf = none, bearings in degrees."""
    if not (vehicle_m < object_m):
        return CameraRange(object_m, "object" if math.isfinite(object_m) else None)
    if previous != "object" or not math.isfinite(object_m) or vehicle_m < SAME_RANGE_SHARE * object_m:
        return CameraRange(vehicle_m, "vehicle")
    a, b = math.radians(object_bearing_deg), math.radians(vehicle_bearing_deg)
    lateral = abs(object_m * math.sin(a) - vehicle_m * math.sin(b))
    return CameraRange(vehicle_m, "vehicle", vehicle_m - object_m if lateral <= same_lateral_m else 0.0)


class Perception:
    """Frame + sensors → cues. One ``perceive`` per frame, time passed in the Observation."""

    def __init__(
        self, vehicle: VehicleLimits | None = None, camera: CameraModel | None = None, pipeline: FramePipeline | None = None,
        marker_spacing_m: float = 5.0, track: TrackProfile | None = None, normal_band: tuple[float, float] = (80.0, 180.0),
        occlusion_calm: float = 0.1,
    ) -> None:
        """``pipeline``: analyse frames with this one (a FrameSteering's); its camera must be ``camera`` if both are given.
        ``track``: read each picture against this profile; ``normal_band``: the rule file's normal light, onto which the
        learnt light band maps; ``occlusion_calm``: the top of the rule file's calm occlusion, onto which normal driving's
        occlusion maps."""
        if track is not None and not isinstance(track, TrackProfile):
            raise TypeError(f"track must be a TrackProfile (fearguard.load_track), got {type(track).__name__}")
        self.track = track
        self.normal_band = normal_band
        self.occlusion_calm = occlusion_calm
        self.vehicle = vehicle if vehicle is not None else VehicleLimits()
        if pipeline is not None and not isinstance(pipeline, FramePipeline):
            raise TypeError(f"pipeline must be a FramePipeline, got {type(pipeline).__name__}")
        if pipeline is not None and camera is not None and pipeline.camera != camera:
            raise ValueError(
                "the steering's frame pipeline has another camera model than the one given to the supervisor: "
                "build both with the same camera (e.g. HoughLaneSteering(camera=cam) and FearGuard(..., camera=cam))"
            )
        # its own pipeline finds the markings the track was learnt with (a given one: the steering's own)
        own = {"markings": track.markings, "guidance": track.guidance} if track is not None else {}
        self.pipeline = pipeline if pipeline is not None else FramePipeline(camera, **own)
        self.camera = self.pipeline.camera
        self.scan_qr = self.vehicle.has_qr_localisation  # no QR localisation on this car: no QR scan either
        v = self.vehicle
        self.ultrasonic = UltrasonicFilter(v.ultrasonic_min_range_m, v.ultrasonic_max_range_m,
                                           max_closing_speed_mps=v.max_closing_speed_mps)
        self.localiser = self._new_localiser(marker_spacing_m)
        self._marker_spacing_m = marker_spacing_m
        self.frozen_s = FROZEN_S
        self._last_pixels: np.ndarray | None = None  # a private copy of the last new frame
        self._same_since_s = _NAN  # when the current frame content was first seen
        self._last_analysis: FrameAnalysis | None = None
        self._range_noted = False  # a range reading reached a car that declares no range sensor, and the reasons said so
        self._range_from: str | None = None  # the camera's range last frame came from the object search or a vehicle box

    def _new_localiser(self, spacing_m: float) -> QrLocaliser:
        """The QR localiser with the car's speed bound and route (VehicleLimits)."""
        v = self.vehicle
        return QrLocaliser(marker_spacing_m=spacing_m, route=v.qr_route, max_speed_mps=v.localiser_max_speed_mps)

    def reset(self) -> None:
        self.pipeline.reset()
        self.ultrasonic.reset()
        self.localiser = self._new_localiser(self._marker_spacing_m)
        self._last_pixels, self._same_since_s, self._last_analysis = None, _NAN, None
        self._range_noted = False
        self._range_from = None

    def perceive(self, obs: Observation) -> Perceived:
        """Cues for one Observation; readings that are missing or not numbers count as missing."""
        clock = time.perf_counter
        t0 = clock()
        t_s = reading(obs.t_s)
        t = t_s if t_s is not None else _NAN
        reasons: list[str] = []  # alerts
        facts: list[str] = []
        box = obs.lead_box if isinstance(obs.lead_box, LeadBox) else None
        analysis = self._vision(obs.frame, t, box, reasons, facts, reading(obs.speed_mps), self._route_path(obs))
        seen = analysis if analysis is not None else _UNSEEN
        t1 = clock()
        lead = obs.lead if isinstance(obs.lead, Lead) else seen.lead
        range_m, estimate, shift = self._range(obs, t, reasons, facts, seen.obstacle, lead)
        t2 = clock()
        staleness, loc = self._staleness(obs, t, seen.qr_payloads, facts)
        t3 = clock()
        lead = self._fuse_lead_range(lead, range_m)
        timings = {f"vision.{k}": v for k, v in seen.timings_ms.items()}
        timings.update(vision=(t1 - t0) * 1e3, ultrasonic=(t2 - t1) * 1e3, localisation=(t3 - t2) * 1e3)
        lane_conf, brightness, occlusion, familiarity = self._as_learnt(obs.frame, analysis, seen, facts)
        cues = Cues(lane_confidence=lane_conf, brightness=brightness, occlusion=occlusion,
                    obstacle_range_m=range_m, qr_staleness_s=staleness, familiarity=familiarity)
        lane, lane_steering = self._lane(analysis)
        guide = analysis.evidence.guide if analysis is not None and analysis.evidence is not None and lane_steering is not None else 0.0
        return Perceived(cues=cues, lead=lead, alerts=tuple(reasons), facts=tuple(facts), analysis=analysis, lane=lane,
                         lane_steering_deg=lane_steering, lane_guide=guide, clear_m=self._clear_m(range_m, analysis, obs),
                         stop_line_m=analysis.stop_line_m if analysis is not None else None,
                         range_estimate=estimate, localisation=loc, timings_ms=timings, range_shift_m=shift)

    def _as_learnt(self, frame: object, analysis: FrameAnalysis | None, seen: FrameAnalysis,
                   facts: list[str]) -> tuple[float, float, float, float]:
        """(lane confidence, brightness, occlusion, familiarity): as measured without a track profile (familiarity 1: the
        cue does not apply); with one, read against it — and unknown (worst) when there was no picture to read."""
        if self.track is None:
            return seen.lane_confidence, seen.brightness, seen.occlusion, 1.0
        if analysis is None:
            return seen.lane_confidence, seen.brightness, seen.occlusion, _NAN
        learnt = read_as_learnt(self.track, frame, seen.lane_confidence, seen.brightness, seen.occlusion, self.normal_band,
                                self.occlusion_calm)
        facts.extend(learnt.facts)
        return learnt.lane_confidence, learnt.brightness, learnt.occlusion, learnt.familiarity

    def _clear_m(self, range_m: float, analysis: FrameAnalysis | None, obs: Observation) -> float:
        """How far ahead the path is known clear: to the obstacle in range; with nothing in range, as far as a range
        sensor reaches (one the car declares, or whose reading arrived) or the camera's object search looked."""
        if not range_m >= 0.0:
            return 0.0  # NaN: a failed reading says nothing
        if math.isfinite(range_m):
            return range_m
        sensed = self.vehicle.has_ultrasonic or (self._range_noted and obs.ultrasonic_range_m is not None)
        searched = analysis.searched_m if analysis is not None and analysis.obstacle is None else 0.0
        return max(self.vehicle.ultrasonic_max_range_m if sensed else 0.0, searched)

    def _lane(self, analysis: FrameAnalysis | None) -> tuple[LaneGeometry | None, float | None]:
        """The lane as a measurement for policy: its ground geometry (camera with mounting height) and the pipeline's
        own steering toward it (None unless finite)."""
        if analysis is None:
            return None, None
        steering = analysis.steering_deg if analysis.steering_deg is not None and math.isfinite(analysis.steering_deg) else None
        geometry = lane_geometry(analysis.left, analysis.right, analysis.region, analysis.scale, self.camera, analysis.steering_deg)
        return geometry, steering

    # -- camera ---------------------------------------------------------------------------------
    def _route_path(self, obs: Observation) -> RoutePath | None:
        """The path the caller's route steers (``Observation.route_steering_deg``, within the steering range; None: no
        finite route) as the bicycle model the policy uses reads a steering angle: curvature tan(δ) / wheelbase."""
        v = self.vehicle
        route = obs.route_deg(v.max_steering_deg)
        return None if route is None else RoutePath(math.tan(math.radians(route)) / v.wheelbase_m, v.width_m)

    def _vision(self, frame: object, t: float, box: LeadBox | None, reasons: list[str], facts: list[str],
                speed_mps: float | None = None, path: RoutePath | None = None) -> FrameAnalysis | None:
        """This frame's analysis by the pipeline (``speed_mps``: the car's own, None if unknown), or None when there was
        nothing to analyse (the cues are unknown)."""
        if frame is None:
            reasons.append("camera: no frame: vision cues unknown (worst)")
            return None
        same_s = self._same_content_s(frame, t)
        if same_s > self.frozen_s:
            reasons.append(f"camera: frozen (identical frames for {same_s:.1f} s): vision cues unknown (worst)")
            return None
        if same_s > 0.0 and self._last_analysis is not None:
            facts.append(f"camera: no new frame (same content for {same_s:.2f} s): last analysis reused")
            return self._last_analysis
        try:
            analysis = self.pipeline.process(frame, t if math.isfinite(t) else None, box, scan_qr=self.scan_qr, speed_mps=speed_mps,
                                             path=path)
        except Exception as exc:  # vision is a measurement: its failure is an unknown, not a crash
            reasons.append(f"camera: analysis failed ({type(exc).__name__}: {exc}): vision cues unknown (worst)")
            self._last_analysis = None
            return None
        self._last_analysis = analysis
        reasons.extend(analysis.reasons)
        ev, ex = analysis.evidence, analysis.exposure
        if ev is not None:
            facts.append(
                f"lane: confidence {ev.confidence:.2f} ("
                + ("" if ev.guidance == "two_lines" else f"guidance {ev.guidance.replace('_', ' ')}: its best line; ")
                + f"support L {ev.support_left:.2f} R {ev.support_right:.2f}, "
                f"geometry {ev.geometry:.2f}, agreement {ev.agreement:.2f}, visibility {ev.visibility:.2f})"
            )
        if math.isfinite(ex.brightness):
            facts.append(
                f"brightness {ex.brightness:.0f}/255 ({100 * ex.saturated_share:.0f} % saturated, {100 * ex.black_share:.0f} % black)"
            )
        if math.isfinite(analysis.occlusion):
            hidden_by = " (vehicle box over the markings)" if analysis.lead_box is not None else ""
            facts.append(f"occlusion {analysis.occlusion:.2f} of the expected marking region hidden{hidden_by}")
        return analysis

    def _same_content_s(self, frame: object, t: float) -> float:
        """How long the frame content has been byte-identical (0.0: new content). Judged by the pixels, never by the
        array object: a caller that refills one buffer with new pixels gets every frame analysed afresh."""
        if not isinstance(frame, np.ndarray) or frame.size == 0 or not math.isfinite(t):
            self._last_pixels, self._same_since_s = None, _NAN
            return 0.0
        pixels = np.ascontiguousarray(frame)
        if not same_bytes(pixels, self._last_pixels):
            self._last_pixels, self._same_since_s = _keep_copy(pixels, self._last_pixels), t
            return 0.0
        return max(t - self._same_since_s, 1e-9)

    # -- ultrasonic -----------------------------------------------------------------------------
    def _range(
        self, obs: Observation, t: float, reasons: list[str], facts: list[str], seen: Obstacle | None = None,
        lead: Lead | None = None,
    ) -> tuple[float, RangeEstimate | None, float]:
        """The range ahead, the range sensor's filter estimate (None without one) and the camera range's history shift."""
        if not self.vehicle.has_ultrasonic:  # no range sensor: the camera's ground-plane range of an object in the lane,
            object_m, object_deg = math.inf, 0.0  # or of the vehicle it boxed there, whichever is nearer
            if seen is not None and seen.range_m is not None:
                facts.append(f"camera: object in the lane at {seen.range_m:.2f} m (ground plane, bearing {seen.bearing_deg:+.1f}°)")
                object_m, object_deg = seen.range_m, seen.bearing_deg
            boxed = lead.usable_range_m if lead is not None and lead.usable else None
            bearing = (finite_reading(lead.bearing_deg) or 0.0) if lead is not None else 0.0  # usable: finite, whatever Real
            fused = fuse_camera_ranges(object_m, object_deg, boxed if boxed is not None else math.inf, bearing,
                                       self._range_from, 0.5 * self.vehicle.width_m)
            if fused.source == "vehicle":
                facts.append(f"camera: vehicle ahead in the lane at {fused.range_m:.2f} m (bearing {bearing:+.1f}°)")
            if fused.shift_m < 0.0:
                facts.append(f"camera: the vehicle's box ranges the object the lane search found {-fused.shift_m:.2f} m nearer: "
                             "the same object, ranged better (no closing speed from the jump)")
            self._range_from = fused.source
            given = self._undeclared_range(obs, reasons)
            return min(fused.range_m, given), None, fused.shift_m if fused.range_m <= given else 0.0
        est = self.ultrasonic.update(t, obs.ultrasonic_range_m, obs.ultrasonic_echo_s)
        if math.isfinite(est.range_m):
            ttc = f", TTC {est.ttc_s:.1f} s" if math.isfinite(est.ttc_s) else ""
            facts.append(f"ultrasonic: obstacle at {est.range_m:.2f} m, closing {est.closing_speed_mps:+.2f} m/s{ttc}")
        if est.reason and (not est.accepted or math.isnan(est.range_m)):
            reasons.append(est.reason)
        return est.range_m, est, 0.0

    def _undeclared_range(self, obs: Observation, reasons: list[str]) -> float:
        """A range reading given to a car that declares no range sensor: it counts (a reading that arrives is a reading).

        Missing (None) or ``inf``: nothing known in range. A finite reading: its metres (beyond the sensor's maximum:
        the maximum), noted once. Anything else that arrives (NaN, negative, text): unknown, NaN (worst)."""
        given = obs.ultrasonic_range_m
        if given is None:
            return math.inf
        value = reading(given)
        if value is None or not value >= 0.0:
            reasons.append(f"range reading {describe(given)} is not a range: unknown (worst)")
            return math.nan
        if math.isfinite(value) and not self._range_noted:
            self._range_noted = True
            reasons.append(f"range reading {value:.4g} m given on a car that declares no range sensor (has_ultrasonic = false): counted")
        return clamp_to_sensor(value, self.vehicle, reasons)

    # -- QR localisation -------------------------------------------------------------------------
    def _staleness(
        self, obs: Observation, t: float, seen: tuple[str, ...], reasons: list[str]
    ) -> tuple[float, LocalisationState | None]:
        if not self.vehicle.has_qr_localisation:
            return 0.0, None  # no QR localisation on this car: the cue does not apply
        payloads = list(seen)
        if obs.qr_payload is not None:
            payloads.append(obs.qr_payload)
        state = self.localiser.update(t, payloads, reading(obs.odometer_m), reading(obs.speed_mps))
        reasons.extend(state.reasons)
        return state.staleness_s, state

    @staticmethod
    def _fuse_lead_range(lead: Lead | None, range_m: float) -> Lead | None:
        """A lead straight ahead is what the ultrasonic measures: its reading beats ground-plane geometry."""
        if lead is None or not lead.usable or not math.isfinite(range_m):
            return lead
        if abs(lead.bearing_deg) <= ULTRASONIC_CONE_DEG / 2:
            return Lead(lead.bearing_deg, range_m)
        return lead


def clamp_to_sensor(range_m: float, vehicle: VehicleLimits, notes: list[str]) -> float:
    """A finite range beyond the range sensor's maximum counts as the maximum — "nothing within the maximum", what
    ``inf`` means for a car with the sensor — never as that many metres (a worse-looking reading must not buy a higher
    limit than "nothing in range" gives). Within the maximum, and ``inf``, unchanged."""
    top = vehicle.ultrasonic_max_range_m
    if math.isfinite(range_m) and range_m > top:
        notes.append(f"obstacle_range_m {range_m:.4g} m is beyond the range sensor's maximum {top:g} m: counted as "
                     f"nothing within {top:g} m")
        return top
    return range_m


SAMPLE_STRIDE = 997  # [bytes] the quick look at a frame before comparing all of it (prime: no alignment with rows or channels)


def same_bytes(pixels: np.ndarray, last: np.ndarray | None) -> bool:
    """True if ``pixels`` (C-contiguous) has the shape, dtype and every byte of ``last``.

    Exact, unlike a hash, and cheap: a strided sample of the bytes is compared first — a new camera frame differs
    there (sensor noise changes most pixels) — so the full comparison runs only on a likely repeat. Arrays of Python
    objects have no pixel bytes: never the same (each is analysed, and rejected as no image).
    """
    if last is None or pixels.shape != last.shape or pixels.dtype != last.dtype or pixels.dtype.hasobject:
        return False
    a, b = pixels.reshape(-1).view(np.uint8), last.reshape(-1).view(np.uint8)
    return bool(np.array_equal(a[::SAMPLE_STRIDE], b[::SAMPLE_STRIDE]) and np.array_equal(a, b))


def _keep_copy(pixels: np.ndarray, buffer: np.ndarray | None) -> np.ndarray:
    """A private copy of ``pixels`` (the caller may refill its buffer), reusing ``buffer`` when it has the same layout."""
    if buffer is None or buffer.shape != pixels.shape or buffer.dtype != pixels.dtype:
        return pixels.copy()
    np.copyto(buffer, pixels)
    return buffer
