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
from dataclasses import dataclass, replace

import cv2
import numpy as np

from fearguard.camera import CameraModel

WORK_WIDTH_PX = 320  # [px] frames are analysed at this width (aspect kept): the cost is then fixed
TOP_FRACTION = 0.62  # [-] road region starts at this share of the height without a camera model (dash-cam horizon ≈ 0.58)
BOTTOM_FRACTION = 0.93  # [-] and ends here (many dash-cams see their own bonnet below)
PITCHED_DEG = 8.0  # [deg] a camera pitched down at least this much gets the near-road settings below
SIDE_FRACTION = 0.75  # [-] of the road region's height: with a camera model, the near part searched across the full width
HORIZON_MARGIN = 0.04  # [-] with a camera model the region starts this share of the height below the horizon
TOPHAT_WIDTH = 0.055  # [-] top-hat window as a share of the width: wider than a far marking, narrower than a far lane
NEAR_TOPHAT_WIDTH = 0.2  # [-] the same in the near half of the road region (a dash-cam's near marking: ~10 px)
TOPHAT_WIDTH_PITCHED = 0.12  # [-] far window with a camera model: a low camera pitched down sees wide tape ...
NEAR_TOPHAT_WIDTH_PITCHED = 0.35  # [-] ... and near window (a model car's tape: ~60 px across there)
RIDGE_MIN = 22  # [grey levels] a marking must be this much brighter than the road beside it
YELLOW_HUE = (14, 40)  # [OpenCV hue 0..180] yellow paint
YELLOW_SAT_MIN = 70  # [0..255] saturation of yellow paint
YELLOW_LIGHT_MIN = 70  # [0..255] lightness of yellow paint
SLOPE_MIN = 0.35  # [-] |dv/du| below this a segment is too flat to be a lane boundary
HOUGH_THRESHOLD = 10  # [votes]
HOUGH_MIN_LENGTH = 0.03  # [-] of the width
HOUGH_MAX_GAP = 0.03  # [-] of the width
FIT_OUTLIER_PX = 0.03  # [-] of the width: a segment whose end points are this close to a line supports it
RANSAC_MAX_SEGMENTS = 40  # [-] per side
RANSAC_KEEP = 0.6  # [-] lines with this share of the best support compete; the innermost wins
MIN_OFF_CENTRE = 0.08  # [-] of the width: a boundary this close to the image centre at the bottom is a seam, not a lane edge
SUPPORT_BAND_PX = 2  # [px] a feature pixel within this of the line supports it
SUPPORT_FULL = 0.35  # [-] covering this share of the rows counts as full support (a dashed line covers about this)


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


@dataclass(frozen=True)
class LaneLine:
    """One boundary as u = slope·v + intercept in working pixels, with the evidence behind it."""

    slope: float  # [px/px] du/dv
    intercept_px: float
    support: float  # [0..1] share of the region's rows with marking pixels on the line, saturating at SUPPORT_FULL
    segments: int  # Hough segments that built it

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


def work_size(width_px: int, height_px: int) -> tuple[int, int]:
    """Working size for a frame: WORK_WIDTH_PX wide (never upscaled), aspect kept."""
    if width_px <= WORK_WIDTH_PX:
        return width_px, height_px
    return WORK_WIDTH_PX, max(1, round(height_px * WORK_WIDTH_PX / width_px))


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
    return RoadRegion(width_px, height_px, top_v, bottom_v, polygon, TOPHAT_WIDTH_PITCHED, NEAR_TOPHAT_WIDTH_PITCHED)


def region_mask(region: RoadRegion) -> np.ndarray:
    """uint8 0/255 mask of the region's trapezoid."""
    mask = np.zeros((region.height_px, region.width_px), np.uint8)
    cv2.fillConvexPoly(mask, np.array(region.polygon_px, np.int32), 255)
    return mask


