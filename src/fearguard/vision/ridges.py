"""Is there a painted marking along a candidate boundary? Row by row: a ridge of plausible width with road beside it.

A lane marking, on every image row it crosses, is a *ridge*: a run of marking pixels (``lanes.marking_features``)
bounded by two edges (rising, then falling), as wide as paint can be at that distance — a share of the lane width
at that row (``WIDTH_RANGE``) — with plain road on both sides: its flanks hold no marking pixels, are darker than
the paint by a ratio (``CONTRAST_RATIO``: the same in sun and in shade) and are smooth compared with that contrast.
Noise, random texture, chessboards and the bright gaps between tree shadows fail at least one of these on most
rows, real paint passes on most rows it covers. The share of rows that pass is the boundary's *support*; the run's
edge nearest the lane centre is the boundary's position on that row (``inner_u``), so the lane width does not
jump between the inner and the outer edge of wide tape.

Written by hand (vectorised over rows, O(rows) per scan from per-frame cumulative sums): OpenCV has no
ridge-with-flanks test, and it is a few array operations.
"""

from __future__ import annotations

from dataclasses import dataclass
from functools import lru_cache

import cv2
import numpy as np

from fearguard.vision.exposure import SATURATED_MIN

WIDTH_RANGE = (0.012, 0.12)  # [-] of the lane width at the row: narrowest and widest paint (road lanes: 10-30 cm of 3-3.7 m)
MIN_WIDTH_PX = 1.0  # [px] a ridge is at least this wide (far rows)
MAX_WIDTH_FLOOR = 0.02  # [-] of the image width: a ridge this wide is always plausible (far paint, blurred; a lane-width prior that is off)
SEARCH = 0.03  # [-] of the image width: the run must reach within this of the candidate line
CONTRAST_RATIO = 1.12  # [-] paint is at least this many times brighter than its flanks (illumination invariant), or
#                        clipped (exposure.SATURATED_MIN: glare's veil lifts the road until no ratio fits under the clip)
CONTRAST_MIN = 6.0  # [grey levels] ... and at least this much brighter (sensor noise)
FLANK_PAINT_MAX = 0.25  # [-] share of marking pixels a flank may hold (the road beside paint is plain)
FLANK_ROUGHNESS = 0.45  # [-] flank standard deviation may be at most this share of the paint's contrast
FLANK_GAP_PX = 1  # [px] between the run's edge and its flank (the edge pixel itself is blurred)
MIN_RUN_ROWS = 3  # [rows] paint spans consecutive rows (a dash many): ridges on isolated rows are texture, not paint
SUPPORT_FULL = 0.35  # [-] covering this share of the rows counts as full support (a dashed line covers about this)


@dataclass(frozen=True)
class RidgeScan:
    """Per-row result of scanning along candidate boundaries: one row of each 2-D array per candidate."""

    rows: np.ndarray  # [px] image rows scanned (n,)
    ok: np.ndarray  # bool (candidates, n): a marking-like ridge was found there
    inner_u: np.ndarray  # [px] (candidates, n): the ridge edge nearest the lane centre (NaN where not ok)
    support: np.ndarray  # [0..1] (candidates,): share of rows ok, saturating at SUPPORT_FULL


