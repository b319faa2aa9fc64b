"""Lane boundaries from one frame: the classic pipeline of the field, made robust to light.

road region (lower image, below the horizon) → marking features → Canny edges → probabilistic Hough
segments → split by slope into left/right → weighted line fit per side → support along each line.

Marking features: a morphological top-hat of the lightness channel keeps what is brighter than its
surroundings over a short horizontal window (a marking on asphalt, in sun or shade, on dark or pale
concrete) and a hue/saturation test keeps yellow paint. The contrast a marking needs is absolute
(``RIDGE_MIN``): in glare or darkness the markings' contrast collapses and the evidence with it.
Lines are u = a·v + b in working-image pixels (u right, v down), fitted as u(v) because lane lines
are steep in the image.
"""

from __future__ import annotations

import math
from collections.abc import Iterator
from dataclasses import dataclass, replace
from functools import lru_cache
from itertools import islice

import cv2
import numpy as np

from fearguard.camera import CameraModel
from fearguard.lane import MARKINGS
from fearguard.vision.exposure import SATURATED_MIN
from fearguard.vision.ridges import RidgeMaps, ridge_maps, scan_ridges

WORK_WIDTH_PX = 320  # [px] frames are analysed at this width (aspect kept): the cost is then fixed
TOP_FRACTION = 0.62  # [-] road region starts at this share of the height without a camera model (dash-cam horizon ≈ 0.58)
BOTTOM_FRACTION = 0.93  # [-] and ends here (many dash-cams see their own bonnet below)
PITCHED_DEG = 8.0  # [deg] a camera pitched down at least this much gets the near-road settings below
SIDE_FRACTION = 0.75  # [-] of the road region's height: with a camera model, the near part searched across the full width
HORIZON_MARGIN = 0.04  # [-] with a camera model the region starts this share of the height below the horizon
TOPHAT_WIDTH = 0.055  # [-] top-hat window as a share of the width: wider than a far marking, narrower than a far lane
NEAR_TOPHAT_WIDTH = 0.1  # [-] the same in the near half of the road region (a dash-cam's near marking: ~10 px)
TOPHAT_WIDTH_PITCHED = 0.12  # [-] far window with a camera model: a low camera pitched down sees wide tape ...
NEAR_TOPHAT_WIDTH_PITCHED = 0.35  # [-] ... and near window (a model car's tape: ~60 px across there)
MARKING_SHARE = (0.012, 0.12)  # [-] of the lane width: paint width on a road (10-30 cm lines on 3-3.7 m lanes) ...
MARKING_SHARE_PITCHED = (0.05, 0.4)  # [-] ... and with a low pitched-down camera (a model car's 48 mm tape on ~0.2 m lanes)
CLUTTER = (0.2, 0.45)  # [-] a road region is mostly road: beyond this share of marking pixels ridges are texture ...
CLUTTER_PITCHED = (0.3, 0.6)  # [-] ... (a model car's wide tape fills more of its near view)
RIDGE_MIN = 14  # [grey levels] a marking must be this much brighter than the road beside it ...
RIDGE_RATIO = 0.15  # [-] ... and by this share of the road's own lightness (a ratio: the same in sun and shade)
YELLOW_HUE = (14, 40)  # [OpenCV hue 0..180] yellow paint
YELLOW_SAT_MIN = 70  # [0..255] saturation of yellow paint
YELLOW_LIGHT_MIN = 70  # [0..255] lightness of yellow paint ... or, darker, saturation × lightness ≥ SAT_MIN × LIGHT_MIN: below
#   L = 128 that product is the chroma (max − min of B, G, R: 2·S·L/255 ≥ 38 grey levels), so a yellow line in the dark,
#   as strongly coloured as paint at the lightness floor, is still paint (MetaDrive by night: L 55, S 255, chroma 110;
#   the asphalt beside it chroma ~9), while a dark pixel whose hue is noise (chroma of a few levels) is not
SLOPE_MIN = 0.35  # [-] |dv/du| below this a segment is too flat to be a lane boundary
HOUGH_THRESHOLD = 10  # [votes]
HOUGH_MIN_LENGTH = 0.03  # [-] of the width
HOUGH_MAX_GAP = 0.03  # [-] of the width
FIT_OUTLIER_PX = 0.03  # [-] of the width: a segment whose end points are this close to a line supports it
RANSAC_MAX_SEGMENTS = 40  # [-] per side
RANSAC_KEEP = 0.4  # [-] lines with this share of the best support compete (marking evidence decides)
CANDIDATES = 3  # [-] competing lines per side, scanned for marking ridges
PREFER_SHARE = 0.8  # [-] a later candidate must beat the preferred one's ridge support by more than 1/this
MIN_OFF_CENTRE = 0.08  # [-] of the width: a boundary this close to the image centre at the bottom is a seam, not a lane edge
DEFAULT_HALF_WIDTH = 0.32  # [-] of the width: default lane's half-width at the bottom row (dash-cam, centred)
MIN_LANE_WIDTH = 0.1  # [-] of the width at the bottom row: narrower than this, two boundaries are not one lane
REFIT_MIN_ROWS = 6  # [rows] marking ridges needed to refit a boundary on their inner edges
REFIT_MAX_SLOPE_CHANGE = 0.5  # [px/px] a refit turning the line more than this is a different line: the Hough fit stays
LANE_WIDTH_RANGE = (0.15, 1.6)  # [-] plausible lane width at the region's middle row, as a share of the image width
VP_ABOVE_TOP = 0.25  # [-] of the height: the lines may meet at most this far above the region top ...
VP_BELOW_TOP = 0.04  # [-] ... and at most this far below it (lines crossing on the road are impossible)
VP_U_RANGE = (0.1, 0.9)  # [-] of the width: where the vanishing point may lie horizontally
FAR_SHIFT_MAX = 0.3  # [-] of the width: the road region's far edge follows the lane at most this far sideways
RAMP = 0.1  # [-] of the image size: plausibility falls from 1 to 0 over this distance outside a range


