"""``fearguard learn``: recordings of normal driving → a track profile (docs/learning.md).

The recordings are read as ``replay`` reads them (videos, image folders, Donkey tubs, ROS bags; a tub's deleted
records and unreadable frames skipped). Frames where the recording says the car stood or backed (a tub's throttle at or
below ``MOVING_THROTTLE``) are not normal driving and are left out. From the rest it learns:

- the familiarity model (``profile.py``): weighted features, their principal components, a bank of learnt frames
  and the recordings' own distances for the calibration;
- the normal light: the ``BAND_PERCENTILES`` of the brightness cue as the camera pipeline measures it;
- the markings the camera's lane model sees this track by (light paint or dark tape: ``learnt_markings``) and what the
  track guides the car by (two lines, a centre line, one edge: ``learnt_guidance``); with them, its lane confidence on
  this track (the median), how much of the marking region its occlusion measure calls hidden in normal driving
  (``OCCLUSION_PERCENTILE``), and the colours of the track's markings;
- the floor: its colours and where the picture usually shows it (``floor.py``);
- the light's shape: each learnt frame's grey levels (``light.py``), calibrated like the familiarity.
"""

from __future__ import annotations

import math
from collections.abc import Callable, Sequence
from dataclasses import dataclass
from pathlib import Path

import cv2
import numpy as np

from fearguard.camera import CameraModel
from fearguard.errors import FearguardError
from fearguard.lane import MARKINGS
from fearguard.replay.recordings import open_recording
from fearguard.replay.sources import parse_position
from fearguard.track.features import features_of, shrink
from fearguard.track.floor import FloorView, floor_view, learn_floor
from fearguard.track.light import LightModel, light_of
from fearguard.track.profile import (
    BAND_PERCENTILES,
    CALIBRATION_GAP_S,
    NEIGHBOURS,
    OCCLUSION_PERCENTILE,
    TrackProfile,
    block_weights,
)
from fearguard.vision.confidence import LaneEvidence
from fearguard.vision.frame import SEEN_WELL_SUPPORT, FrameAnalysis, FramePipeline

COMPONENTS = 24  # principal components kept: enough for a track's few kinds of view, few enough to be fast
BANK_MAX = 2000  # [frames] learnt frames kept for the comparison (more: thinned evenly; keeps a frame ≤ 1 ms)
CALIBRATION_MAX = 1000  # [frames] frames whose distances calibrate the cue
ANALYSED_MAX = 1500  # [frames] frames the camera pipeline measures for the light band and the lane confidence
ONE_LINE_RATIO = 3.0  # [-] frames showing one boundary seen well per frame showing both, from which one line guides the track
ONE_LINE_MIN_SHARE = 0.25  # [-] of the analysed frames: fewer showing one line seen well teach nothing about the guidance
CENTRE_SHARE = 0.2  # [-] of the width: a one-line track's line this close to the picture's middle is a centre line
DARK_MARGIN = 0.05  # [0..1] dark markings are learnt only when the lane model's median confidence with them is this much
#                    higher than with light ones (noise on a track where neither sees anything keeps the default)
MOVING_THROTTLE = 0.05  # [-] a tub frame with throttle at or below this is the car standing or backing: not normal driving
MIN_FRAMES = 20  # [frames] fewer normal-driving frames than this teach nothing
MARKING_CLUSTERS = 4  # colour clusters of high-contrast floor pixels tried as markings
MARKING_PRESENT_SHARE = 0.5  # [-] a cluster seen in at least this share of frames is one of the track's markings
MARKING_MIN_PIXELS = 0.003  # [-] share of the lower half a cluster needs in a frame to count as seen there
_THROTTLE_KEYS = ("user_throttle_donkey", "pilot_throttle_donkey")


@dataclass(frozen=True)
class LearnOptions:
    """Which frames to learn from: the same --fps/--from/--to/--every as replay."""

    fps: float | None = None
    start: str | None = None
    stop: str | None = None
    every: int = 1
    camera: CameraModel | None = None


