"""Occlusion: the share of the expected lane-marking region that something foreign hides.

Definition (measurable, see docs/perception.md): the expected marking region is a band along each
expected boundary (tracked, else detected, else a default lane) sampled every ``ROW_STEP`` rows from
the road region's top to its bottom. A sample is *hidden* when there is no marking pixel in its band and
the pixels there do not look like road — compared with a *road appearance* (``RoadAppearance``: grey level,
saturation and roughness of the lane interior; ``RoadModel`` keeps it over recent frames, so one frame's
occluder, even one reaching the frame bottom, does not become the idea of road): they are much brighter, or
darker than any shadow, or strongly coloured but not yellow (car paint), or smooth where the road is rough
(texture: the coefficient of variation of a small patch — a ratio, so it survives shade; a painted body panel,
a box, a sheet are smooth). A shadow keeps the road's texture and colour and is only darker: it is road.
A sample on a row that is uniformly road-like across the whole road (ego lane ± a lane width) is road too
(pale concrete after dark asphalt, a shadow across the road). Samples inside a known vehicle box are hidden.
occlusion = max(hidden / samples, min(the most hidden boundary's own share, ONE_SIDE_MAX)): an object over one line
hides that line as much as its share says, not half of it; one line hidden whole is half the markings, as the share of
both says. The lane confidence discounts hidden / samples (it averages the two boundaries' evidence).
"""

from __future__ import annotations

import math
from collections import deque
from dataclasses import dataclass, replace

import cv2
import numpy as np

from fearguard.vision.lanes import LaneLine, RoadRegion, default_lines  # noqa: F401  (default_lines: re-exported)
from fearguard.vision.medians import median
from fearguard.vision.ridges import clamp

ROW_STEP = 2  # [px] sample every this many rows of the working image
BAND = 0.02  # [-] of the width: half-width of the band around an expected boundary
BRIGHTER = 1.45  # [-] a sample this many times brighter than the road is not road (no shadow brightens) ...
DARKER = 0.25  # [-] ... nor one darker than this share of it (deeper than a daylight shadow) ...
FOREIGN_DEV_MIN = 30.0  # [grey levels] ... when it differs by at least this much (noise in the dark)
COLOUR_SAT_MIN = 110  # [0..255] HLS saturation of car paint (yellow paint excluded by hue)
SAT_DEV = 70  # [0..255] a saturation this far from the road's is a coloured object
HUE_DEV = 20  # [OpenCV hue 0..180] on a saturated floor, a pixel as saturated as car paint this far from its hue (40°) is
#               a coloured object: a blue box on an orange tarp is no more saturated than the tarp, but it is blue
FLOOR_COLOURED_SHARE = 0.8  # [-] of the region's bottom rows, across its whole width, saturated (≥ COLOUR_SAT_MIN − SAT_DEV / 2)
#                            and of one hue (resultant length ≥ this too): a coloured floor, not an object on a grey one
YELLOW_HUE = (14, 40)  # [OpenCV hue 0..180] yellow paint is not car paint
SMOOTH_SHARE = 0.35  # [-] a patch with less than this share of the road's roughness is a smooth object ...
SMOOTHER_SHARE = 0.6  # [-] a brighter patch with less than this share of the road's roughness is a pale object
ROUGH_MIN = 0.004  # [-] ... when the road itself is measurably rough (a rendered road may be flat) ...
ROUGH_MIN_LEVELS = 0.5  # [grey levels] ... and its texture stands above quantisation: a mean neighbour difference under half
#   a grey level is fewer than half the pairs one level apart (a flat road's noise); the ratio alone grows as the light
#   dims, and a dark, flat rendered road at night read as rough made its every smooth patch an object
DIFF_CLIP_PX = 8.0  # [grey levels] roughness counts a neighbour difference up to this (beyond: an edge, not texture)
ROW_SAMPLES = 15  # [-] points across the road (ego lane ± a lane width) that give a row's road grey
ROW_UNIFORM = 0.8  # [-] share of a row's points close to its median for the row to count as all road
ROW_DEV = 0.25  # [-] relative deviation from the row median that still counts as the same surface
REFERENCE_ROWS = 0.15  # [-] of the region's height: bottom rows whose lane interior gives the road reference
PATCH_HALF_PX = 6  # [px] roughness patches are 3 rows × (2·this + 1) columns of the working image
MODEL_FRAMES = 15  # [frames] the road appearance is the median of this many recent frames ...
MODEL_CHANGE_FRAMES = 10  # [frames] ... and re-learnt after this many frames in a row unlike it (the road changed)
MODEL_GREY_RATIO = 1.35  # [-] a frame's road this much brighter or darker than the model is unlike it ...
MODEL_ROUGH_RATIO = 2.0  # [-] ... as is one this much rougher or smoother
ONE_SIDE_MAX = 0.5  # [-] one boundary's hidden share counts up to this: hidden entirely, the other seen whole, it is half the
#   markings, as the share of both says; only both hidden is more
LEARN_OCCLUSION_MAX = 0.15  # [-] frames with more occlusion than this do not teach the model
_INTERIOR_FRACTIONS = np.linspace(0.2, 0.8, 5)  # [-] of the lane width: where road_appearance samples each row
ACROSS_ROAD = np.linspace(-0.9, 1.9, ROW_SAMPLES)  # [-] of the lane width: row_references' points across the road
ACROSS_LANE = np.linspace(0.05, 0.95, ROW_SAMPLES)  # [-] of the lane width: ... across the ego lane alone