@dataclass(frozen=True)
class RoadRegion:
    """Where the ego lane is searched in the working image: rows top..bottom and a trapezoid mask."""

    width_px: int
    height_px: int
    top_v_px: int
    bottom_v_px: int
    polygon_px: tuple[tuple[int, int], ...]
    far_tophat: float = 0.055  # [-] of the width: top-hat window in the far half of the region
    near_tophat: float = 0.2  # [-] of the width: top-hat window in the near half (markings are widest there)
    marking_share: tuple[float, float] = MARKING_SHARE  # [-] of the lane width: narrowest and widest paint
    clutter: tuple[float, float] = CLUTTER  # [-] share of the region that is marking pixels: full evidence up to, none from


@dataclass(frozen=True)
class SeenRows:
    """The image rows a boundary's marking ridges were found on: how many, their mean and their spread. A line through
    one short dash is known near the dash and barely beyond it (its slope rests on a few rows); a solid line, or dashes
    far apart, pin it down over the whole region (a detection is compared with its track within these rows:
    confidence.agreement)."""

    count: int
    mean_v_px: float
    std_v_px: float

    @staticmethod
    def of(rows: np.ndarray) -> SeenRows | None:
        """The spread of a set of rows; None for fewer than two (no direction)."""
        n = len(rows)
        if n < 2:
            return None
        mean = float(rows.sum()) / n  # sums and a dot product: a quarter of mean() and std()'s cost, for every candidate line
        return SeenRows(n, mean, math.sqrt(max(0.0, float(rows @ rows) / n - mean * mean)))


@dataclass(frozen=True)
class LaneLine:
    """One boundary as u = slope·v + intercept in working pixels, with the evidence behind it."""

    slope: float  # [px/px] du/dv
    intercept_px: float
    support: float  # [0..1] share of the region's rows with a marking ridge on the line, saturating (ridges.SUPPORT_FULL)
    segments: int  # Hough segments that built it
    rows: SeenRows | None = None  # where on the line the ridges were found (None: not measured, read as the whole region)

    def u_at(self, v_px: float) -> float:
        return self.slope * v_px + self.intercept_px


