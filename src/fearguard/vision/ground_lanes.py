"""A lane model that bends: both boundaries fitted in the ground plane, sides decided by colour.

With a camera model (mount height and pitch) every marking pixel of the near road projects to a ground point
(x forward, y left, metres, from the camera's foot). There a boundary is a circular arc or a straight line — the
shapes roads and Duckietown tiles are built from — however the image shows it: a tight curve, tape that crosses
the picture or leaves it sideways. A Duckietown-style road says which side is which by colour — the yellow centre
line on the left of the ego lane, the white edge on its right — so the sides are not guessed from the image slope
(which flips on a curve):

    marking pixels (row and column ridges) → ground points → yellow: left; white right of it: right
      → robust circle-or-line fit per side (RANSAC over 3-point hypotheses, then a least-squares refit on the inliers)
      → support (share of the near range covered), width of the lane, agreement with last frame's fit
      → the lane centre (each boundary offset by half a lane) → the pure-pursuit point ``aim_m`` from the camera

A boundary is a·(x²+y²) + b·x + c·y + d = 0 normalised to b² + c² − 4·a·d = 1 (Pratt), which makes one formula the
signed Euclidean distance for circles and lines alike (a = 0 is a line; curvature is 2|a|). Written by hand: it is
a few array operations over the projected points, and no library fits circles robustly to colour-labelled sets.
"""

from __future__ import annotations

import math
from collections import deque
from dataclasses import dataclass, replace
from functools import lru_cache
from typing import NamedTuple

import cv2
import numpy as np

from fearguard.camera import CameraModel
from fearguard.vision.lane_tracker import LOST_AFTER_S, SUPPORT_HOLD_S
from fearguard.vision.lanes import RIDGE_MIN, YELLOW_SAT_MIN, LaneLine, RoadRegion, smoothed_light
from fearguard.vision.medians import median
from fearguard.vision.obstacle import INSET
from fearguard.vision.occlusion import ROW_STEP
from fearguard.vision.paint_light import balanced_hls, blue_chroma, is_neutral, measure_light

HYPOTHESES = 48  # [-] RANSAC hypotheses per side (deterministic: a fixed-seed generator)
INLIER_M = 0.02  # [m] a point this close to a boundary curve lies on it (tape is 2-5 cm wide)
MIN_POINTS = 12  # [-] fewer marking points than this on a side: no boundary there
BIN_M = 0.02  # [m] the near range (distance from the camera) is cut into bins of this length; support is the share
SUPPORT_FULL = 0.35  # [-] of bins with inliers, saturating here (a dashed centre line covers about half its length)
MAX_POINTS = 1500  # [-] points per side kept for the fit (an even subsample beyond: the cost stays bounded)
GATE_M = 0.06  # [m] with last frame's fit as a prior, points farther than this from it are not this side's
WIDTH_TOLERANCE = (0.3, 0.6)  # [-] relative lane-width error: full plausibility up to the first, none from the second
AGREEMENT_M = 0.35  # [-] of the lane width: mean disagreement with the prior at which agreement reaches 0
WHITE_SAT_MAX = 60  # [0..255] white paint is unsaturated (Duckietown's mat: 5-26, its grass: 77-207)
YELLOW_HUE = (14, 34)  # [OpenCV hue 0..180] yellow paint (Duckietown's: 26-29); grass (38-48) is not yellow here
YELLOW_LIGHT_MIN = 60  # [0..255] (saturation: lanes.YELLOW_SAT_MIN; contrast: lanes.RIDGE_MIN)
RIDGE_RATIO = 0.6  # [-] paint is brighter than the road by this share of its lightness (tape on a mat: 2-3; the mat's own
#   pattern: < 0.6; lanes.RIDGE_RATIO, 0.15, is for paint on asphalt in any light)
RIDGE_WINDOW = (0.12, 0.35)  # [-] of the width: far and near top-hat windows, in rows and in columns
MAX_CURVATURE = 8.0  # [1/m] a boundary bending tighter (radius < 12.5 cm) is no road edge a car can follow
MAX_START_ANGLE_DEG = 60.0  # [deg] where a boundary starts (its marking nearest ahead) it runs within this of the car's
#   heading: on a 0.4 m curve the visible edges start within ~40° of it, a line across the lane (a tile seam, a stop line) at ~90°
STRAIGHT = 1e-6  # [1/m] |a| below this (radius beyond 500 km) is a straight line
REFIT_KEEP = 0.9  # [-] share of the hypothesis' (weighted) inliers the least-squares refit must keep to replace it
NEAR_WEIGHT_FAR = 0.1  # [-] an inlier at the far end of the fit range counts this much of a near one (full weight up to aim_m):
#   the lane the car is in is nearest; far markings may belong to the road after the curve or beyond it
EXTEND_M = 0.3  # [m] the model is followed this far beyond the last marking seen (the aim point may lie there)
EXPECT_BEYOND_M = 0.1  # [m] occlusion expects a boundary this far beyond the last marking seen on it
STEP_M = 0.01  # [m] spacing of the points sampled along a boundary
CHOSEN_AT_HEIGHT_M = 0.108  # [m] the camera height at which the metric sizes above and the spec's defaults were chosen (a
#   Duckiebot's): a camera mounted h high sees a world scaled by h / CHOSEN_AT_HEIGHT_M the same, so a spec for it scales them
LANE_WIDTHS_PER_HEIGHT = 3.0  # [-] a lane is about this many camera heights wide, until one is measured: a road 3.5 m under
#   a 1.3 m dash-cam 2.7; a 1:10 car's taped track 0.45 m under 0.15 m 3; Duckietown 0.236 m under 0.108 m 2.2
WIDTH_FRAMES = 40  # [frames] a measured lane width is the median of the last this many frames that found both boundaries
WIDTH_MIN_FRAMES = 5  # [frames] ... once there are this many
YELLOW_TRACK_FRAMES = 5  # [frames] a yellow left boundary found in this many frames makes the track one with a yellow centre
#   line (a yellow object read as one in a frame or two does not)
COAST_SUPPORT_MIN = 0.5  # [-] a side whose held support is less is not coasted through a miss (``coast``)
FLANK_M = (0.07, 0.1)  # [m] beyond a boundary (its tape's inner edge), away from the lane: past any tape (Duckietown's 5 cm
#   wide, the widest), road again (at the spec's scale)
FLANK_FILLED = 0.5  # [-] share of the flank's samples that are paint at every offset: the edge of a wide bright patch
FLANK_MIN_SAMPLES = 5  # [-] fewer flank samples in view than this tell nothing
RESOLVED_SPAN = 0.5  # [-] of the fit range: a boundary seen over less whose arc stays within the inlier band of its chord
#   is a line (``_resolved``)
JUMP_AGREEMENT = 0.5  # [-] a side found with less agreement with its prior than this is another line: its hold starts afresh
WIDTH_RANGE = (0.5, 2.0)  # [-] of the assumed width: a two-sided fit measuring a width outside is no measurement of this lane