@dataclass(frozen=True)
class RoadAppearance:
    """What the road looks like: median grey level, median HLS saturation, median patch roughness (std / mean), and —
    on a saturated floor (a wood floor, an orange tarp) — its hue."""

    grey: float
    saturation: float
    roughness: float
    hue: float = math.nan  # [OpenCV 0..180] a coloured floor's hue (circular mean); NaN: a grey road (``floor_hue``)

    def like(self, other: RoadAppearance) -> bool:
        """Same surface (within the model's tolerances)?"""
        g = max(self.grey, 1.0) / max(other.grey, 1.0)
        r = max(self.roughness, 1e-4) / max(other.roughness, 1e-4)
        return 1 / MODEL_GREY_RATIO <= g <= MODEL_GREY_RATIO and 1 / MODEL_ROUGH_RATIO <= r <= MODEL_ROUGH_RATIO

    @property
    def textured(self) -> bool:
        """Rough enough that a smooth patch on it is something else (ROUGH_MIN, and ROUGH_MIN_LEVELS in grey levels)."""
        return self.roughness >= ROUGH_MIN and self.roughness * self.grey >= ROUGH_MIN_LEVELS


class RoadModel:
    """The road's appearance over recent frames: robust to a single frame's (or a short) occluder.

    A frame's appearance is learnt when the frame's occlusion was low and it looks like the model (or the model is
    new); after MODEL_CHANGE_FRAMES frames in a row unlike the model, the road itself changed and it is re-learnt."""

    def __init__(self) -> None:
        self._seen: deque[RoadAppearance] = deque(maxlen=MODEL_FRAMES)
        self._unlike = 0
        self.current: RoadAppearance | None = None

    def reset(self) -> None:
        self.__init__()  # type: ignore[misc]

    def reference(self, measured: RoadAppearance) -> RoadAppearance:
        """The appearance to judge this frame by: the model, else this frame's own measurement."""
        return self.current if self.current is not None else measured

    def learn(self, measured: RoadAppearance, occlusion: float) -> None:
        if self.current is not None and not measured.like(self.current):
            self._unlike += 1
            if self._unlike < MODEL_CHANGE_FRAMES:
                return
            self._seen.clear()
        elif not occlusion <= LEARN_OCCLUSION_MAX:
            return
        self._unlike = 0
        self._seen.append(measured)
        grey, sat, rough = median(np.array([(a.grey, a.saturation, a.roughness) for a in self._seen]), axis=0)
        self.current = RoadAppearance(float(grey), float(sat), float(rough), mean_hue(np.array([a.hue for a in self._seen])))