@dataclass(frozen=True)
class LaneDetection:
    """Both boundaries (None when not found) and the feature mask they came from."""

    region: RoadRegion
    left: LaneLine | None
    right: LaneLine | None
    features: np.ndarray  # uint8 0/255 marking pixels inside the region
    segment_count: int
    maps: RidgeMaps  # the ridge tables (their marking-pixel integral serves occlusion too)


def _inside(x: float, lo: float, hi: float, ramp: float) -> float:
    """1 inside [lo, hi], falling linearly to 0 at ramp outside."""
    if lo <= x <= hi:
        return 1.0
    d = lo - x if x < lo else x - hi
    return max(0.0, 1.0 - d / ramp)


def vanishing_point(left: LaneLine, right: LaneLine) -> tuple[float, float] | None:
    """Where the two boundaries meet (u, v); None if they are parallel in the image."""
    den = left.slope - right.slope
    if abs(den) < 1e-9:
        return None
    v = (right.intercept_px - left.intercept_px) / den
    return left.u_at(v), v


def geometry_plausibility(left: LaneLine, right: LaneLine, region: RoadRegion) -> float:
    """1 when lane width and vanishing point look like a lane seen from a forward camera, else falling to 0."""
    w, h = region.width_px, region.height_px
    mid = 0.5 * (region.top_v_px + region.bottom_v_px)
    width = (right.u_at(mid) - left.u_at(mid)) / w
    vp = vanishing_point(left, right)
    if vp is None or width <= 0:
        return 0.0
    vp_u, vp_v = vp[0] / w, (vp[1] - region.top_v_px) / h
    return min(
        _inside(width, *LANE_WIDTH_RANGE, RAMP),
        _inside(vp_v, -VP_ABOVE_TOP, VP_BELOW_TOP, RAMP),
        _inside(vp_u, *VP_U_RANGE, RAMP),
    )


def work_size(width_px: int, height_px: int) -> tuple[int, int]:
    """Working size for a frame: WORK_WIDTH_PX wide (never upscaled), aspect kept."""
    if width_px <= WORK_WIDTH_PX:
        return width_px, height_px
    return WORK_WIDTH_PX, max(1, round(height_px * WORK_WIDTH_PX / width_px))


def assumed_horizon_v_px(width_px: int, height_px: int, camera: CameraModel | None = None) -> float:
    """Image row where the road region assumes the horizon: the pitched camera model's, else the dash-cam default
    (``road_region`` starts HORIZON_MARGIN of the height below it)."""
    if camera is not None and camera.pitch_deg != 0.0:
        return camera.scaled_to(width_px, height_px).horizon_v_px()
    return (TOP_FRACTION - HORIZON_MARGIN) * height_px


def road_region(width_px: int, height_px: int, camera: CameraModel | None = None) -> RoadRegion:
    """Road region of a working image: below the horizon (camera model) or a dash-cam default."""
    top = TOP_FRACTION * height_px
    if camera is not None and camera.pitch_deg != 0.0:
        top = camera.scaled_to(width_px, height_px).horizon_v_px() + HORIZON_MARGIN * height_px
    top_v = int(min(max(top, 0.0), 0.8 * height_px))
    pitched = camera is not None and camera.pitch_deg >= PITCHED_DEG
    bottom_v = height_px - 1 if pitched else int(BOTTOM_FRACTION * height_px)  # a dash-cam sees its bonnet below
    w = width_px - 1
    # a low camera pitched well down (a model car's) sees the lines leave through the image sides, and wide tape
    side = SIDE_FRACTION if pitched else 0.0
    side_v = int(bottom_v - side * (bottom_v - top_v))
    polygon = ((0, bottom_v), (0, side_v), (int(0.38 * w), top_v), (int(0.62 * w), top_v), (w, side_v), (w, bottom_v))
    if not pitched:
        return RoadRegion(width_px, height_px, top_v, bottom_v, polygon, TOPHAT_WIDTH, NEAR_TOPHAT_WIDTH)
    return RoadRegion(
        width_px, height_px, top_v, bottom_v, polygon, TOPHAT_WIDTH_PITCHED, NEAR_TOPHAT_WIDTH_PITCHED, MARKING_SHARE_PITCHED,
        CLUTTER_PITCHED,
    )