@dataclass(frozen=True)
class GroundLaneSpec:
    """What the ground model must know of the road: its lane and paint in metres, and where to fit.

    ``for_camera`` gives the spec of a camera that knows only its mount (height and pitch): every length scaled by its
    height, the lane width assumed (``LANE_WIDTHS_PER_HEIGHT``) until the picture measures it (``GroundMemory.spec_now``),
    and which paint bounds which side read from the picture (``yellow_centre`` None)."""

    lane_width_m: float  # between the inner edges of the two boundary markings (assumed, when ``width_measured``)
    near_m: float = 0.07  # fit range, from the camera's foot: the nearest ground the camera sees ...
    far_m: float = 0.5  # ... and the farthest where the projection is still precise
    aim_m: float = 0.25  # distance from the camera of the steering's pure-pursuit point on the lane centre
    max_bearing_deg: float = 75.0  # the aim's bearing is held within this: a lane centre further round at aim_m is no lane
    scale: float = 1.0  # [-] the model's own metric sizes (tape width, bins, gates, curvature) × this
    width_measured: bool = False  # the lane width is measured from the picture (lane_width_m: the assumption before that)
    yellow_centre: bool | None = True  # the left boundary is a yellow centre line (Duckietown's, a US road's); None: the
    #   picture says (a yellow boundary found in YELLOW_TRACK_FRAMES frames); until then white bounds either side

    @classmethod
    def for_camera(cls, camera: CameraModel) -> GroundLaneSpec:
        """The spec of a mounted camera (``mount_height_m`` set) without a lane spec: the defaults scaled by its height."""
        h = float(camera.mount_height_m or CHOSEN_AT_HEIGHT_M)
        s = h / CHOSEN_AT_HEIGHT_M
        base = cls(lane_width_m=LANE_WIDTHS_PER_HEIGHT * h)
        return replace(base, near_m=base.near_m * s, far_m=base.far_m * s, aim_m=base.aim_m * s, scale=s,
                       width_measured=True, yellow_centre=None)

    def metres(self, m: float) -> float:
        """A metric size of the model (chosen at CHOSEN_AT_HEIGHT_M) for this spec's scale."""
        return m * self.scale


@dataclass(frozen=True)
class GroundBoundary:
    """One boundary: a·(x²+y²) + b·x + c·y + d = 0 (metres; b² + c² − 4ad = 1), oriented so that the signed distance is
    positive to the left of the direction away from the camera; with the nearest and farthest marking seen on it."""

    a: float
    b: float
    c: float
    d: float
    start: tuple[float, float]  # the inlier nearest ahead (smallest x)
    end: tuple[float, float]  # the inlier farthest along the boundary from it
    support: float  # [0..1] share of the near range's bins with inliers, saturating at SUPPORT_FULL
    inliers: int

    def distance(self, x: np.ndarray, y: np.ndarray) -> np.ndarray:
        """Signed Euclidean distance of the points from the boundary (+ = left of it)."""
        return _distance(np.array([self.a, self.b, self.c, self.d]), x, y)

    @property
    def curvature_per_m(self) -> float:
        """1 / radius (0 for a line)."""
        return 2.0 * abs(self.a)

    def offset(self, delta_m: float) -> GroundBoundary | None:
        """The parallel curve delta_m to the left (negative: right); None if it would pass through the circle's centre."""
        k = 1.0 + 2.0 * self.a * delta_m
        if k <= 1e-6:
            return None
        a, b, c = self.a / k, self.b / k, self.c / k
        d = (b * b + c * c - 1.0) / (4.0 * a) if abs(a) > STRAIGHT else self.d - delta_m
        moved = [tuple(np.asarray(p) + delta_m * self._normal(*p)) for p in (self.start, self.end)]
        start, end = (float(moved[0][0]), float(moved[0][1])), (float(moved[1][0]), float(moved[1][1]))
        return replace(self, a=a, b=b, c=c, d=d, start=start, end=end)

    def samples(self, extend_m: float = 0.0) -> np.ndarray:
        """Points (n, 2) along the boundary from its start, past its end by extend_m, STEP_M apart."""
        p0 = self._foot(self.start)
        p1 = self._foot(self.end)
        if abs(self.a) <= STRAIGHT:
            t = p1 - p0
            length = float(np.hypot(*t))
            t = t / length if length > 1e-9 else np.array([1.0, 0.0])
            s = np.arange(0.0, length + extend_m + STEP_M, STEP_M)
            return p0[None, :] + s[:, None] * t[None, :]
        centre = np.array([-self.b, -self.c]) / (2.0 * self.a)
        radius = 1.0 / (2.0 * abs(self.a))
        t0 = math.atan2(*(p0 - centre)[::-1])
        sweep = (math.atan2(*(p1 - centre)[::-1]) - t0 + math.pi) % (2 * math.pi) - math.pi
        direction = 1.0 if sweep >= 0 else -1.0
        span = abs(sweep) + extend_m / radius
        theta = t0 + direction * np.arange(0.0, span + STEP_M / radius, STEP_M / radius)
        return centre[None, :] + radius * np.stack([np.cos(theta), np.sin(theta)], axis=1)

    def _normal(self, x: float, y: float) -> np.ndarray:
        return self.normals(np.array([x], dtype=np.float64), np.array([y], dtype=np.float64))[0]

    def normals(self, x: np.ndarray, y: np.ndarray) -> np.ndarray:
        """(n, 2) unit normals at the points, toward + (left of the way away from the camera): the gradient of
        a·(x²+y²) + b·x + c·y + d."""
        g = np.stack([2.0 * self.a * x + self.b, 2.0 * self.a * y + self.c], axis=1)
        return g / np.maximum(np.hypot(g[:, 0], g[:, 1]), 1e-12)[:, None]

    def _foot(self, p: tuple[float, float]) -> np.ndarray:
        """The point of the curve nearest p."""
        q = np.asarray(p, dtype=np.float64)
        return q - float(self.distance(q[0:1], q[1:2])[0]) * self._normal(*q)


@dataclass(frozen=True)
class GroundLanes:
    """Both boundaries in the ground plane (None where not found) and how plausible they are as one lane."""

    left: GroundBoundary | None
    right: GroundBoundary | None
    geometry: float  # [0..1] lane width against the spec (1 with one boundary)
    points: int  # marking points projected
    light_gains: tuple[float, float, float] | None = None  # (B, G, R) gains the paint's colour was judged under (paint_light)
    light_split: float | None = None  # the split between the paints in b that went with them (paint_light.Light.white_b_min)
    width_m: float = math.nan  # [m] the lane width both boundaries measure (NaN: not both found)
    yellow_left: bool = False  # the left boundary is yellow paint (as a prior: the track has a yellow centre line)
    held: tuple[float, float] = (0.0, 0.0)  # [0..1] each side's best support over the last SUPPORT_HOLD_S (as priors: what
    #   GroundMemory holds; in a fit: with this frame's, faded on a coasted side — ``coast``)
    coasted: tuple[bool, bool] = (False, False)  # a side not found this frame, held from its last sighting (``coast``)
    unseen_s: tuple[float, float] = (math.inf, math.inf)  # [s] (as priors) since each side was last found
    agreement: tuple[float, float] = (1.0, 1.0)  # [0..1] (in a fit) each side found against its prior (``agreement``): below
    #   JUMP_AGREEMENT another line than the one held, whose hold starts afresh


@dataclass(frozen=True)
class GroundGrid:
    """Per working-image row: its ground range and metres of lateral offset per pixel (None rows: beyond the range)."""

    top_v_px: int
    x_m: np.ndarray  # (rows,) forward distance of each row from top_v_px on
    lateral_m_per_px: np.ndarray  # (rows,)
    cx_px: float

    def plane(self, width_px: int) -> tuple[np.ndarray, np.ndarray]:
        """Every pixel's lateral offset y (m, + = left) and squared ground distance x² + y², (rows, width): the same for
        every frame of the camera, so computed once per width (``lane_interior`` tests every pixel against the lane)."""
        cache = self.__dict__.setdefault("_planes", {})  # the dataclass is frozen; this is a cache, not state
        if width_px not in cache:
            y = -(np.arange(width_px)[None, :] - self.cx_px) * self.lateral_m_per_px[:, None]
            x = self.x_m[:, None]
            cache[width_px] = (y, x * x + y * y)
        return cache[width_px]