@dataclass(frozen=True)
class SurfaceMaps:
    """Per-frame maps over the road region's rows (computed once, looked up by every sample): 3 × (2·PATCH_HALF_PX + 1)
    patch means of grey and saturation, patch roughness, the pixels' hue, and an integral image of the marking pixels.

    Roughness = mean absolute difference of horizontally adjacent pixels, each clipped at DIFF_CLIP_PX, over the mean
    grey: fine texture counts fully, a single edge through the patch (a shadow's, a marking's) only a little, and the
    ratio is the same in sun and in shade."""

    top_v_px: int
    grey: np.ndarray  # float32 patch means
    saturation: np.ndarray
    roughness: np.ndarray
    hue: np.ndarray  # uint8, the pixel's own
    paint_integral: np.ndarray  # integral image of the marking pixels (0/1) over the band


def surface_maps(
    gray: np.ndarray, hls: np.ndarray, features: np.ndarray, region: RoadRegion, paint_integral: np.ndarray | None = None
) -> SurfaceMaps:
    """The maps for a working image; paint_integral: the band's marking-pixel integral when already computed
    (``LaneDetection.maps``)."""
    band = slice(region.top_v_px, region.bottom_v_px + 1)
    g = gray[band].astype(np.float32)
    k = (2 * PATCH_HALF_PX + 1, 3)
    grey = cv2.blur(g, k, borderType=cv2.BORDER_REPLICATE)
    diff = np.zeros_like(g)  # |right neighbour − pixel|, clipped; 0 in the last column (no right neighbour)
    cv2.min(cv2.absdiff(g[:, 1:], g[:, :-1]), DIFF_CLIP_PX, dst=diff[:, :-1])
    rough = cv2.divide(cv2.blur(diff, k, borderType=cv2.BORDER_REPLICATE), cv2.max(grey, 1.0))
    sat = cv2.blur(cv2.extractChannel(hls[band], 2).astype(np.float32), k, borderType=cv2.BORDER_REPLICATE)
    if paint_integral is None:
        paint_integral = cv2.integral((features[band] > 0).view(np.uint8), sdepth=cv2.CV_64F)
    return SurfaceMaps(region.top_v_px, grey, sat, rough, hls[band, :, 0], paint_integral)


def road_appearance(
    gray: np.ndarray, hls: np.ndarray, region: RoadRegion, left: LaneLine, right: LaneLine, maps: SurfaceMaps | None = None,
    *, interior: np.ndarray | None = None,
) -> RoadAppearance:
    """The lane interior's appearance over the whole road region (medians over patches spread through it: one
    shadow or patch of concrete does not set it). The interior: between the straight boundaries, or ``interior`` (bool
    over the road rows: the bending lane's, ``ground_lanes.lane_interior``), sampled on every 2·ROW_STEP-th row."""
    maps = maps if maps is not None else surface_maps(gray, hls, np.zeros_like(gray), region)
    if interior is not None:
        r, c = np.nonzero(interior[1 :: 2 * ROW_STEP, ::2])
        if len(r):
            r, c = 1 + 2 * ROW_STEP * r, 2 * c
            grey, sat, rough = median(np.array([maps.grey[r, c], maps.saturation[r, c], maps.roughness[r, c]]), axis=1)
            return RoadAppearance(float(grey), float(sat), float(rough), floor_hue(maps))
    rows = np.arange(region.top_v_px + 1, region.bottom_v_px, 2 * ROW_STEP)
    a, b = left.u_at(rows.astype(float)), right.u_at(rows.astype(float))
    lo, hi = np.minimum(a, b), np.maximum(a, b)
    frac = _INTERIOR_FRACTIONS
    cols = clamp(np.rint(lo[:, None] + frac[None, :] * (hi - lo)[:, None]).astype(np.int64), 0, region.width_px - 1)
    r = (rows - maps.top_v_px)[:, None]
    grey, sat, rough = median(np.array([maps.grey[r, cols], maps.saturation[r, cols], maps.roughness[r, cols]]).reshape(3, -1), axis=1)
    return RoadAppearance(float(grey), float(sat), float(rough), floor_hue(maps))