def region_mask(region: RoadRegion, far_shift_px: int = 0) -> np.ndarray:
    """uint8 0/255 mask of the region's trapezoid; ``far_shift_px``: its top edge moved that far sideways (+ right)."""
    mask = np.zeros((region.height_px, region.width_px), np.uint8)
    polygon = [(u + far_shift_px if v == region.top_v_px else u, v) for u, v in region.polygon_px]
    cv2.fillConvexPoly(mask, np.array(polygon, np.int32), 255)
    return mask


def far_shift_px(lane_centre_top_u_px: float | None, region: RoadRegion) -> int:
    """How far the road region's far edge moves sideways to lie on the lane: the lane's centre at the region's top row
    (last frame's, between its straight lines) less the image centre, within ±FAR_SHIFT_MAX of the width; 0 without a
    lane."""
    if lane_centre_top_u_px is None or not math.isfinite(lane_centre_top_u_px):
        return 0
    limit = FAR_SHIFT_MAX * region.width_px
    return round(min(limit, max(-limit, lane_centre_top_u_px - 0.5 * region.width_px)))


@lru_cache(maxsize=64)
def region_toward(region: RoadRegion, far_shift_px: int) -> np.ndarray:
    """The region's mask with its far edge moved ``far_shift_px`` sideways, onto the lane (read-only).

    The trapezoid's top is centred for a straight lane ahead; round a tight bend, or with the car yawed in its lane,
    the lane lies to one side and its inner boundary leaves the centred trapezoid (MetaDrive, R 21 m at 10 m/s: the
    yellow centre line outside it from 12 m on, the left boundary fitted to whatever was left inside, the car
    under-steered out of the bend). Centring the far edge between last frame's straight lines keeps them in the
    search. Not on the traced bend's far end: the straight lines are fitted as chords, and a region centred on the
    curve cut off the outer chord's far part on a gentle bend (the simulator's three_lane_curve: confidence 0.88 →
    0.35); nor widened on one side only: a yawed car then took the next lane's lines, with confidence, for its own."""
    mask = region_mask(region, far_shift_px)
    mask.flags.writeable = False
    return mask


def marking_features(
    hls: np.ndarray, mask: np.ndarray, region: RoadRegion | None = None, light: np.ndarray | None = None
) -> np.ndarray:
    """uint8 0/255 pixels that look like lane paint (bright ridges or yellow) inside the mask, from an HLS image.

    Markings widen toward the camera, so the top-hat window is wider in the near half of the road region (the
    top-hat is row by row, so each half is computed on its own rows only). ``light``: ``smoothed_light(hls)`` when
    the caller already has it.
    """
    light = smoothed_light(hls) if light is None else light
    ridge_l = _ridges(light, region)
    # every test on whole uint8 images (OpenCV's vectorised loops; numpy's on the strided HLS channels cost ~5×)
    background = cv2.subtract(light, ridge_l)  # the opening: the road's lightness under the marking (≤ light: exact)
    bright = cv2.bitwise_and(cv2.compare(ridge_l, cv2.LUT(background, _BRIGHT_MIN), cv2.CMP_GE), mask)
    yellow = cv2.inRange(hls, (YELLOW_HUE[0], 0, YELLOW_SAT_MIN), (YELLOW_HUE[1], 255, 255))
    sat = cv2.extractChannel(hls, 2)  # once, contiguous: the chroma test and the saturation ridge both read it
    yellow &= cv2.compare(cv2.multiply(sat, light, dtype=cv2.CV_16U), _YELLOW_CHROMA, cv2.CMP_GE) & mask
    rows = np.flatnonzero(cv2.reduce(yellow, 1, cv2.REDUCE_SUM, dtype=cv2.CV_32S))  # the saturation ridge matters only on these rows
    if len(rows):
        yellow &= cv2.compare(_ridges(sat, region, rows), RIDGE_MIN, cv2.CMP_GE)
    return bright | yellow