@dataclass(frozen=True)
class Learnt:
    """A profile and how it was learnt (for the printout and the picture)."""

    profile: TrackProfile
    frames_read: int
    frames_standing: int  # left out: the car stood or backed
    skipped: int  # frames the recordings could not give
    typical_frames: tuple[np.ndarray, ...]  # a few learnt frames, for the picture
    brightness: np.ndarray  # the brightness cue on the analysed frames


@dataclass
class _Frames:
    features: list[np.ndarray]
    recording: list[int]
    t_s: list[float]
    brightness: list[float]
    lanes: dict[str, list[LaneRead]]  # per markings (lane.MARKINGS): the camera lane model's reading of each analysed frame
    marking_pixels: list[np.ndarray]
    floor: list[FloorView]
    typical: list[np.ndarray]
    light: list[np.ndarray]  # each learnt frame's light (``light.light_of``)


def learn_track(recordings: Sequence[str | Path], options: LearnOptions = LearnOptions(),
                on_frame: Callable[[int], None] | None = None) -> Learnt:
    """Learn a profile from recordings of normal driving (raises ``FearguardError`` when there is too little)."""
    got = _Frames([], [], [], [], {m: [] for m in MARKINGS}, [], [], [], [])
    read = standing = skipped = 0
    for rec_id, path in enumerate(recordings):
        source = open_recording(path, options.fps)
        start = parse_position(options.start, source.fps) if options.start else 0
        stop = parse_position(options.stop, source.fps) if options.stop else None
        pipelines = {m: FramePipeline(options.camera, markings=m) for m in MARKINGS}
        total = source.expected_frames
        stride = max(1, math.ceil((total or ANALYSED_MAX) / options.every / ANALYSED_MAX))
        for k, frame in enumerate(source.iter_frames(start, stop, options.every)):
            read += 1
            if on_frame is not None:
                on_frame(read)
            if _standing(frame.log_fields):
                standing += 1
                continue
            shrunk = shrink(frame.image_bgr)
            if shrunk is None:
                skipped += 1
                continue
            got.features.append(features_of(*shrunk))
            got.light.append(light_of(shrunk[1]))
            got.recording.append(rec_id)
            got.t_s.append(frame.t_s)
            if k % stride == 0:
                for m, pipeline in pipelines.items():
                    a = pipeline.process(frame.image_bgr, frame.t_s)
                    got.lanes[m].append(LaneRead.of(a))
                    if m == "light":
                        got.brightness.append(a.brightness)
                got.marking_pixels.append(_contrast_pixels(frame.image_bgr))
                got.floor.append(floor_view(frame.image_bgr))
                if len(got.typical) < 64:
                    got.typical.append(frame.image_bgr)
        skipped += len(source.skipped)
    if len(got.features) < MIN_FRAMES:
        raise FearguardError(f"learn: only {len(got.features)} frames of normal driving in {', '.join(map(str, recordings))} "
                             f"({standing} with the car standing or backing, {skipped} unreadable); at least {MIN_FRAMES} "
                             f"are needed")
    profile = _fit(got, ", ".join(str(p) for p in recordings))
    pick = np.linspace(0, len(got.typical) - 1, min(6, len(got.typical))).astype(int)
    return Learnt(profile, read, standing, skipped, tuple(got.typical[i] for i in pick), np.array(got.brightness))


def _standing(log_fields: object) -> bool:
    """The recording says the car stood or backed on this frame (a tub's throttle ≤ MOVING_THROTTLE)."""
    if not hasattr(log_fields, "get"):
        return False
    for key in _THROTTLE_KEYS:
        v = log_fields.get(key)
        if isinstance(v, (int, float)) and not isinstance(v, bool) and math.isfinite(v):
            return v <= MOVING_THROTTLE
    return False