@lru_cache(maxsize=8)
def ground_grid(camera: CameraModel, top_v_px: int, bottom_v_px: int, far_m: float) -> GroundGrid | None:
    """The rows of a working-size camera whose ground lies within far_m (None: the camera cannot see the ground)."""
    if camera.mount_height_m is None:
        return None
    p = math.radians(camera.pitch_deg)
    rows, xs, lat = [], [], []
    for v in range(top_v_px, bottom_v_px + 1):
        x = camera.ground_range_m(v)
        if x is None or x > far_m:
            continue
        rows.append(v)
        xs.append(x)
        lat.append((x * math.cos(p) + camera.mount_height_m * math.sin(p)) / camera.fx_px)
    if not rows:
        return None
    first = rows[0]
    return GroundGrid(first, np.array(xs), np.array(lat), camera.cx_px)


class PaintMasks(NamedTuple):
    """The paint of the road rows and the light it was judged under."""

    white: np.ndarray  # uint8 0/255
    yellow: np.ndarray  # uint8 0/255
    gains: np.ndarray | None  # (B, G, R) gains of the light (paint_light): None without the BGR image, ones for white light
    hls_white: np.ndarray | None  # the HLS image with its road rows as under white light, when the light was tinted
    split: float | None = None  # the split between the paints in b the white tape was judged by (None: the plain test)


def marking_masks(
    hls: np.ndarray, light: np.ndarray, mask: np.ndarray, top_v_px: int, bottom_v_px: int,
    bgr: np.ndarray | None = None, held_gains: np.ndarray | None = None, held_split: float | None = None,
) -> PaintMasks:
    """Paint masks of the road rows and the light they were judged under. White: brighter than its surroundings
    along the row *or* the column (tape crossing the picture on a curve is thin only vertically) and unsaturated;
    yellow: by colour. With the working-size ``bgr``, colour is judged under the light measured off the paint
    (``paint_light``), or ``held_gains`` and ``held_split`` (a previous frame's) when this frame cannot tell."""
    white = np.zeros(mask.shape, np.uint8)
    yellow = np.zeros(mask.shape, np.uint8)
    w = mask.shape[1]
    band = slice(top_v_px, bottom_v_px + 1)
    split = (top_v_px + bottom_v_px) // 2
    ridged = np.zeros((bottom_v_px + 1 - top_v_px, w), bool)  # road rows brighter than their surroundings, as paint is
    for lo, hi, share in ((top_v_px, split, RIDGE_WINDOW[0]), (split, bottom_v_px + 1, RIDGE_WINDOW[1])):
        if hi <= lo:
            continue
        rows = light[lo:hi]
        k = max(3, int(share * w) | 1)
        ridge = np.maximum(cv2.morphologyEx(rows, cv2.MORPH_TOPHAT, cv2.getStructuringElement(cv2.MORPH_RECT, (k, 1))),
                           cv2.morphologyEx(rows, cv2.MORPH_TOPHAT, cv2.getStructuringElement(cv2.MORPH_RECT, (1, k))))
        ridged[lo - top_v_px : hi - top_v_px] = (ridge >= RIDGE_MIN) & (ridge >= RIDGE_RATIO * (rows.astype(np.int16) - ridge))
    light_band = light[band]
    white_b, yellow_b = _paint_colours(hls[band], light_band)
    gains, hls_white, split_b = None, None, None
    if bgr is not None:  # judged under the light measured off the paint (this frame's, or the one held from before)
        on_road = mask[band] > 0
        measured = measure_light(bgr[band], ridged & on_road, on_road, white_b, _looks_yellow)
        if measured is not None:
            gains, split_b = measured.gains, measured.white_b_min
        elif held_gains is not None:
            gains, split_b = held_gains, held_split
        else:
            gains = np.ones(3)
        if not is_neutral(gains):
            hls_white = hls.copy()
            hls_white[band] = balanced_hls(bgr[band], gains)
            white_b, yellow_b = _paint_colours(hls_white[band], light_band)
            if split_b is not None:
                # white as the light was measured: a ridge on the white tape's side of the split between the paints
                # (the next tile's tape, under that tile's own tint, stays too saturated for the plain test)
                tape_side = ridged & ~yellow_b  # only ridges can be tape: the chroma of those alone
                white_b[tape_side] |= blue_chroma(bgr[band][tape_side]) > split_b
        else:
            split_b = None
    white[band] = (ridged & white_b) * np.uint8(255)
    yellow[band] = yellow_b * np.uint8(255)
    # an opening removes specks (grass blades, the mat's grain) that no tape is as thin as
    speck = cv2.getStructuringElement(cv2.MORPH_RECT, (3, 3))
    return PaintMasks(cv2.bitwise_and(cv2.morphologyEx(white, cv2.MORPH_OPEN, speck), mask),
                      cv2.bitwise_and(cv2.morphologyEx(yellow, cv2.MORPH_OPEN, speck), mask), gains, hls_white, split_b)


STANDING_DEPTH_M = 0.15  # [m] a yellow blob whose rows span more ground than this (read as flat) ...
STANDING_WIDTH_M = 0.04  # [m] ... and whose rows are this wide (median, read as flat) stands up: a toy duck 5 cm tall
#   and 5 cm wide 0.3 m ahead spans 0.2 m of the fit range, its rows 5-9 cm wide; a centre-line dash spans its length
#   (5 cm), a solid line 2.5 cm tape (wider only where it runs across the rows, over a short span)


def flat_paint(yellow: np.ndarray, grid: GroundGrid, bottom_v_px: int, scale: float = 1.0) -> np.ndarray:
    """The yellow mask without blobs that stand up. Paint is flat: read as flat ground, a marking's rows span its own
    length and its tape width. A yellow object standing in the lane (a toy duck) keeps its width in pixels while its
    upper rows, read as flat, lie far beyond its foot, where a pixel is more ground: it spans much ground and is wide.
    It is no centre line (it would become the left boundary, and the lane interior would pass it by): it is left to
    the object search. Only the fit range's rows are judged. ``scale``: ``GroundLaneSpec.scale`` (the sizes × this)."""
    band = yellow[grid.top_v_px : bottom_v_px + 1]
    n, labels, stats, _ = cv2.connectedComponentsWithStats(band, connectivity=8)
    out = yellow
    for i in range(1, n):
        left, top, width, height = (int(v) for v in stats[i, :4])
        foot = top + height - 1  # band row of its lowest pixel
        if float(grid.x_m[top] - grid.x_m[foot]) <= STANDING_DEPTH_M * scale:
            continue
        mine = labels[top : foot + 1, left : left + width] == i
        widths = mine.sum(axis=1) * grid.lateral_m_per_px[top : foot + 1]
        if float(median(widths)) >= STANDING_WIDTH_M * scale:
            if out is yellow:
                out = yellow.copy()
            out[grid.top_v_px + top : grid.top_v_px + foot + 1, left : left + width][mine] = 0
    return out