_YELLOW_CHROMA = YELLOW_SAT_MIN * YELLOW_LIGHT_MIN  # saturation × lightness of yellow paint at the least (YELLOW_LIGHT_MIN)
# the least ridge that is bright over each background lightness b: ≥ RIDGE_MIN and ≥ RIDGE_RATIO·b (as float, rounded up);
# over a background too bright for the ratio to fit under the clip (b > ~217: glare's veil), paint reaching the clip
# (SATURATED_MIN) is as bright as the camera can show it: the ratio is not seen there, RIDGE_MIN still is
_BRIGHT_MIN = np.maximum(RIDGE_MIN, np.minimum(np.ceil(RIDGE_RATIO * np.arange(256)), SATURATED_MIN - np.arange(256))).astype(np.uint8)


def marking_view(hls: np.ndarray, top_v_px: int, bottom_v_px: int, markings: str = "light") -> np.ndarray:
    """The HLS image the marking finder reads (``MARKINGS``): the picture itself for light markings; for dark ones — black,
    dark blue or dark red tape on a paler floor — the road rows' lightness inverted, so a dark line is a ridge found by the
    same top-hat, ridge-width and flank tests as paint (contrast to the local background, by a ratio), and their
    saturation cleared (the yellow-paint test is for light paint). The rows outside top..bottom are returned as given."""
    if markings == "light":
        return hls
    if markings != "dark":
        raise ValueError(f"markings must be one of {', '.join(MARKINGS)}, got {markings!r}")
    view = hls.copy()
    band = view[top_v_px : bottom_v_px + 1]
    band[:, :, 1] = cv2.bitwise_not(np.ascontiguousarray(band[:, :, 1]))
    band[:, :, 2] = 0
    return view


def smoothed_light(hls: np.ndarray) -> np.ndarray:
    """HLS lightness, 3×3 Gaussian-smoothed: the classic smoothing step (sensor noise must not make ridges)."""
    return cv2.GaussianBlur(hls[:, :, 1], (3, 3), 0)


def _ridges(channel: np.ndarray, region: RoadRegion | None, rows: np.ndarray | None = None) -> np.ndarray:
    """Top-hat of one channel: the near window on the near half of the region's rows, the far window elsewhere. The
    top-hat is row by row, so each window runs on its own rows only (the same result, half the work), and ``rows``
    (sorted indices) limits it to the rows a caller needs (the others are 0)."""
    w, n = channel.shape[1], len(channel)
    windows: tuple[tuple[int, int, float], ...] = ((0, n, TOPHAT_WIDTH),)
    if region is not None:
        split, end = (region.top_v_px + region.bottom_v_px) // 2, min(region.bottom_v_px + 1, n)
        windows = ((0, split, region.far_tophat), (split, end, region.near_tophat), (end, n, region.far_tophat))
    out = np.zeros_like(channel)
    for lo, hi, window in windows:
        mine = slice(lo, hi) if rows is None else rows[np.searchsorted(rows, lo) : np.searchsorted(rows, hi)]
        if hi > lo and (rows is None or len(mine)):
            out[mine] = _tophat(channel[mine], window * w)
    return out


def _tophat(channel: np.ndarray, width_px: float) -> np.ndarray:
    """What is brighter than its surroundings within a horizontal window (morphological top-hat)."""
    k = max(3, int(width_px) | 1)
    return cv2.morphologyEx(channel, cv2.MORPH_TOPHAT, cv2.getStructuringElement(cv2.MORPH_RECT, (k, 1)))


def hough_segments(features: np.ndarray) -> np.ndarray:
    """Probabilistic Hough segments (N, 4: u1, v1, u2, v2) on the Canny edges of the feature mask."""
    edges = cv2.Canny(features, 50, 150)
    w = features.shape[1]
    lines = cv2.HoughLinesP(
        edges, 1, math.pi / 180, HOUGH_THRESHOLD, minLineLength=max(4, HOUGH_MIN_LENGTH * w), maxLineGap=max(2, HOUGH_MAX_GAP * w)
    )
    return np.empty((0, 4), np.float64) if lines is None else lines.reshape(-1, 4).astype(np.float64)