def _fit(got: _Frames, source: str) -> TrackProfile:
    feats = np.array(got.features)
    mean = feats.mean(axis=0)
    weights = block_weights(feats)
    z = (feats - mean) * weights
    _, _, vt = np.linalg.svd(z, full_matrices=False)
    basis = vt[: min(COMPONENTS, vt.shape[0])]
    partial = TrackProfile(source, len(feats), mean, weights, basis, np.zeros((1, basis.shape[0] + 1)), np.ones(1),
                           (0.0, 255.0), math.nan)
    embedded = partial.embed(feats)
    keep = np.unique(np.linspace(0, len(feats) - 1, min(BANK_MAX, len(feats))).astype(int))
    bank = embedded[keep]
    recording, t_s, light = np.array(got.recording), np.array(got.t_s), np.array(got.light)
    calib = _calibration(embedded, keep, recording, t_s)
    light_calib = _calibration(light, keep, recording, t_s)
    b = np.array([x for x in got.brightness if math.isfinite(x)])
    band = tuple(float(v) for v in np.percentile(b, BAND_PERCENTILES)) if b.size else (0.0, 255.0)
    markings = learnt_markings([r.confidence for r in got.lanes["light"]], [r.confidence for r in got.lanes["dark"]])
    reads = got.lanes[markings]
    guidance = learnt_guidance(reads)
    lanes = _finite([r.confidence if guidance == "two_lines" else r.as_guidance(guidance) for r in reads])
    occ = _finite([r.occlusion for r in reads])
    return TrackProfile(
        source=source, frames_learnt=len(feats), mean=mean, weights=weights, basis=basis, bank=bank,
        calibration_distances=np.sort(calib), brightness_band=(band[0], band[1]),
        lane_confidence_median=float(np.median(lanes)) if lanes.size else math.nan,
        marking_colours_bgr=_marking_colours(got.marking_pixels),
        occlusion_usual=float(np.percentile(occ, OCCLUSION_PERCENTILE)) if occ.size else math.nan,
        floor=learn_floor(got.floor), light=LightModel(light[keep], np.sort(light_calib)), markings=markings,
        guidance=guidance,
    )


def learnt_markings(light: Sequence[float], dark: Sequence[float]) -> str:
    """The markings the camera's lane model sees this track by, from its lane confidences on the recordings with each:
    dark (black or dark tape) where the median beats the light markings' (paint, white or yellow tape) by DARK_MARGIN,
    else light. Unknown confidences (NaN) are left out; none known counts as 0."""
    def median(xs: Sequence[float]) -> float:
        v = _finite(xs)
        return float(np.median(v)) if v.size else 0.0

    return "dark" if median(dark) >= median(light) + DARK_MARGIN else "light"


@dataclass(frozen=True)
class LaneRead:
    """The camera lane model's reading of one analysed frame: its confidence (two lines), occlusion, the evidence behind
    them, and where each boundary seen well this frame meets the road region's bottom row (share of the width)."""

    confidence: float
    occlusion: float
    evidence: LaneEvidence | None
    seen_well_at: tuple[float, ...]

    @staticmethod
    def of(a: FrameAnalysis) -> LaneRead:
        ev, region = a.evidence, a.region
        lines = [] if ev is None or region is None else [
            line for line, support in ((a.left, ev.support_left), (a.right, ev.support_right))
            if line is not None and support >= SEEN_WELL_SUPPORT]
        at = tuple(line.u_at(region.bottom_v_px) / region.width_px for line in lines) if region is not None else ()
        return LaneRead(a.lane_confidence, a.occlusion, ev, at)

    def as_guidance(self, guidance: str) -> float:
        return self.evidence.as_guidance(guidance) if self.evidence is not None else math.nan


def learnt_guidance(reads: Sequence[LaneRead]) -> str:
    """What the track guides the car by, from the recordings: one line where frames that show exactly one boundary seen
    well outnumber those that show both ONE_LINE_RATIO times (a two-line track shows one line now and then, in a tight
    curve: a one-line track mostly) and are at least ONE_LINE_MIN_SHARE of the frames (a lane model that hardly sees
    the track tells nothing); a centre line where that line's median place at the bottom of the picture lies within
    CENTRE_SHARE of the width from the middle, else one edge. Otherwise two lines (the default)."""
    one = [r.seen_well_at[0] for r in reads if len(r.seen_well_at) == 1]
    both = sum(len(r.seen_well_at) == 2 for r in reads)
    if len(one) < max(ONE_LINE_MIN_SHARE * len(reads), ONE_LINE_RATIO * both, 1):
        return "two_lines"
    return "centre_line" if abs(float(np.median(one)) - 0.5) <= CENTRE_SHARE else "one_edge"