def floor_hue(maps: SurfaceMaps) -> float:
    """A coloured floor's hue (a wood floor, an orange tarp), NaN for a grey road. The floor is coloured when the region's
    bottom rows (REFERENCE_ROWS, the road just ahead), across the whole picture's width and so beyond the lane's lines
    too, are saturated and of one hue (FLOOR_COLOURED_SHARE of them, and the hues' resultant length): an object in the
    lane — a red car — covers the lane, not the floor on both sides of it."""
    rows = max(1, round(REFERENCE_ROWS * maps.saturation.shape[0]))
    sat, hue = maps.saturation[-rows::ROW_STEP, ::2], maps.hue[-rows::ROW_STEP, ::2]
    coloured = sat >= COLOUR_SAT_MIN - 0.5 * SAT_DEV
    if not coloured.mean() >= FLOOR_COLOURED_SHARE:
        return math.nan
    mean, resultant = _circular_hue(hue[coloured].astype(np.float64))
    return mean if resultant >= FLOOR_COLOURED_SHARE else math.nan


def mean_hue(hues: np.ndarray) -> float:
    """Circular mean of OpenCV hues (0..180 = 0..360°), NaN ones left out; NaN when none is given."""
    return _circular_hue(hues[np.isfinite(hues)])[0]


def _circular_hue(hues: np.ndarray) -> tuple[float, float]:
    """Circular mean of OpenCV hues and the resultant length (0..1: how much they agree); (NaN, 0) for none."""
    if hues.size == 0:
        return math.nan, 0.0
    a = np.radians(2.0 * hues)
    c, s = float(np.cos(a).mean()), float(np.sin(a).mean())
    return (math.degrees(math.atan2(s, c)) % 360.0) / 2.0, math.hypot(c, s)


def hue_distance(hue: np.ndarray, reference: float) -> np.ndarray:
    """Circular distance of OpenCV hues from a reference hue, 0..90 (= 0..180°)."""
    d = np.abs(hue.astype(np.float32) - np.float32(reference)) % 180.0
    return np.minimum(d, 180.0 - d)


def road_reference(gray: np.ndarray, region: RoadRegion, left: LaneLine, right: LaneLine) -> float:
    """Median grey of the lane interior in the bottom rows of the region (the road just ahead)."""
    bottom = region.bottom_v_px
    top = max(region.top_v_px, int(bottom - REFERENCE_ROWS * (bottom - region.top_v_px)))
    rows = np.arange(top, bottom + 1, ROW_STEP)
    a, b = left.u_at(rows.astype(float)), right.u_at(rows.astype(float))
    inset = 0.15 * np.abs(b - a)
    lo = np.maximum(0, np.minimum(a, b) + inset).astype(np.int64)
    hi = np.minimum(region.width_px, np.maximum(a, b) - inset).astype(np.int64)
    cols = np.arange(gray.shape[1])
    inside = (cols >= lo[:, None]) & (cols < hi[:, None])  # [lo, hi) of each row
    if not inside.any():
        return float(median(gray[top : bottom + 1]))
    return float(median(gray[rows][inside]))


def row_references(
    gray: np.ndarray, region: RoadRegion, rows: np.ndarray, interior: tuple[LaneLine, LaneLine], across: np.ndarray = ACROSS_ROAD,
) -> tuple[np.ndarray, np.ndarray]:
    """Median grey across the road on each row — at ``across`` (shares of the lane width from its left boundary; by
    default the ego lane and a lane width either side), in the image only — and whether the row is uniform (ROW_UNIFORM
    of its points close to that median: one surface across the road, not a vehicle or a box covering part of it)."""
    cols, inside = _across_points(region, rows, interior, across)
    values = gray[rows[:, None], cols].astype(float)
    med = _row_medians(values, inside)
    close = inside & (np.abs(values - med[:, None]) <= np.maximum(FOREIGN_DEV_MIN, ROW_DEV * med)[:, None])
    return med, close.sum(axis=1) >= ROW_UNIFORM * np.maximum(inside.sum(axis=1), 1)