def split_by_slope(segments: np.ndarray, width_px: int) -> tuple[np.ndarray, np.ndarray]:
    """Left boundary segments rise to the right (dv/du < 0) in the left part; right ones the mirror."""
    if len(segments) == 0:
        return segments, segments
    du = segments[:, 2] - segments[:, 0]
    dv = segments[:, 3] - segments[:, 1]
    steep = np.abs(dv) >= SLOPE_MIN * np.abs(du)
    steep &= np.abs(du) + np.abs(dv) > 0
    mid_u = 0.5 * (segments[:, 0] + segments[:, 2])
    neg = du * dv < 0
    left = steep & neg & (mid_u < 0.62 * width_px)
    right = steep & ~neg & (du != 0) & (mid_u > 0.38 * width_px)
    right |= steep & (du == 0) & (mid_u > 0.5 * width_px)
    left |= steep & (du == 0) & (mid_u <= 0.5 * width_px)
    return segments[left], segments[right]


def fit_line(segments: np.ndarray, region: RoadRegion, prior: LaneLine | None = None) -> tuple[float, float] | None:
    """The preferred boundary among one side's segments (the first of ``candidate_fits``), or None."""
    return next(candidate_fits(segments, region, prior, 1), None)


def candidate_fits(
    segments: np.ndarray, region: RoadRegion, prior: LaneLine | None = None, count: int = CANDIDATES
) -> Iterator[tuple[float, float]]:
    """Up to ``count`` distinct boundary lines among one side's segments, preferred first (lazily: the caller stops
    when the first is good enough).

    RANSAC over segment hypotheses; hypotheses with RANSAC_KEEP of the best support compete, ordered by distance to
    the prior — last frame's tracked boundary — else innermost first (the ego lane's boundary is the marking nearest
    the car's path); each is the length-weighted least-squares fit u = a·v + b of its inlier segments. The caller
    picks among them by marking evidence (``ridge_lines``); the prior keeps a curved boundary, which two straight
    lines fit about equally, from flipping."""
    if len(segments) == 0:
        return
    w = region.width_px
    dv = segments[:, 3] - segments[:, 1]
    seg = segments[np.abs(dv) > 1e-9]
    if len(seg) == 0:
        return
    if len(seg) > RANSAC_MAX_SEGMENTS:  # hypotheses and voters: the longest segments (bounds the O(n²) cost)
        seg = seg[np.argsort(-np.hypot(seg[:, 2] - seg[:, 0], seg[:, 3] - seg[:, 1]))[:RANSAC_MAX_SEGMENTS]]
    slope = (seg[:, 2] - seg[:, 0]) / (seg[:, 3] - seg[:, 1])
    icpt = seg[:, 0] - slope * seg[:, 1]
    length = np.hypot(seg[:, 2] - seg[:, 0], seg[:, 3] - seg[:, 1])
    tol = FIT_OUTLIER_PX * w
    # distance of every segment's two end points from every hypothesis line (rows: hypotheses)
    d1 = np.abs(seg[None, :, 0] - (slope[:, None] * seg[None, :, 1] + icpt[:, None]))
    d2 = np.abs(seg[None, :, 2] - (slope[:, None] * seg[None, :, 3] + icpt[:, None]))
    inlier = (d1 <= tol) & (d2 <= tol)
    score = inlier @ length
    off_centre = np.abs(slope * region.bottom_v_px + icpt - 0.5 * w)
    candidates = (score >= RANSAC_KEEP * score.max()) & (off_centre >= MIN_OFF_CENTRE * w)
    if not candidates.any():
        candidates = score >= RANSAC_KEEP * score.max()
    if prior is not None:  # mean distance from the prior at the region's middle and bottom rows
        mid, bottom = 0.5 * (region.top_v_px + region.bottom_v_px), float(region.bottom_v_px)
        order_key = (np.abs(slope * mid + icpt - prior.u_at(mid)) + np.abs(slope * bottom + icpt - prior.u_at(bottom))) / 2
    else:
        order_key = off_centre
    taken = np.zeros(len(seg), bool)
    given = 0
    for best in np.flatnonzero(candidates)[np.argsort(order_key[candidates])].tolist():
        if taken[best]:
            continue  # a hypothesis already explained by a preferred line is the same line
        if given >= count:
            return
        mine = inlier[best]
        taken |= mine
        chosen = seg[mine]
        v = np.concatenate([chosen[:, 1], chosen[:, 3]])
        u = np.concatenate([chosen[:, 0], chosen[:, 2]])
        weight = length[mine]
        given += 1
        yield _weighted_fit(v, u, np.concatenate([weight, weight])) or (float(slope[best]), float(icpt[best]))