def _paint_colours(hls: np.ndarray, light: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """(white-coloured, yellow) bool masks by colour alone: unsaturated; yellow hue, saturated and not dark."""
    hue, sat = hls[..., 0], hls[..., 2]
    return sat <= WHITE_SAT_MAX, (hue >= YELLOW_HUE[0]) & (hue <= YELLOW_HUE[1]) & (sat >= YELLOW_SAT_MIN) & (light >= YELLOW_LIGHT_MIN)


def _looks_yellow(hls: np.ndarray) -> np.ndarray:
    """bool: yellow paint by colour alone (its lightness read off the HLS image itself)."""
    return _paint_colours(hls, hls[..., 1])[1]


def inner_edges(paint: np.ndarray, lane_is_right: bool) -> np.ndarray:
    """bool: the paint pixels on the edge that faces the ego lane — the lane lies right of a left boundary (or left of
    a right one) and, for a marking crossing the picture ahead, below it. Fitting that edge, not the whole tape, keeps
    the lane width right at any offset and the curve thin. Beyond the image counts as paint (no edge there)."""
    p = paint > 0
    side = np.ones_like(p)
    if lane_is_right:
        side[:, :-1] = p[:, 1:]
    else:
        side[:, 1:] = p[:, :-1]
    below = np.ones_like(p)
    below[:-1] = p[1:]
    return p & ~(side & below)


def ground_points(white: np.ndarray, yellow: np.ndarray, grid: GroundGrid, bottom_v_px: int) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """(x, y, is_yellow) of the inner-edge pixels of the markings in the grid's rows: the yellow line's (a left
    boundary) and the white paint's (a right one)."""
    yx, yy = edge_points(yellow, grid, bottom_v_px, lane_is_right=True)
    wx, wy = edge_points(white, grid, bottom_v_px, lane_is_right=False)
    return np.concatenate([yx, wx]), np.concatenate([yy, wy]), np.arange(len(yx) + len(wx)) < len(yx)


def edge_points(paint: np.ndarray, grid: GroundGrid, bottom_v_px: int, *, lane_is_right: bool) -> tuple[np.ndarray, np.ndarray]:
    """(x, y) of the paint's edge pixels facing a lane on its right (a left boundary's) or on its left, in the grid's rows."""
    r, c = np.nonzero(inner_edges(paint[grid.top_v_px : bottom_v_px + 1], lane_is_right=lane_is_right))
    return grid.x_m[r], -(c - grid.cx_px) * grid.lateral_m_per_px[r]


def _distance(v: np.ndarray, x: np.ndarray, y: np.ndarray) -> np.ndarray:
    """Signed distances of points (x, y) from normalised curves v (4,) or (H, 4) → (N,) or (H, N)."""
    curves = np.atleast_2d(v)
    a, b, c, d = (curves[:, i : i + 1] for i in range(4))
    p = a * (x * x + y * y)[None, :] + b * x[None, :] + c * y[None, :] + d
    dist = 2.0 * p / (1.0 + np.sqrt(np.maximum(1.0 + 4.0 * a * p, 0.0)))
    return dist[0] if v.ndim == 1 else dist


def _normalised(v: np.ndarray) -> np.ndarray:
    """Curves (H, 4) scaled to b² + c² − 4ad = 1 (rows that are no real curve become NaN)."""
    s = v[:, 1] ** 2 + v[:, 2] ** 2 - 4.0 * v[:, 0] * v[:, 3]
    with np.errstate(invalid="ignore", divide="ignore"):
        return v / np.sqrt(np.where(s > 1e-18, s, np.nan))[:, None]


_PRATT_INV = np.linalg.inv(np.array([[0.0, 0, 0, -2], [0, 1, 0, 0], [0, 0, 1, 0], [-2, 0, 0, 0]]))  # Pratt's constraint b²+c²−4ad


def _refit(x: np.ndarray, y: np.ndarray) -> np.ndarray | None:
    """Least-squares circle or line through the points: Pratt's fit (the algebraic residual under b² + c² − 4ad = 1,
    nearly unbiased on short arcs where the plain algebraic fit bends lines), on the centred and scaled points."""
    mx, my = float(x.mean()), float(y.mean())
    scale = float(np.sqrt(np.mean((x - mx) ** 2 + (y - my) ** 2))) or 1.0
    qx, qy = (x - mx) / scale, (y - my) / scale
    m = np.stack([qx * qx + qy * qy, qx, qy, np.ones_like(qx)], axis=1)
    values, vectors = np.linalg.eig(_PRATT_INV @ (m.T @ m))
    values, vectors = values.real, vectors.real
    usable = np.flatnonzero(values >= -1e-9)
    if len(usable) == 0:
        return None
    a_, b_, c_, d_ = vectors[:, usable[np.argmin(values[usable])]]
    a = a_ / scale**2
    b = -2.0 * a * mx + b_ / scale
    c = -2.0 * a * my + c_ / scale
    d = a * (mx * mx + my * my) - (b_ * mx + c_ * my) / scale + d_
    v = _normalised(np.array([[a, b, c, d]]))[0]
    return None if not np.isfinite(v).all() else v


def fit_boundary(x: np.ndarray, y: np.ndarray, spec: GroundLaneSpec, prior: GroundBoundary | None, seed: int = 0) -> GroundBoundary | None:
    """The boundary best supported by the points (x, y): RANSAC over the circles (or lines) through 3 points, one from
    each third of the points by distance from the camera, refitted on the inliers. Only curves that run along the car
    where they start count (MAX_START_ANGLE_DEG): a tile seam or a stop line across the lane is no boundary, however
    many points it has. A prior (last frame's boundary) gates the points first."""
    if prior is not None:
        near = np.abs(prior.distance(x, y)) <= spec.metres(GATE_M)
        x, y = x[near], y[near]
    if len(x) < MIN_POINTS:
        return None
    if len(x) > MAX_POINTS:
        keep = np.linspace(0, len(x) - 1, MAX_POINTS).astype(np.int64)
        x, y = x[keep], y[keep]
    r = np.hypot(x, y)
    thirds = np.array_split(np.argsort(r, kind="stable"), 3)
    rng = np.random.default_rng(seed)
    picks = np.stack([t[rng.integers(0, len(t), HYPOTHESES)] for t in thirds], axis=1)  # (H, 3)
    px, py = x[picks], y[picks]
    m = np.stack([px * px + py * py, px, py, np.ones_like(px)], axis=2)  # (H, 3, 4): each hypothesis its null vector
    curves = _normalised(np.linalg.svd(m)[2][:, -1, :])
    first = np.argmin(px, axis=1)[:, None]  # each hypothesis' point nearest ahead
    inlier_m, max_curvature = spec.metres(INLIER_M), MAX_CURVATURE / spec.scale
    usable = np.isfinite(curves).all(axis=1) & (2.0 * np.abs(curves[:, 0]) <= max_curvature)
    usable &= _runs_along(curves, np.take_along_axis(px, first, 1)[:, 0], np.take_along_axis(py, first, 1)[:, 0])
    curves = curves[usable]
    if len(curves) == 0:
        return None
    weight = np.clip((spec.far_m - r) / (spec.far_m - spec.aim_m), NEAR_WEIGHT_FAR, 1.0)  # near markings count more
    counts = (np.abs(_distance(curves, x, y)) <= inlier_m) @ weight
    best = curves[int(np.argmax(counts))]
    inlier = np.abs(_distance(best, x, y)) <= inlier_m
    if inlier.sum() < MIN_POINTS:
        return None
    # the least-squares refit on the inliers is the boundary (a 3-point hypothesis carries the noise of its points),
    # unless it loses the consensus the hypothesis found
    refit = _refit(x[inlier], y[inlier])
    if refit is not None and 2.0 * abs(refit[0]) <= max_curvature:
        refit = _resolved(refit, x[inlier], y[inlier], inlier_m, spec)
        refined = np.abs(_distance(refit, x, y)) <= inlier_m
        if refined @ weight >= REFIT_KEEP * (inlier @ weight) and _starts_along(refit, x[refined], y[refined]):
            return _oriented(refit, x[refined], y[refined], spec)
    best = _resolved(best, x[inlier], y[inlier], inlier_m, spec)
    if not _starts_along(best, x[inlier], y[inlier]):
        return None  # its inliers start elsewhere than its three points: the curve runs across the lane there
    return _oriented(best, x[inlier], y[inlier], spec)


def _resolved(v: np.ndarray, x: np.ndarray, y: np.ndarray, inlier_m: float, spec: GroundLaneSpec) -> np.ndarray:
    """The curve (4,), or the straight line through its points (x, y) when they cannot tell it from one: seen over less
    than RESOLVED_SPAN of the fit range, with the arc straying from its chord over that span (the sagitta, span² ·
    curvature / 8) by less than the inlier band — the curvature is then the tape's width and the noise, not the
    road's. One short dash (its near end's pixels an edge too) fitted as a circle of radius 0.19-0.24 m beside a
    straight solid line in the simulator, and the lane followed beyond the dash crossed the road; a curve's inner
    tape, seen over 0.23 m of a Duckiebot's 0.43 m with the same small sagitta, is a curve (its span says so)."""
    if abs(v[0]) <= STRAIGHT or len(x) < 2:
        return v
    i0 = int(np.argmin(x))
    span = float(np.max(np.hypot(x - x[i0], y - y[i0])))
    if span >= RESOLVED_SPAN * (spec.far_m - spec.near_m) or span * span * 2.0 * abs(v[0]) / 8.0 >= inlier_m:
        return v
    mx, my = float(x.mean()), float(y.mean())
    _, _, vt = np.linalg.svd(np.stack([x - mx, y - my], axis=1), full_matrices=False)
    nx, ny = vt[-1]  # the unit normal of the total-least-squares line (b² + c² = 1, a = 0: Pratt-normalised)
    return np.array([0.0, nx, ny, -(nx * mx + ny * my)])


def _runs_along(curves: np.ndarray, x: np.ndarray, y: np.ndarray) -> np.ndarray:
    """Whether each curve (H, 4) runs within MAX_START_ANGLE_DEG of the car's heading (+x) at its point (x[i], y[i]):
    the curve's normal there, the gradient of a·(x²+y²) + b·x + c·y + d, is then mostly lateral."""
    gx = 2.0 * curves[:, 0] * x + curves[:, 1]
    gy = 2.0 * curves[:, 0] * y + curves[:, 2]
    return np.abs(gy) >= math.cos(math.radians(MAX_START_ANGLE_DEG)) * np.hypot(gx, gy)


def _starts_along(curve: np.ndarray, x: np.ndarray, y: np.ndarray) -> bool:
    """Whether the curve (4,) runs along the car where its points (x, y) start: at the one nearest ahead."""
    i = int(np.argmin(x))
    return bool(_runs_along(curve[None, :], x[i : i + 1], y[i : i + 1])[0])


def _oriented(v: np.ndarray, x: np.ndarray, y: np.ndarray, spec: GroundLaneSpec) -> GroundBoundary:
    """The boundary with its ends, its support, and its sign chosen so that + is left of the way away from the camera."""
    r = np.hypot(x, y)
    i0 = int(np.argmin(x))  # the nearest ahead: a boundary runs away from the car (its nearest point by distance may
    i1 = int(np.argmax(np.hypot(x - x[i0], y - y[i0])))  # lie mid-arc, where a curve passes beside the camera)
    start, end = (float(x[i0]), float(y[i0])), (float(x[i1]), float(y[i1]))
    travel = np.array([end[0] - start[0], end[1] - start[1]])
    left = np.array([-travel[1], travel[0]])
    mid = (0.5 * (start[0] + end[0]), 0.5 * (start[1] + end[1]))
    gradient = np.array([2 * v[0] * mid[0] + v[1], 2 * v[0] * mid[1] + v[2]])
    if float(gradient @ left) < 0:
        v = -v
    bin_m = spec.metres(BIN_M)
    bins = max(1, math.ceil((spec.far_m - spec.near_m) / bin_m))
    covered = np.unique(np.clip(((r - spec.near_m) / bin_m).astype(np.int64), 0, bins - 1))
    support = min(1.0, len(covered) / bins / SUPPORT_FULL)
    return GroundBoundary(float(v[0]), float(v[1]), float(v[2]), float(v[3]), start, end, support, len(x))


def detect_ground_lanes(
    white: np.ndarray, yellow: np.ndarray, grid: GroundGrid, bottom_v_px: int, spec: GroundLaneSpec,
    priors: tuple[GroundBoundary | None, GroundBoundary | None] = (None, None), yellow_centre: bool = True,
) -> GroundLanes:
    """Left (yellow) and right (white, right of the yellow line, or near the prior) boundaries of the ego lane. Without a
    yellow boundary on a track not known to have a yellow centre line (``yellow_centre`` False), white paint bounds
    whichever side it lies on (``_white_sides``)."""
    x, y, is_yellow = ground_points(white, yellow, grid, bottom_v_px)
    left = _beside(fit_boundary(x[is_yellow], y[is_yellow], spec, priors[0], seed=1), spec, left_side=True)
    if left is None and priors[0] is not None:
        left = _beside(fit_boundary(x[is_yellow], y[is_yellow], spec, None, seed=1), spec, left_side=True)
    wx, wy = x[~is_yellow], y[~is_yellow]
    yellow_path = left is not None or yellow_centre
    if not yellow_path:  # white on both sides: a left boundary's points are the tape's edge facing right
        left, right = _white_sides(edge_points(white, grid, bottom_v_px, lane_is_right=True), (wx, wy), spec, priors)
    else:
        if left is not None:
            wx, wy = _across(left, wx, wy, spec, left_side=True)
        right = _beside(fit_boundary(wx, wy, spec, priors[1], seed=2), spec, left_side=False)
        if right is None and priors[1] is not None:  # the prior lost the line (a jump): search afresh
            right = _beside(fit_boundary(wx, wy, spec, None, seed=3), spec, left_side=False)
    left = None if left is not None and _edge_of_wide_paint(left, yellow if yellow_path else white, grid, bottom_v_px, spec,
                                                             outward_left=True) else left
    right = None if right is not None and _edge_of_wide_paint(right, white, grid, bottom_v_px, spec, outward_left=False) else right
    geometry, width = 1.0, math.nan
    if left is not None and right is not None:
        near = right.samples()[: max(2, int(spec.metres(0.25) / STEP_M))]
        width = float(np.mean(-left.distance(near[:, 0], near[:, 1])))
        error = abs(width - spec.lane_width_m) / spec.lane_width_m
        lo, hi = WIDTH_TOLERANCE
        geometry = float(min(1.0, max(0.0, (hi - error) / (hi - lo))))
    return GroundLanes(left, right, geometry, len(x), width_m=width, yellow_left=left is not None and yellow_path)


def _edge_of_wide_paint(boundary: GroundBoundary, paint: np.ndarray, grid: GroundGrid, bottom_v_px: int, spec: GroundLaneSpec,
                        *, outward_left: bool) -> bool:
    """Whether a boundary fitted to paint edges is the edge of a bright patch far wider than any tape: along the span
    its markings were seen, the ground FLANK_M beyond it, away from the lane (left of a left boundary), is paint on at
    least FLANK_FILLED of the samples at every offset. A tape is road again past its width; a sunlit gap between two
    tree shadows passes the paint test (brighter than the shade round it by more than tape is than the mat) and its
    edge runs as smoothly as a line — fitted, it bent the lane off the road. Unknown (too little of the flank in view):
    not wide."""
    pts = boundary.samples()
    outward = boundary.normals(pts[:, 0], pts[:, 1]) * (1.0 if outward_left else -1.0)
    for d in FLANK_M:
        q = pts + spec.metres(d) * outward
        hit, seen = _paint_at(paint, grid, bottom_v_px, q[:, 0], q[:, 1])
        if seen.sum() < FLANK_MIN_SAMPLES or hit[seen].mean() < FLANK_FILLED:
            return False
    return True


def _paint_at(paint: np.ndarray, grid: GroundGrid, bottom_v_px: int, x: np.ndarray, y: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """(paint, in view) at ground points: the mask's pixel on the grid row nearest each point's range."""
    xs = grid.x_m  # decreasing from the grid's top row down
    rows = np.clip(np.searchsorted(-xs, -x), 0, len(xs) - 1)
    u = np.rint(grid.cx_px - y / grid.lateral_m_per_px[rows]).astype(np.int64)
    v = rows + grid.top_v_px
    seen = (u >= 0) & (u < paint.shape[1]) & (v <= bottom_v_px) & (x <= xs[0]) & (x >= xs[-1])
    hit = np.zeros(len(x), bool)
    hit[seen] = paint[v[seen], u[seen]] > 0
    return hit, seen


def _across(found: GroundBoundary, x: np.ndarray, y: np.ndarray, spec: GroundLaneSpec, *, left_side: bool) -> tuple[np.ndarray, np.ndarray]:
    """The points about a lane width across the lane from a found boundary (``left_side``: it is the left one): where
    the other boundary lies (0.5 to 1.6 lane widths over)."""
    w = spec.lane_width_m
    gap = -found.distance(x, y) if left_side else found.distance(x, y)
    keep = (gap >= 0.5 * w) & (gap <= 1.6 * w)
    return x[keep], y[keep]


def _white_sides(left_points: tuple[np.ndarray, np.ndarray], right_points: tuple[np.ndarray, np.ndarray], spec: GroundLaneSpec,
                 priors: tuple[GroundBoundary | None, GroundBoundary | None]) -> tuple[GroundBoundary | None, GroundBoundary | None]:
    """Both boundaries from one paint (white on both sides, a taped track), each from its tapes' edges facing the lane
    (``left_points``, ``right_points``): each side near its prior first; a side still missing from the points a lane
    width across from the other, or — the other not found either — from the points on its side of the camera's heading
    (a fit over both tapes' points can join the near end of one to the far end of the other: a line across the lane)."""
    sides: list[GroundBoundary | None] = [None, None]
    points = (left_points, right_points)
    for i, prior in enumerate(priors):
        if prior is not None:
            sides[i] = _beside(fit_boundary(*points[i], spec, prior, seed=2 + i), spec, left_side=i == 0)
    for i in (0, 1):
        if sides[i] is not None:
            continue
        x, y = points[i]
        other = sides[1 - i]
        if other is not None:
            x, y = _across(other, x, y, spec, left_side=i == 1)
        else:
            mine = y > 0 if i == 0 else y < 0
            x, y = x[mine], y[mine]
        sides[i] = _beside(fit_boundary(x, y, spec, None, seed=4 + i), spec, left_side=i == 0)
    return sides[0], sides[1]


BESIDE_LANES = 1.5  # [-] of the lane width: a boundary farther than this from the camera (or on its wrong side by more
#   than half a lane) does not bound the lane the car is in: a yellow duck on the verge, the other lane's white edge


def _beside(boundary: GroundBoundary | None, spec: GroundLaneSpec, *, left_side: bool) -> GroundBoundary | None:
    """The boundary if the camera is on its lane side (to its right for a left boundary), within BESIDE_LANES lanes."""
    if boundary is None:
        return None
    inward = -float(boundary.distance(np.zeros(1), np.zeros(1))[0]) if left_side else float(boundary.distance(np.zeros(1), np.zeros(1))[0])
    w = spec.lane_width_m
    return boundary if -0.5 * w <= inward <= BESIDE_LANES * w else None


def aim_point(lanes: GroundLanes, spec: GroundLaneSpec) -> tuple[float, float] | None:
    """The pure-pursuit point: where the lane centre — each boundary offset by half a lane toward it, the two averaged
    when both are seen — lies ``aim_m`` from the camera (its farthest modelled point when it stays nearer)."""
    points = []
    for side, delta in ((lanes.left, -0.5 * spec.lane_width_m), (lanes.right, 0.5 * spec.lane_width_m)):
        centre = side.offset(delta) if side is not None else None
        if centre is not None:
            points.append(_at_distance(centre.samples(spec.metres(EXTEND_M)), spec.aim_m))
    if not points:
        return None
    x, y = np.mean(points, axis=0)
    return float(x), float(y)


def _at_distance(curve: np.ndarray, distance_m: float) -> np.ndarray:
    """The first point of a sampled curve that is distance_m from the camera (interpolated), else its farthest."""
    r = np.hypot(curve[:, 0], curve[:, 1])
    beyond = np.flatnonzero(r >= distance_m)
    if len(beyond) == 0:
        return curve[int(np.argmax(r))]
    i = int(beyond[0])
    if i == 0:
        return curve[0]
    t = (distance_m - r[i - 1]) / (r[i] - r[i - 1])
    return curve[i - 1] + t * (curve[i] - curve[i - 1])


def agreement(now: GroundBoundary | None, before: GroundBoundary | None, spec: GroundLaneSpec) -> float:
    """1 when a boundary lies on last frame's, 0 at AGREEMENT_M of a lane width apart (mean over its near 0.3 m)."""
    if now is None or before is None:
        return 1.0
    near = now.samples()[: max(2, int(spec.metres(0.3) / STEP_M))]
    err = float(np.mean(np.abs(before.distance(near[:, 0], near[:, 1]))))
    return max(0.0, 1.0 - err / (AGREEMENT_M * spec.lane_width_m))


class GroundMemory:
    """Last frame's boundaries, each kept as the prior (the gate of its points) until LOST_AFTER_S unseen (the image
    tracks' limit), and the light's last gains and the split between the paints that came with them (kept until a
    frame measures new ones: the light's colour changes slowly, and a frame with one paint in view cannot measure it).
    For a spec that measures its lane (``width_measured``): the widths of the last WIDTH_FRAMES two-sided fits, and
    how many frames found a yellow left boundary (from YELLOW_TRACK_FRAMES on, the track has a yellow centre line:
    ``GroundLaneSpec.yellow_centre``)."""

    def __init__(self) -> None:
        self._last: list[tuple[float, GroundBoundary] | None] = [None, None]
        self._gains: tuple[float, float, float] | None = None
        self._split: float | None = None
        self._widths: deque[float] = deque(maxlen=WIDTH_FRAMES)
        self._yellow_frames = 0
        self._supports: tuple[deque[tuple[float, float]], deque[tuple[float, float]]] = (deque(), deque())

    def priors(self, t_s: float) -> GroundLanes | None:
        kept = [b if b is not None and t_s - b[0] <= LOST_AFTER_S else None for b in self._last]
        held = tuple(max((s for t, s in seen if 0.0 <= t_s - t <= SUPPORT_HOLD_S), default=0.0) for seen in self._supports)
        unseen = tuple(t_s - b[0] if b is not None else math.inf for b in kept)
        return GroundLanes(kept[0][1] if kept[0] else None, kept[1][1] if kept[1] else None, 1.0, 0, self._gains, self._split,
                           yellow_left=self._yellow_frames >= YELLOW_TRACK_FRAMES, held=(held[0], held[1]),
                           unseen_s=(unseen[0], unseen[1]))

    def spec_now(self, spec: GroundLaneSpec) -> GroundLaneSpec:
        """The spec with the lane width measured so far: the median of the remembered widths within WIDTH_RANGE of the
        spec's assumed one, once there are WIDTH_MIN_FRAMES of them; a spec that knows its width, unchanged."""
        if not spec.width_measured:
            return spec
        widths = np.array(self._widths)
        lo, hi = WIDTH_RANGE
        widths = widths[(widths >= lo * spec.lane_width_m) & (widths <= hi * spec.lane_width_m)]
        return replace(spec, lane_width_m=float(median(widths))) if len(widths) >= WIDTH_MIN_FRAMES else spec

    def remember(self, t_s: float, lanes: GroundLanes) -> None:
        """This frame's fit: its boundaries found (a coasted one is no new sighting), their supports, light and width."""
        for i, b in enumerate((lanes.left, lanes.right)):
            seen = self._supports[i]
            while seen and not 0.0 <= t_s - seen[0][0] <= SUPPORT_HOLD_S:  # too old (or time went back: a new run)
                seen.popleft()
            if b is not None and not lanes.coasted[i]:
                if lanes.agreement[i] < JUMP_AGREEMENT:
                    seen.clear()  # another line than the one held: what that one showed vouches nothing for this one
                self._last[i] = (t_s, b)
                seen.append((t_s, b.support))
        if lanes.light_gains is not None:
            self._gains, self._split = lanes.light_gains, lanes.light_split
        self._yellow_frames += lanes.yellow_left
        if math.isfinite(lanes.width_m):
            self._widths.append(lanes.width_m)


@dataclass(frozen=True)
class GroundFit:
    """The ground model's result for the rest of the frame analysis, in working pixels."""

    lanes: GroundLanes
    left: LaneLine | None  # each boundary's image chord over its near 0.15 m (the lead search, the overlay, the width memory)
    right: LaneLine | None
    agreement: tuple[float, float]  # each side's agreement with its prior
    features: np.ndarray  # the marking mask (white | yellow)
    paint_integral: np.ndarray  # its integral over the road rows
    out_of_view: tuple[bool, bool]  # a missing side that the model places outside the picture
    expected: tuple[tuple[np.ndarray, np.ndarray], ...]  # where the boundaries should show: (rows, columns) per side
    curves_px: tuple[np.ndarray | None, np.ndarray | None]  # each boundary as an image polyline (n, 2: u, v), for the overlay
    interior: np.ndarray | None = None  # bool over the road rows: pixels whose ground lies inside the lane, inset from its
    #   boundaries, as far as the markings were seen (the road model's samples, the object search)
    hls_white: np.ndarray | None = None  # the HLS image under white light when a tinted one was measured (paint_light)
    white: np.ndarray | None = None  # bool over the road rows: the white (edge-line) paint, the interior's wall


def ground_lanes_in_image(
    hls: np.ndarray, mask: np.ndarray, region: RoadRegion, camera: CameraModel, spec: GroundLaneSpec, priors: GroundLanes | None,
    bgr: np.ndarray | None = None,
) -> GroundFit | None:
    """The ground model on a working-size HLS image (and its BGR, to judge colour under white light: paint_light).
    None when the camera cannot see the fit range."""
    cam = camera.scaled_to(region.width_px, region.height_px)
    grid = ground_grid(cam, region.top_v_px, region.bottom_v_px, spec.far_m)
    if grid is None:
        return None
    light = smoothed_light(hls)
    before = priors if priors is not None else GroundLanes(None, None, 1.0, 0)
    held = np.array(before.light_gains) if before.light_gains is not None else None
    white, yellow, gains, hls_white, split_b = marking_masks(
        hls, light, mask, region.top_v_px, region.bottom_v_px, bgr, held, before.light_split)
    yellow = flat_paint(yellow, grid, region.bottom_v_px, spec.scale)
    features = cv2.bitwise_or(white, yellow)
    centre = spec.yellow_centre if spec.yellow_centre is not None else before.yellow_left
    lanes = detect_ground_lanes(white, yellow, grid, region.bottom_v_px, spec, (before.left, before.right), centre)
    lanes = replace(lanes, agreement=(agreement(lanes.left, before.left, spec), agreement(lanes.right, before.right, spec)))
    hidden = (lanes.left is None and lanes.right is not None and not _in_view(lanes.right.offset(spec.lane_width_m), cam, grid, spec),
              lanes.right is None and lanes.left is not None and not _in_view(lanes.left.offset(-spec.lane_width_m), cam, grid, spec))
    lanes = coast(lanes, before, spec)
    if gains is not None:
        lanes = replace(lanes, light_gains=(float(gains[0]), float(gains[1]), float(gains[2])), light_split=split_b)
    band = slice(region.top_v_px, region.bottom_v_px + 1)
    integral = cv2.integral((features[band] > 0).view(np.uint8), sdepth=cv2.CV_64F)
    left, right = (_image_chord(b, cam, spec) for b in (lanes.left, lanes.right))
    curves = tuple(_image_polyline(b, cam, spec) for b in (lanes.left, lanes.right))
    edge_paint = white[band] > 0
    return GroundFit(lanes, left, right, lanes.agreement, features, integral, hidden,
                     expected_points(_expected_lanes(lanes, before, spec), cam, region, spec),
                     (curves[0], curves[1]), lane_interior(lanes, grid, region, spec, edge_paint), hls_white, edge_paint)


def coast(lanes: GroundLanes, before: GroundLanes, spec: GroundLaneSpec) -> GroundLanes:
    """This frame's boundaries (with their ``agreement`` with the priors), a side not found in it held through the miss
    when it was seen well within SUPPORT_HOLD_S (its held support ≥ COAST_SUPPORT_MIN: a stray fit on a far dash of the
    next lane, which restarts the hold, is no line to hold) — between two dashes of a dashed line, over a short gap in
    worn paint, the lane goes on as it was, as the image tracks coast through such a miss (``frame.coasting_sides``):

    - the other side found: the missing one is that side a lane width over (where the model expects it anyway: its
      last sighting is where it was before the car moved on, and on a Duckietown curve the car turns 40° in 0.6 s);
    - neither found: both as last seen (straight on: nothing tells otherwise, and the hold is short).

    A held side's own support is 0 (nothing of it is seen now): its held support, fading linearly over SUPPORT_HOLD_S
    from its last sighting, is what it adds to the lane confidence, and only in a clean picture
    (``confidence.lane_confidence``: at night it does not). A side found keeps the best support of its last
    SUPPORT_HOLD_S, this frame's included, when it is the line held (agreement ≥ JUMP_AGREEMENT), so a dashed line does
    not flicker as its dashes pass a camera that sees only a few of them (0.5 m ahead of a Duckiebot); a side neither
    found nor held has 0."""
    found = (lanes.left, lanes.right)
    sides: list[GroundBoundary | None] = []
    held: list[float] = []
    coasted: list[bool] = []
    for i, prior in enumerate((before.left, before.right)):
        unseen = before.unseen_s[i]
        fade = 1.0 - unseen / SUPPORT_HOLD_S if unseen >= 0.0 else 0.0  # time went back (a new run): nothing held
        now, other = found[i], found[1 - i]
        if now is None and before.held[i] >= COAST_SUPPORT_MIN and fade > 0.0:
            kept = other.offset(spec.lane_width_m if i == 0 else -spec.lane_width_m) if other is not None else prior
            if kept is not None:
                sides.append(replace(kept, support=0.0, inliers=0))
                held.append(before.held[i] * fade)
                coasted.append(True)
                continue
        sides.append(now)
        coasted.append(False)
        if now is None:
            held.append(0.0)
        elif lanes.agreement[i] >= JUMP_AGREEMENT:  # the line held: its best of the hold
            held.append(max(now.support, before.held[i]))
        else:
            held.append(now.support)
    return replace(lanes, left=sides[0], right=sides[1], held=(held[0], held[1]), coasted=(coasted[0], coasted[1]))


def _image_polyline(boundary: GroundBoundary | None, camera: CameraModel, spec: GroundLaneSpec) -> np.ndarray | None:
    """The boundary where its markings were seen (and EXPECT_BEYOND_M beyond), within the fit range, in image pixels."""
    if boundary is None:
        return None
    pts = boundary.samples(spec.metres(EXPECT_BEYOND_M))
    pts = pts[np.hypot(pts[:, 0], pts[:, 1]) <= spec.far_m]
    u, v, ok = camera.project_ground(pts[:, 0], pts[:, 1])
    return np.stack([u[ok], v[ok]], axis=1) if ok.sum() >= 2 else None


def _expected_lanes(lanes: GroundLanes, before: GroundLanes, spec: GroundLaneSpec) -> GroundLanes:
    """Where the boundaries should show: this frame's; when it found neither, the last ones seen (the priors, kept
    LOST_AFTER_S), else a straight lane of the spec's width centred on the camera. Paint that ends on a plain road (a
    crossing without tape, a gap in worn paint) is absent, not hidden: the occlusion measure then finds road where the
    boundaries should be, and something standing there hidden (with no boundary expected at all, every frame without
    paint read as fully occluded and stopped the car at the first gap)."""
    if lanes.left is not None or lanes.right is not None:
        return lanes
    if before.left is not None or before.right is not None:
        return replace(lanes, left=before.left, right=before.right)
    half = 0.5 * spec.lane_width_m
    return replace(lanes, left=_straight_boundary(half, spec), right=_straight_boundary(-half, spec))


def _straight_boundary(y_m: float, spec: GroundLaneSpec) -> GroundBoundary:
    """A straight boundary along the camera's heading, ``y_m`` to its left (negative: right), over the fit range."""
    return GroundBoundary(0.0, 0.0, 1.0, -y_m, (spec.near_m, y_m), (spec.far_m, y_m), 0.0, 0)


def expected_points(
    lanes: GroundLanes, camera: CameraModel, region: RoadRegion, spec: GroundLaneSpec,
) -> tuple[tuple[np.ndarray, np.ndarray], ...]:
    """Image points (rows on the occlusion grid, columns) where each boundary should show — the fitted curve over the
    span its markings were seen on and a little beyond (EXPECT_BEYOND_M: the model's extrapolation is a guess, not an
    expectation), or for a missing side the seen one a lane width over — inside the fit range and the road region."""
    out = []
    w = spec.lane_width_m
    for side, other, delta in ((lanes.left, lanes.right, w), (lanes.right, lanes.left, -w)):
        curve = side if side is not None else (other.offset(delta) if other is not None else None)
        if curve is None:
            continue
        pts = curve.samples(spec.metres(EXPECT_BEYOND_M))
        pts = pts[np.hypot(pts[:, 0], pts[:, 1]) <= spec.far_m]
        u, v, ok = camera.project_ground(pts[:, 0], pts[:, 1])
        keep = ok & (u >= 0) & (u < region.width_px) & (v >= region.top_v_px) & (v <= region.bottom_v_px)
        last = region.top_v_px + ((region.bottom_v_px - region.top_v_px) // ROW_STEP) * ROW_STEP
        rows = np.minimum(region.top_v_px + ROW_STEP * np.rint((v[keep] - region.top_v_px) / ROW_STEP), last)
        out.append((rows.astype(np.int64), np.rint(u[keep]).astype(np.int64)))
    return tuple(out)


def lane_interior(
    lanes: GroundLanes, grid: GroundGrid, region: RoadRegion, spec: GroundLaneSpec, white: np.ndarray,
) -> np.ndarray | None:
    """bool (road rows, width): the pixels whose ground point lies between the two boundaries — following their curves,
    obstacle.INSET of the lane width inside each — and no farther than the markings were seen (EXPECT_BEYOND_M beyond
    the farthest), nor beyond the edge line: on each row the interior ends at the first white paint pixel (``white``,
    bool over the road rows) either side of its middle, where a fit that strays at its far end (a tape corner) would
    cross the tape onto the verge. Yellow is no wall: a yellow duck stands in the lane, and beyond the yellow centre
    line lies more road. A missing side is the seen one a lane width over. None without any boundary.

    On a curve the straight chords between the boundaries cut across the verge; this follows the lane round it."""
    w = spec.lane_width_m
    left = lanes.left if lanes.left is not None else (lanes.right.offset(w) if lanes.right is not None else None)
    right = lanes.right if lanes.right is not None else (lanes.left.offset(-w) if lanes.left is not None else None)
    if left is None or right is None:
        return None
    seen = [b for b in (lanes.left, lanes.right) if b is not None]
    reach = min(spec.far_m, max(math.hypot(*b.end) for b in seen) + spec.metres(EXPECT_BEYOND_M))
    out = np.zeros((region.bottom_v_px - region.top_v_px + 1, region.width_px), bool)
    rows = np.flatnonzero(grid.x_m <= reach)  # grid rows (from grid.top_v_px) within reach ahead
    if len(rows) == 0:
        return out
    cols = np.arange(region.width_px)
    x = grid.x_m[rows][:, None]
    y_all, r2_all = grid.plane(region.width_px)
    y, r2 = y_all[rows], r2_all[rows]  # (rows, width)
    inset = INSET * w
    inside = r2 <= reach * reach
    # right of the left boundary by the inset and left of the right one: the sign of the offset curves' polynomial is
    # the sign of the distance (no square root per pixel); a curve with no offset there is judged by its distance
    for curve, delta, sign in ((left, -inset, -1.0), (right, inset, 1.0)):
        moved = curve.offset(delta)
        if moved is not None:
            value = moved.a * r2 + moved.b * x + moved.c * y + moved.d
        else:
            value = (curve.distance(np.broadcast_to(x, y.shape).ravel(), y.ravel()) - delta).reshape(y.shape)
        inside &= (value >= 0.0) if sign > 0 else (value <= 0.0)  # sign · value ≥ 0, without the product
    band_rows = rows + grid.top_v_px - region.top_v_px
    has = inside.any(axis=1)
    middle = np.where(has, np.argmax(inside, axis=1) + inside.sum(axis=1) // 2, 0)[:, None]  # a column inside each row
    wall = white[band_rows]
    right_wall, left_wall = wall & (cols >= middle), wall & (cols <= middle)
    first_right = np.where(right_wall.any(axis=1), np.argmax(right_wall, axis=1), region.width_px)[:, None]
    last_left = np.where(left_wall.any(axis=1), region.width_px - 1 - np.argmax(left_wall[:, ::-1], axis=1), -1)[:, None]
    out[band_rows] = inside & (cols > last_left) & (cols < first_right)
    return out


VISIBLE_SHARE = 0.25  # [-] a boundary with less than this share of its near 0.3 m inside the road region is out of view


def _in_view(expected: GroundBoundary | None, camera: CameraModel, grid: GroundGrid, spec: GroundLaneSpec) -> bool:
    """Would the camera see this boundary (its near 0.3 m at the spec's scale, as the lane model places it)?"""
    if expected is None:
        return True  # the model cannot place it: count it as missing
    near_m = spec.metres(0.3)
    pts = expected.samples(near_m)[: int(near_m / STEP_M)]
    u, v, ok = camera.project_ground(pts[:, 0], pts[:, 1])
    inside = ok & (u >= 0) & (u < camera.width_px) & (v >= grid.top_v_px) & (v < camera.height_px)
    return float(inside.mean()) >= VISIBLE_SHARE


def _image_chord(boundary: GroundBoundary | None, camera: CameraModel, spec: GroundLaneSpec) -> LaneLine | None:
    """The straight image line through the boundary's nearest point and the one 0.15 m along it (at the spec's scale; or
    its end)."""
    if boundary is None:
        return None
    pts = boundary.samples()
    ends = pts[[0, min(len(pts) - 1, int(spec.metres(0.15) / STEP_M))]]
    u, v, ok = camera.project_ground(ends[:, 0], ends[:, 1])
    if not ok.all() or abs(v[0] - v[1]) < 1e-6:
        return None
    slope = (u[0] - u[1]) / (v[0] - v[1])
    return LaneLine(float(slope), float(u[0] - slope * v[0]), boundary.support, boundary.inliers)