@dataclass(frozen=True)
class RidgeMaps:
    """Per-frame tables that make every scan O(rows · log width): one stack of integral images (cv2.integral2) — the
    marking mask, then each channel and its square — and, to find the run of marking pixels through a pixel by
    binary search, the row-wise count of non-marking pixels left of each column, offset by row so it is sorted."""

    top_v_px: int
    feat: np.ndarray  # bool, rows top.. of the band
    integrals: np.ndarray  # (1 + 2·channels, rows + 1, width + 1) float64
    gaps_key: np.ndarray  # flat (rows · (width + 1)): non-marking pixels in [0, u) of row r, + r · (width + 1)
    near_pad: int  # [px] columns of False each side of ``feat_padded``: the search window never leaves it
    feat_padded: np.ndarray  # flat (rows · (width + 2·near_pad)): the marking mask, padded

    def near_marking(self, r: np.ndarray, u: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """For band rows r and columns u (int, broadcastable): whether a marking pixel lies within the search distance, and
        the column of the nearest one (ties: the left one; only meaningful where found). Columns outside the image are
        never marking pixels."""
        w, pad = self.feat.shape[1], self.near_pad
        offsets = _preference(_search_px(w))  # nearest first
        u = clamp(u, -pad // 2 - 1, w + pad // 2)  # beyond these the whole window lies in the padding anyway
        near = self.feat_padded.take((r * (w + 2 * pad) + pad + u)[..., None] + offsets)
        return near.any(axis=-1), u + offsets[np.argmax(near, axis=-1)]

    @property
    def paint_integral(self) -> np.ndarray:
        """Integral image of the marking mask (0/1) over the band."""
        return self.integrals[0]

    def runs(self, r: np.ndarray, u: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """First and last column of the run of marking pixels through (band row r, column u) — u a marking pixel."""
        stride = self.feat.shape[1] + 1
        base = r * stride
        k = self.gaps_key[base + u]  # non-marking pixels left of u, + base
        start = np.searchsorted(self.gaps_key, k, "left") - base  # just after the last gap left of u
        end = np.searchsorted(self.gaps_key, k + 1, "left") - base - 2  # just before the first gap right of u
        return start, end


def ridge_maps(channels: tuple[np.ndarray, ...], features: np.ndarray, top_v_px: int, bottom_v_px: int) -> RidgeMaps:
    """The tables for the rows top..bottom of full-size channels (lightness, saturation) and marking mask."""
    band = slice(top_v_px, bottom_v_px + 1)
    feat = features[band] > 0
    h, w = feat.shape
    integrals = np.empty((1 + 2 * len(channels), h + 1, w + 1), np.float64)
    cv2.integral(feat.view(np.uint8), sum=integrals[0], sdepth=cv2.CV_64F)  # written in place: no copies
    for i, c in enumerate(channels):
        cv2.integral2(c[band], sum=integrals[1 + 2 * i], sqsum=integrals[2 + 2 * i], sdepth=cv2.CV_64F, sqdepth=cv2.CV_64F)
    # non-marking pixels in [0, u) of each row, u minus the row's marking pixels there (from the integral: exact in
    # float64), + r · (width + 1); int32: rows · (width + 1) is far below 2³¹
    gaps = np.subtract(integrals[0, :-1], integrals[0, 1:])
    gaps += _row_keys(h, w)
    gaps = gaps.astype(np.int32)
    pad = 2 * _search_px(w) + 1
    padded = np.zeros((h, w + 2 * pad), bool)
    padded[:, pad : pad + w] = feat
    return RidgeMaps(top_v_px, feat, integrals, gaps.ravel(), pad, padded.ravel())


@lru_cache(maxsize=8)
def _row_keys(rows: int, width_px: int) -> np.ndarray:
    """u + r · (width + 1) for r < rows, u ≤ width (float64, read-only): the same every frame, so built once."""
    keys = np.arange(rows * (width_px + 1), dtype=np.float64).reshape(rows, width_px + 1)
    keys.flags.writeable = False
    return keys


def _search_px(width_px: int) -> int:
    """How far from a candidate column a marking pixel is looked for."""
    return max(2, int(SEARCH * width_px))


def _span_sums(integrals: np.ndarray, r: np.ndarray, lo: np.ndarray, hi: np.ndarray) -> np.ndarray:
    """Sums over columns [lo, hi) of band rows r (r: (rows,); lo, hi: (..., rows)), for every layer: (layers, ..., rows).
    One flat ``take`` for all corners of all spans (fancy indexing per corner costs more than the arithmetic)."""
    stride = integrals.shape[2]
    rows = np.array([(r + 1) * stride, r * stride])  # the integral rows below and above each span
    idx = rows.reshape(2, 1, *([1] * (hi.ndim - 1)), -1) + np.array([hi, lo])  # (corner row, hi/lo, ..., points)
    c = np.take(integrals.reshape(integrals.shape[0], -1), idx, axis=1)
    return c[:, 0, 0] - c[:, 0, 1] - c[:, 1, 0] + c[:, 1, 1]


def scan_ridges(
    maps: RidgeMaps, rows: np.ndarray, centre_u: np.ndarray, lane_width_px: np.ndarray, inner_is_left: np.ndarray,
    width_range: tuple[float, float] = WIDTH_RANGE,
) -> RidgeScan:
    """Scan rows (ints, inside the maps' band) around the columns centre_u of every candidate boundary (float,
    (candidates, rows)) for a marking ridge — all candidates in one pass of array operations, whose cost is mostly
    per operation, not per element.

    maps: ``ridge_maps`` of the (smoothed) lightness and the saturation (yellow paint on pale concrete is no lighter
    than the concrete, only more saturated: a ridge must stand out in one of them) and of the marking pixels;
    lane_width_px: the lane width on each row (from the tracked boundaries or a prior); inner_is_left: bool per
    candidate, True for a right boundary (its inner edge is the run's left edge); width_range: paint width as a share
    of the lane width.
    """
    centre_u = np.atleast_2d(centre_u)
    k, n = centre_u.shape
    if n == 0 or k == 0:
        return RidgeScan(rows, np.zeros((k, n), bool), np.zeros((k, n)), np.zeros(k))
    w = maps.feat.shape[1]
    lw = np.maximum(lane_width_px, 4.0)
    rr = rows - maps.top_v_px
    # the marking pixel nearest the candidate column within the search distance (a tie: the left one)
    found, nearest = maps.near_marking(rr[None, :], np.rint(centre_u).astype(np.int64))  # rows broadcast over candidates
    at = np.flatnonzero(found)  # flat (k·n) indices where one was found
    # from here on only those points, as flat arrays
    row_of = at % n
    r, u0 = rr[row_of], nearest.ravel()[at]
    a, b = maps.runs(r, u0)
    width = b - a + 1
    lw_at = lw[row_of]
    fits = (width >= np.maximum(MIN_WIDTH_PX, width_range[0] * lw_at)) & (width <= np.maximum(MAX_WIDTH_FLOOR * w, width_range[1] * lw_at))
    at, r, a, b, width = at[fits], r[fits], a[fits], b[fits], width[fits]
    fw = np.maximum(2, width)
    # np.array of equal-shape arrays is np.stack (axis 0) at about a sixth of its call overhead
    lo, hi = clamp(np.array([a, a - FLANK_GAP_PX - fw, b + FLANK_GAP_PX + 1,  # spans: run, left flank, right flank
                             b + 1, a - FLANK_GAP_PX, b + FLANK_GAP_PX + 1 + fw]), 0, w).reshape(2, 3, -1)
    count = hi - lo
    means = _span_sums(maps.integrals, r, lo, hi) / np.maximum(count, 1)  # (layers, spans, points)
    paint = means[1::2, 0]  # each channel's mean over the run
    clipped = np.zeros(paint.shape, bool)
    clipped[0] = paint[0] >= SATURATED_MIN  # lightness only: glare's veil lifts the road's lightness, not its saturation
    stands_out = None
    for f in (1, 2):  # the flanks
        mean, sq = means[1::2, f], means[2::2, f]
        std = np.sqrt(np.maximum(sq - mean * mean, 0.0))
        contrast = paint - mean
        bright = (paint >= CONTRAST_RATIO * mean) | clipped  # clipped paint: no ratio fits under the clip
        passes = bright & (contrast >= CONTRAST_MIN) & (std <= FLANK_ROUGHNESS * contrast)
        passes &= means[0, f] <= FLANK_PAINT_MAX  # the road beside paint holds (almost) no paint
        passes |= count[f] == 0  # a flank outside the image says nothing (lines leaving sideways)
        stands_out = passes if stands_out is None else stands_out & passes
    good = (count[1] + count[2] > 0) & stands_out.any(axis=0)
    ok = np.zeros(k * n, bool)
    ok[at[good]] = True
    ok = _in_long_runs(ok.reshape(k, n), MIN_RUN_ROWS)
    inner = np.full(k * n, np.nan)
    inner[at] = np.where(np.asarray(inner_is_left)[at // n], a, b)
    inner = np.where(ok, inner.reshape(k, n), np.nan)
    support = np.minimum(1.0, ok.sum(axis=1) / n / SUPPORT_FULL)
    return RidgeScan(rows, ok, inner, support)


@lru_cache(maxsize=4)
def _preference(search: int) -> np.ndarray:
    """Column offsets -search..search, nearest first and left before right: 0, -1, 1, -2, 2, ..."""
    offsets = np.arange(-search, search + 1)
    return offsets[np.argsort(np.abs(offsets), kind="stable")]


def clamp(x: np.ndarray, lo: int, hi: int) -> np.ndarray:
    """np.clip for index arrays, without its per-call dtype-limit lookups (measurably slower on small arrays)."""
    return np.minimum(np.maximum(x, lo), hi)




def _in_long_runs(ok: np.ndarray, min_rows: int) -> np.ndarray:
    """ok (candidates, rows), keeping only runs of at least min_rows consecutive True rows: a morphological opening
    with a min_rows-long line along the rows (erosion marks the windows that are all True, dilation gives each its
    rows back; beyond the ends nothing is True) — two OpenCV calls for all candidates."""
    n = ok.shape[1]
    if min_rows <= 1 or n == 0:
        return ok
    if n < min_rows:
        return np.zeros_like(ok)
    line = np.ones((1, min_rows), np.uint8)
    starts = cv2.erode(ok.view(np.uint8), line, anchor=(0, 0), borderType=cv2.BORDER_CONSTANT, borderValue=0)  # i..i+m-1 all
    return cv2.dilate(starts, line, anchor=(min_rows - 1, 0)).view(bool)  # any window start in i-m+1..i