def _weighted_fit(v: np.ndarray, u: np.ndarray, w: np.ndarray) -> tuple[float, float] | None:
    """Weighted least squares u = a·v + b (dot products: a few array operations, this runs for every candidate)."""
    sw = w.sum()
    if sw <= 0:
        return None
    mv, mu = (w @ v) / sw, (w @ u) / sw
    dv = v - mv
    wdv = w * dv
    var = wdv @ dv
    if var < 1.0:  # all points on one row: no direction
        return None
    a = (wdv @ (u - mu)) / var
    return float(a), float(mu - a * mv)


def default_lines(region: RoadRegion) -> tuple[LaneLine, LaneLine]:
    """A centred lane meeting just above the top of the road region: the prior when nothing is known."""
    w, top, bottom = region.width_px, region.top_v_px, region.bottom_v_px
    vp_v = top - 0.04 * region.height_px
    lines = []
    for u_bottom in ((0.5 - DEFAULT_HALF_WIDTH) * w, (0.5 + DEFAULT_HALF_WIDTH) * w):
        slope = (u_bottom - 0.5 * w) / max(1.0, bottom - vp_v)
        lines.append(LaneLine(slope, u_bottom - slope * bottom, 0.0, 0))
    return lines[0], lines[1]


def lane_width_rows(rows: np.ndarray, priors: tuple[LaneLine | None, LaneLine | None], region: RoadRegion) -> np.ndarray:
    """The lane width expected on each row (the prior that scales the paint width): the tracked lane when it makes
    one, else the default lane."""
    v = rows.astype(np.float64)
    left, right = priors
    narrowest = MIN_LANE_WIDTH * region.width_px * (v - v[0] + 1) / (v[-1] - v[0] + 1)  # tapering toward the horizon
    if left is None or right is None or not (right.u_at(v) - left.u_at(v) >= narrowest).all():
        left, right = default_lines(region)
    return right.u_at(v) - left.u_at(v)


def ridge_lines(
    maps: RidgeMaps, region: RoadRegion, fits: list[tuple[float, float]], lane_width: np.ndarray, right_sides: list[bool]
) -> list[tuple[tuple[float, float], float, SeenRows | None]]:
    """Each Hough fit refitted on the inner edges of the marking ridges along it, its support (ridges.py) and the rows
    the ridges lie on; all fits scanned in one pass."""
    if not fits:
        return []
    rows = np.arange(region.top_v_px, region.bottom_v_px + 1)
    centres = np.array([a * rows + b for a, b in fits])
    scan = scan_ridges(maps, rows, centres, lane_width, np.array(right_sides, bool), region.marking_share)
    out = []
    for fit, ok, inner, support in zip(fits, scan.ok, scan.inner_u, scan.support, strict=True):
        if ok.sum() >= REFIT_MIN_ROWS:
            refit = _weighted_fit(rows[ok].astype(np.float64), inner[ok], np.ones(int(ok.sum())))
            if refit is not None and abs(refit[0] - fit[0]) < REFIT_MAX_SLOPE_CHANGE:
                fit = refit
        out.append((fit, float(support), SeenRows.of(rows[ok])))
    return out


def _scan_sides(
    maps: RidgeMaps, region: RoadRegion, per_side: list[list[tuple[float, float]]], lane_width: np.ndarray
) -> list[list[tuple[tuple[float, float], float, SeenRows | None]]]:
    """``ridge_lines`` of the left and the right candidates in one pass (the cost is mostly per array operation),
    split back by side."""
    left, right = per_side
    out = ridge_lines(maps, region, left + right, lane_width, [False] * len(left) + [True] * len(right))
    return [out[: len(left)], out[len(left) :]]