def marking_features(hls: np.ndarray, mask: np.ndarray, region: RoadRegion | None = None) -> np.ndarray:
    """uint8 0/255 pixels that look like lane paint (bright ridges or yellow) inside the mask, from an HLS image.

    Markings widen toward the camera, so the top-hat window is wider in the near half of the road region.
    """
    hue, light, sat = hls[:, :, 0], hls[:, :, 1], hls[:, :, 2]
    light = cv2.GaussianBlur(light, (3, 3), 0)  # the classic smoothing step: sensor noise must not make ridges
    w = hls.shape[1]
    far = region.far_tophat if region is not None else TOPHAT_WIDTH
    ridge_l, ridge_s = _tophat(light, far * w), _tophat(sat, far * w)
    if region is not None:
        near = slice((region.top_v_px + region.bottom_v_px) // 2, region.bottom_v_px + 1)
        ridge_l[near] = _tophat(light[near], region.near_tophat * w)
        ridge_s[near] = _tophat(sat[near], region.near_tophat * w)
    bright = ridge_l >= RIDGE_MIN
    yellow = (hue >= YELLOW_HUE[0]) & (hue <= YELLOW_HUE[1]) & (sat >= YELLOW_SAT_MIN) & (light >= YELLOW_LIGHT_MIN)
    yellow &= ridge_s >= RIDGE_MIN
    features = ((bright | yellow) * np.uint8(255)).astype(np.uint8)
    return cv2.bitwise_and(features, mask)


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
    """The boundary among one side's segments: the best-supported line (RANSAC over segment hypotheses; among
    near-ties the one nearest the prior — last frame's tracked boundary — else the innermost, since the ego lane's
    boundary is the marking nearest the car's path), then a length-weighted least-squares fit u = a·v + b of its
    inlier segments. The prior keeps a curved boundary, which two straight lines fit about equally, from flipping."""
    if len(segments) == 0:
        return None
    w = region.width_px
    dv = segments[:, 3] - segments[:, 1]
    steep = np.abs(dv) > 1e-9
    seg = segments[steep]
    if len(seg) == 0:
        return None
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
    u_bottom = slope * region.bottom_v_px + icpt
    off_centre = np.abs(u_bottom - 0.5 * w)
    candidates = (score >= RANSAC_KEEP * score.max()) & (off_centre >= MIN_OFF_CENTRE * w)
    if not candidates.any():
        candidates = score >= RANSAC_KEEP * score.max()
    if prior is not None:
        rows = np.array([0.5 * (region.top_v_px + region.bottom_v_px), region.bottom_v_px])
        distance = np.abs(slope[:, None] * rows[None, :] + icpt[:, None] - prior.u_at(rows)[None, :]).mean(axis=1)
        best = int(np.flatnonzero(candidates)[np.argmin(distance[candidates])])
    else:
        best = int(np.flatnonzero(candidates)[np.argmin(off_centre[candidates])])
    chosen = seg[inlier[best]]
    v = np.concatenate([chosen[:, 1], chosen[:, 3]])
    u = np.concatenate([chosen[:, 0], chosen[:, 2]])
    wts = np.tile(length[inlier[best]], 2)
    return _weighted_fit(v, u, wts) or (float(slope[best]), float(icpt[best]))


def _weighted_fit(v: np.ndarray, u: np.ndarray, w: np.ndarray) -> tuple[float, float] | None:
    sw = w.sum()
    if sw <= 0:
        return None
    mv, mu = (w * v).sum() / sw, (w * u).sum() / sw
    var = (w * (v - mv) ** 2).sum()
    if var < 1.0:  # all points on one row: no direction
        return None
    a = (w * (v - mv) * (u - mu)).sum() / var
    return float(a), float(mu - a * mv)


def line_support(features: np.ndarray, region: RoadRegion, slope: float, intercept_px: float) -> float:
    """Share of region rows with a marking pixel within SUPPORT_BAND_PX of the line, scaled so a dashed line is 1."""
    rows = np.arange(region.top_v_px, region.bottom_v_px + 1)
    cols = np.rint(slope * rows + intercept_px).astype(np.int64)
    inside = (cols >= 0) & (cols < region.width_px)
    if not inside.any():
        return 0.0
    band = cv2.dilate(features, np.ones((1, 2 * SUPPORT_BAND_PX + 1), np.uint8)) if SUPPORT_BAND_PX else features
    hits = band[rows[inside], cols[inside]] > 0
    covered = hits.sum() / len(rows)
    return float(min(1.0, covered / SUPPORT_FULL))


def detect_lanes(
    hls: np.ndarray, region: RoadRegion, mask: np.ndarray | None = None, priors: tuple[LaneLine | None, LaneLine | None] = (None, None)
) -> LaneDetection:
    """Left/right boundaries of the ego lane in a working-size HLS image (cv2.COLOR_BGR2HLS); priors: last tracked ones."""
    mask = region_mask(region) if mask is None else mask
    band = slice(region.top_v_px, region.bottom_v_px + 1)  # everything below runs on the road rows only
    crop = replace(region, top_v_px=0, bottom_v_px=region.bottom_v_px - region.top_v_px, height_px=region.bottom_v_px - region.top_v_px + 1)
    features = np.zeros(mask.shape, np.uint8)
    features[band] = marking_features(hls[band], mask[band], crop)
    segments = hough_segments(features[band])
    segments[:, [1, 3]] += region.top_v_px
    left_s, right_s = split_by_slope(segments, region.width_px)
    lines: list[LaneLine | None] = []
    for side, prior in zip((left_s, right_s), priors, strict=True):
        fit = fit_line(side, region, prior)
        if fit is None:
            lines.append(None)
            continue
        support = line_support(features, region, *fit)
        lines.append(LaneLine(fit[0], fit[1], support, len(side)) if support > 0 else None)
    return LaneDetection(region, lines[0], lines[1], features, len(segments))
