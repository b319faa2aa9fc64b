"""Occlusion: the share of the expected lane-marking region that something foreign hides.

Definition (measurable, see docs/perception.md): the expected marking region is a band along each
expected boundary (tracked, else detected, else a default lane) sampled every ``ROW_STEP`` rows from
the road region's top to its bottom. A sample is *hidden* when the pixels at it are neither road nor
paint: their median grey differs from the road reference by more than ``FOREIGN_DEV`` (relative, with
an absolute floor) or they are strongly coloured but not yellow (car paint), and there is no marking
pixel in the band. Samples inside a known vehicle box are hidden too. occlusion = hidden / samples.
Road-like means close to the road reference of the bottom rows (the road just ahead) *or* to the road
across the same row (so pale concrete after dark asphalt, or a shadow across the whole road, is road).
"""

from __future__ import annotations

import numpy as np

from fearguard.vision.lanes import LaneLine, RoadRegion

ROW_STEP = 2  # [px] sample every this many rows of the working image
BAND = 0.02  # [-] of the width: half-width of the band around an expected boundary
FOREIGN_DEV = 0.5  # [-] relative deviation of the median grey from the road reference that is not road ...
FOREIGN_DEV_MIN = 45.0  # [grey levels] ... and at least this absolute deviation
COLOUR_SAT_MIN = 110  # [0..255] HLS saturation of car paint (yellow paint excluded by hue)
ROW_SAMPLES = 15  # [-] points across the road (ego lane ± a lane width) that give a row's road grey
REFERENCE_ROWS = 0.15  # [-] of the region's height: bottom rows whose lane interior gives the road reference
DEFAULT_HALF_WIDTH = 0.32  # [-] of the width: default lane's half-width at the bottom row (dash-cam, centred)


def default_lines(region: RoadRegion) -> tuple[LaneLine, LaneLine]:
    """A centred lane meeting at the top of the road region: the prior when nothing is known."""
    w, top, bottom = region.width_px, region.top_v_px, region.bottom_v_px
    vp_v = top - 0.04 * region.height_px
    lines = []
    for u_bottom in ((0.5 - DEFAULT_HALF_WIDTH) * w, (0.5 + DEFAULT_HALF_WIDTH) * w):
        slope = (u_bottom - 0.5 * w) / max(1.0, bottom - vp_v)
        lines.append(LaneLine(slope, u_bottom - slope * bottom, 0.0, 0))
    return lines[0], lines[1]


def road_reference(gray: np.ndarray, region: RoadRegion, left: LaneLine, right: LaneLine) -> float:
    """Median grey of the lane interior in the bottom rows of the region (the road just ahead)."""
    bottom = region.bottom_v_px
    top = max(region.top_v_px, int(bottom - REFERENCE_ROWS * (bottom - region.top_v_px)))
    values = []
    for v in range(top, bottom + 1, ROW_STEP):
        a, b = left.u_at(v), right.u_at(v)
        lo, hi = int(max(0, min(a, b) + 0.15 * abs(b - a))), int(min(region.width_px, max(a, b) - 0.15 * abs(b - a)))
        if hi > lo:
            values.append(gray[v, lo:hi])
    if not values:
        return float(np.median(gray[top : bottom + 1]))
    return float(np.median(np.concatenate(values)))


def row_references(gray: np.ndarray, region: RoadRegion, rows: np.ndarray, interior: tuple[LaneLine, LaneLine]) -> np.ndarray:
    """Median grey across the road on each row: the ego lane and a lane width either side (in the image only),
    so one vehicle covering the ego lane or a neighbour cannot become the row's idea of road."""
    a, b = interior[0].u_at(rows.astype(float)), interior[1].u_at(rows.astype(float))
    frac = np.linspace(-0.9, 1.9, ROW_SAMPLES)
    cols = np.rint(a[:, None] + frac[None, :] * (b - a)[:, None])
    inside = (cols >= 0) & (cols < region.width_px)
    values = gray[rows[:, None], np.clip(cols, 0, region.width_px - 1).astype(np.int64)].astype(float)
    # median of the in-image samples per row (np.nanmedian goes through masked arrays: 10× slower here)
    ordered = np.sort(np.where(inside, values, np.inf), axis=1)
    n = inside.sum(axis=1)
    lo = np.maximum(n - 1, 0) // 2
    r = np.arange(len(rows))
    med = 0.5 * (ordered[r, lo] + ordered[r, np.where(n % 2 == 0, n // 2, lo)])
    return np.where(n > 0, med, np.nan)


def sample_rows(region: RoadRegion) -> np.ndarray:
    """The working-image rows the expected marking region is sampled on."""
    return np.arange(region.top_v_px, region.bottom_v_px + 1, ROW_STEP)


def hidden_samples(
    gray: np.ndarray, hls: np.ndarray, features: np.ndarray, region: RoadRegion, line: LaneLine, reference: float,
    row_ref: np.ndarray, boxes: tuple[tuple[int, int, int, int], ...] = (),
) -> tuple[int, int]:
    """(hidden, total) samples along one expected boundary (vectorised over rows); row_ref: row_references on sample_rows."""
    half = max(2, int(BAND * region.width_px))
    rows = sample_rows(region)
    centre = np.rint(line.u_at(rows.astype(float))).astype(np.int64) if len(rows) else rows
    offsets = np.arange(-half, half + 1)
    cols = centre[:, None] + offsets[None, :]
    inside = (cols >= 0) & (cols < region.width_px)
    seen = inside.any(axis=1)  # rows where the band is in the image at all
    if not seen.any():
        return 0, 0
    rows, cols, inside, row_ref = rows[seen], cols[seen], inside[seen], row_ref[seen]
    clipped = np.clip(cols, 0, region.width_px - 1)  # a band running off the image repeats its edge pixel
    r = rows[:, None]
    paint = (features[r, clipped] > 0) & inside
    dev = max(FOREIGN_DEV_MIN, FOREIGN_DEV * reference)
    grey = np.median(gray[r, clipped], axis=1)
    row_dev = np.maximum(FOREIGN_DEV_MIN, FOREIGN_DEV * row_ref)
    foreign = (np.abs(grey - reference) > dev) & (np.abs(grey - row_ref) > row_dev)
    sat = np.median(hls[r, clipped, 2], axis=1)
    med_hue = np.median(hls[r, clipped, 0], axis=1)
    foreign |= (sat >= COLOUR_SAT_MIN) & ~((med_hue >= 14) & (med_hue <= 40))
    hidden = foreign & ~paint.any(axis=1)
    u = centre[seen]
    for x, y, w, h in boxes:
        hidden |= (u >= x) & (u < x + w) & (rows >= y) & (rows < y + h)
    return int(hidden.sum()), len(rows)


def occlusion(
    gray: np.ndarray, hls: np.ndarray, features: np.ndarray, region: RoadRegion, left: LaneLine, right: LaneLine,
    reference: float, boxes: tuple[tuple[int, int, int, int], ...] = (),
) -> float:
    """Occlusion 0..1 over both expected boundaries (1 when no boundary is in view at all)."""
    row_ref = row_references(gray, region, sample_rows(region), (left, right))  # the same rows for both boundaries
    h_l, n_l = hidden_samples(gray, hls, features, region, left, reference, row_ref, boxes)
    h_r, n_r = hidden_samples(gray, hls, features, region, right, reference, row_ref, boxes)
    n = n_l + n_r
    return float((h_l + h_r) / n) if n else 1.0