def _finite(xs: Sequence[float]) -> np.ndarray:
    return np.array([x for x in xs if math.isfinite(x)], dtype=np.float64)


def _calibration(embedded: np.ndarray, keep: np.ndarray, recording: np.ndarray, t_s: np.ndarray) -> np.ndarray:
    """Each calibration frame's mean distance to its NEIGHBOURS nearest bank frames that are not its neighbours in
    time (another recording, or more than the gap away). The gap shrinks for a recording too short to leave any."""
    n = len(embedded)
    span = float(np.ptp(t_s)) if n > 1 and np.all(np.isfinite(t_s)) else 0.0
    gap = min(CALIBRATION_GAP_S, span / 4.0)
    idx = np.unique(np.linspace(0, n - 1, min(CALIBRATION_MAX, n)).astype(int))
    bank, bank_rec, bank_t = embedded[keep], recording[keep], t_s[keep]
    out = np.empty(idx.size)
    for j, i in enumerate(idx):
        d2 = np.einsum("ij,ij->i", bank - embedded[i], bank - embedded[i])
        near = (bank_rec == recording[i]) & (np.abs(bank_t - t_s[i]) <= gap)
        near |= (keep == i)
        d2 = d2[~near]
        if d2.size == 0:
            out[j] = 0.0
            continue
        k = min(NEIGHBOURS, d2.size)
        out[j] = float(np.sqrt(np.partition(d2, k - 1)[:k]).mean())
    return out


def _contrast_pixels(bgr: np.ndarray, samples: int = 200) -> np.ndarray:
    """Colours (BGR) of a sample of the lower half's pixels that stand out from their surroundings (marking candidates),
    plus the share of the lower half they cover in the last row of the result."""
    small = cv2.resize(bgr, (160, 120), interpolation=cv2.INTER_AREA)[60:]
    lab = cv2.cvtColor(small, cv2.COLOR_BGR2LAB).astype(np.float32)
    local = cv2.blur(lab, (15, 15))
    contrast = np.sqrt(((lab - local) ** 2).sum(axis=2))
    ys, xs = np.nonzero(contrast > 25.0)
    share = ys.size / contrast.size
    rng = np.random.default_rng(ys.size)
    pick = rng.choice(ys.size, size=min(samples, ys.size), replace=False) if ys.size else np.zeros(0, dtype=int)
    colours = small[ys[pick], xs[pick]].astype(np.float32)
    return np.vstack([colours, [[share, share, share]]])


def _marking_colours(samples: list[np.ndarray]) -> np.ndarray:
    """The typical colours of high-contrast floor pixels seen in at least MARKING_PRESENT_SHARE of the frames."""
    per_frame = [s[:-1] for s in samples if len(s) > 1]
    if len(per_frame) < 3:
        return np.zeros((0, 3))
    allpx = np.vstack(per_frame).astype(np.float32)
    k = min(MARKING_CLUSTERS, len(allpx))
    criteria = (cv2.TERM_CRITERIA_EPS + cv2.TERM_CRITERIA_MAX_ITER, 20, 1.0)
    cv2.setRNGSeed(0)
    _, labels, centres = cv2.kmeans(allpx, k, None, criteria, 3, cv2.KMEANS_PP_CENTERS)
    labels = labels.ravel()
    seen = np.zeros(k)
    start = 0
    for s in samples:
        n = len(s) - 1
        if n <= 0:
            continue
        lab = labels[start:start + n]
        start += n
        share = float(s[-1, 0])
        for c in range(k):
            if share * (lab == c).mean() >= MARKING_MIN_PIXELS:
                seen[c] += 1
    present = seen / len(samples) >= MARKING_PRESENT_SHARE
    return centres[present].astype(np.float64)