def row_roughness(
    maps: SurfaceMaps, region: RoadRegion, rows: np.ndarray, interior: tuple[LaneLine, LaneLine], across: np.ndarray = ACROSS_ROAD,
) -> np.ndarray:
    """Median patch roughness on each row at ``row_references``' points (in the image only; NaN on a row with none): a
    row's own texture, which changes along the road (asphalt ahead of concrete) as its grey does."""
    cols, inside = _across_points(region, rows, interior, across)
    return _row_medians(maps.roughness[(rows - maps.top_v_px)[:, None], cols].astype(float), inside)


def _across_points(
    region: RoadRegion, rows: np.ndarray, interior: tuple[LaneLine, LaneLine], across: np.ndarray,
) -> tuple[np.ndarray, np.ndarray]:
    """Each row's columns at ``across`` (shares of the lane width from its left boundary), clamped into the image, and
    which of them lie in it."""
    a, b = interior[0].u_at(rows.astype(float)), interior[1].u_at(rows.astype(float))
    cols = np.rint(a[:, None] + across[None, :] * (b - a)[:, None])
    inside = (cols >= 0) & (cols < region.width_px)
    return clamp(cols, 0, region.width_px - 1).astype(np.int64), inside


def _row_medians(values: np.ndarray, inside: np.ndarray) -> np.ndarray:
    """Median of each row's values where ``inside`` (NaN for a row with none): np.nanmedian goes through masked arrays,
    10× slower here."""
    ordered = np.sort(np.where(inside, values, np.inf), axis=1)
    n = inside.sum(axis=1)
    lo = np.maximum(n - 1, 0) // 2
    r = np.arange(len(values))
    med = 0.5 * (ordered[r, lo] + ordered[r, np.where(n % 2 == 0, n // 2, lo)])
    return np.where(n > 0, med, np.nan)


def sample_rows(region: RoadRegion) -> np.ndarray:
    """The working-image rows the expected marking region is sampled on."""
    return np.arange(region.top_v_px, region.bottom_v_px + 1, ROW_STEP)


def hidden_at(
    maps: SurfaceMaps, region: RoadRegion, rows: np.ndarray, centre: np.ndarray, road: RoadAppearance,
    row_ref: tuple[np.ndarray, np.ndarray], boxes: tuple[tuple[int, int, int, int], ...] = (),
) -> tuple[int, int]:
    """(hidden, total) of expected marking points (rows on the sample_rows grid, columns ``centre``; a bending lane's
    boundary may cross a row more than once, or not at all)."""
    half = max(2, int(BAND * region.width_px))
    lo, hi = clamp(centre - half, 0, region.width_px), clamp(centre + half + 1, 0, region.width_px)
    seen = hi > lo  # rows where the band is in the image at all
    if not seen.any():
        return 0, 0
    rows, centre, lo, hi = rows[seen], centre[seen], lo[seen], hi[seen]
    k = (rows - region.top_v_px) // ROW_STEP  # the sample row of each point
    row_grey, row_uniform = row_ref[0][k], row_ref[1][k]
    r = rows - maps.top_v_px
    u = clamp(centre, 0, region.width_px - 1)  # a band running off the image is judged at its edge pixel
    pi = maps.paint_integral
    paint = (pi[r + 1, hi] - pi[r + 1, lo] - pi[r, hi] + pi[r, lo]) > 0
    grey, rough, sat, hue = maps.grey[r, u], maps.roughness[r, u], maps.saturation[r, u], maps.hue[r, u]
    ref = max(road.grey, 1.0)
    off_grey = np.abs(grey - ref) >= FOREIGN_DEV_MIN
    textured = road.textured
    smooth = (rough < SMOOTH_SHARE * road.roughness) if textured else np.zeros(len(rows), bool)
    smoother = (rough < SMOOTHER_SHARE * road.roughness) if textured else np.ones(len(rows), bool)
    # brighter than the road *and* smoother (a white or silver body; sunlit concrete keeps its texture), or darker than
    # any shadow (a black body, a tyre)
    foreign = off_grey & (((grey > BRIGHTER * ref) & smoother) | (grey < DARKER * ref))
    coloured = coloured_unlike_road(sat, hue, road)
    coloured &= ~((hue >= YELLOW_HUE[0]) & (hue <= YELLOW_HUE[1]))
    row_road = row_uniform & (np.abs(grey - row_grey) <= np.maximum(FOREIGN_DEV_MIN, ROW_DEV * row_grey)) & ~smooth
    hidden = ((foreign & ~row_road) | coloured | smooth) & ~paint
    for x, y, w, h in boxes:
        hidden |= (centre >= x) & (centre < x + w) & (rows >= y) & (rows < y + h)
    return int(hidden.sum()), len(rows)


def coloured_unlike_road(sat: np.ndarray, hue: np.ndarray, road: RoadAppearance) -> np.ndarray:
    """Pixels coloured unlike the road, SAT_DEV from the road's saturation either way, or as saturated as car paint
    (COLOUR_SAT_MIN): on a grey road (``road.hue`` NaN) any such pixel; on a coloured floor (a wood floor, an orange tarp:
    the road, not an object over it) one half SAT_DEV more saturated than the floor, or of another hue (HUE_DEV)."""
    paint = sat >= COLOUR_SAT_MIN
    if math.isfinite(road.hue):
        paint &= (sat - road.saturation >= 0.5 * SAT_DEV) | (hue_distance(hue, road.hue) >= HUE_DEV)
    return paint | (np.abs(sat - road.saturation) >= SAT_DEV)


@dataclass(frozen=True)
class HiddenMarkings:
    """How much of the expected marking region something foreign hides: of both boundaries' samples together, and of the
    most hidden boundary's own."""

    share: float  # [0..1] hidden samples / samples, both boundaries together (what the lane confidence discounts)
    worst_side: float  # [0..1] the most hidden boundary's own share

    @property
    def occlusion(self) -> float:
        """The occlusion cue: the share of both, or the most hidden boundary's own share up to ONE_SIDE_MAX — an object
        over one line hides that line as much as its share there says, not half of it."""
        return max(self.share, min(self.worst_side, ONE_SIDE_MAX))


NOTHING_SEEN = HiddenMarkings(1.0, 1.0)


def hidden_markings(
    gray: np.ndarray, hls: np.ndarray, features: np.ndarray, region: RoadRegion, left: LaneLine, right: LaneLine,
    road: RoadAppearance | float, boxes: tuple[tuple[int, int, int, int], ...] = (), maps: SurfaceMaps | None = None,
    curves: tuple[tuple[np.ndarray, np.ndarray], ...] | None = None,
) -> HiddenMarkings:
    """The hidden shares of the expected boundaries (all 1 when no boundary is in view at all). road: the road's
    appearance (``road_appearance`` or ``RoadModel``); a bare grey level (the road reference) is accepted too.
    maps: this frame's ``surface_maps`` (computed here when not given). curves: the expected boundaries as image
    points (rows, columns) when the lane model bends (``ground_lanes.expected_points``); the lines then only say
    where the road lies across each row."""
    maps = maps if maps is not None else surface_maps(gray, hls, features, region)
    if not isinstance(road, RoadAppearance):
        measured = road_appearance(gray, hls, region, left, right, maps)
        road = replace(measured, grey=float(road)) if math.isfinite(road) else measured
    rows = sample_rows(region)
    row_ref = row_references(gray, region, rows, (left, right))  # the same rows for both boundaries
    if curves is None:  # both straight boundaries sampled on every sample row
        v = rows.astype(float)
        curves = tuple((rows, np.rint(line.u_at(v)).astype(np.int64)) for line in (left, right))
    per_side = [hidden_at(maps, region, r, c, road, row_ref, boxes) for r, c in curves]  # each sample on its own
    hidden, n = sum(h for h, _ in per_side), sum(m for _, m in per_side)
    if not n:
        return NOTHING_SEEN  # no boundary expected anywhere in view: nothing of them is seen
    return HiddenMarkings(hidden / n, max(h / m for h, m in per_side if m))