def best_pair(
    lefts: list[LaneLine], rights: list[LaneLine], region: RoadRegion
) -> tuple[LaneLine | None, LaneLine | None]:
    """The left/right candidates (preferred first) that make the best lane: mean support × geometry, where a later
    candidate's support counts PREFER_SHARE less (it must be clearly better). A side without candidates contributes
    no support; two lines that make no lane are at best one boundary of it."""
    best: tuple[float, LaneLine | None, LaneLine | None] = (0.0, None, None)
    for i, left in enumerate(lefts or [None]):
        for j, right in enumerate(rights or [None]):
            s_l = left.support * (PREFER_SHARE if i else 1.0) if left is not None else 0.0
            s_r = right.support * (PREFER_SHARE if j else 1.0) if right is not None else 0.0
            geometry = geometry_plausibility(left, right, region) if left is not None and right is not None else 1.0
            score, pair = 0.5 * (s_l + s_r) * geometry, (left, right)
            if left is not None and right is not None and geometry <= 0.0:
                score = 0.5 * max(s_l, s_r) * PREFER_SHARE
                pair = (left, None) if s_l >= s_r else (None, right)
            if score > best[0]:
                best = (score, *pair)
    return best[1], best[2]


def _plainness(paint_share: float, clutter: tuple[float, float]) -> float:
    """1 while marking pixels cover at most clutter[0] of the region, falling linearly to 0 at clutter[1]: in noise
    or a random texture everything is a ridge somewhere, and ridges found there are no evidence of paint."""
    return float(min(1.0, max(0.0, (clutter[1] - paint_share) / (clutter[1] - clutter[0]))))


@lru_cache(maxsize=8)
def _band_region(region: RoadRegion) -> RoadRegion:
    """The region as seen by the road rows alone (row 0 = its top): the same every frame, so built once."""
    height = region.bottom_v_px - region.top_v_px
    return replace(region, top_v_px=0, bottom_v_px=height, height_px=height + 1)


def detect_lanes(
    hls: np.ndarray, region: RoadRegion, mask: np.ndarray | None = None, priors: tuple[LaneLine | None, LaneLine | None] = (None, None)
) -> LaneDetection:
    """Left/right boundaries of the ego lane in a working-size HLS image (cv2.COLOR_BGR2HLS); priors: last tracked ones."""
    mask = region_mask(region) if mask is None else mask
    band = slice(region.top_v_px, region.bottom_v_px + 1)  # everything below runs on the road rows only
    crop = _band_region(region)
    features = np.zeros(mask.shape, np.uint8)
    light = np.zeros(mask.shape, np.uint8)
    light[band] = smoothed_light(hls[band])
    features[band] = marking_features(hls[band], mask[band], crop, light[band])
    maps = ridge_maps((light, hls[:, :, 2]), features, region.top_v_px, region.bottom_v_px)
    segments = hough_segments(features[band])
    segments[:, [1, 3]] += region.top_v_px
    sides = split_by_slope(segments, region.width_px)
    lane_width = lane_width_rows(np.arange(region.top_v_px, region.bottom_v_px + 1), priors, region)
    plain = _plainness(maps.paint_integral[-1, -1] / max(1, cv2.countNonZero(mask)), region.clutter)
    fits = [candidate_fits(side, region, prior) for side, prior in zip(sides, priors, strict=True)]
    # the preferred candidate of each side first, both in one pass: when it is well supported it cannot be beaten
    # clearly, and the others need neither a fit nor a scan; the others of the sides that still need them in a second pass
    scanned = _scan_sides(maps, region, [list(islice(f, 1)) for f in fits], lane_width)
    rest = [list(f) if s and s[0][1] * plain < PREFER_SHARE else [] for s, f in zip(scanned, fits, strict=True)]
    if any(rest):
        more = _scan_sides(maps, region, rest, lane_width)
        scanned = [a + b for a, b in zip(scanned, more, strict=True)]
    found: list[list[LaneLine]] = [[], []]
    for i, results in enumerate(scanned):
        for (a, b), support, seen_rows in results:
            support *= plain
            if support > 0:
                found[i].append(LaneLine(a, b, support, len(sides[i]), seen_rows))
            if support >= PREFER_SHARE and len(found[i]) == 1:
                break  # ... in preference order: a well-supported preferred line cannot be beaten clearly
    left, right = best_pair(found[0], found[1], region)
    return LaneDetection(region, left, right, features, len(segments), maps)
