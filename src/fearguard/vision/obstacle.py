"""Anything standing in the ego lane, seen by the camera: a toy duck, a cone, a box, a car — and its ground-plane range.

Inside the lane interior (the expected boundaries, inset by ``INSET`` of the lane width, so the lane's own paint is not
in it) a pixel is *foreign* when its 3-row patch (``occlusion.SurfaceMaps``) does not look like the road
(``occlusion.RoadAppearance``, the model of recent frames): strongly coloured or of another saturation (any hue — paint
is not inside the lane), darker than any shadow, brighter and smoother, or smooth where the road is rough. A row whose
foreign pixels cover ``MIN_SHARE`` of the interior width is an object row; the nearest stretch of ``MIN_ROWS`` such rows
is the object, standing on its lowest row. Its range is the flat-ground range of that row,
D = H / tan(α + arctan((v − v0) / f_y)) (``CameraModel.ground_range_m``), so it needs the camera's mounting height;
it is given from the car's front (``CameraModel.range_ahead_m``).
In the bending lane model's interior, a candidate that enters from the interior's edge and goes on past it is the lane's
edge (tape or verge let in where the edge line went unseen), not an object: ``_edge_runs``.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import cv2
import numpy as np

from fearguard.camera import CameraModel
from fearguard.vision.lanes import LaneLine, RoadRegion
from fearguard.vision.occlusion import (
    ACROSS_LANE,
    BRIGHTER,
    COLOUR_SAT_MIN,
    DARKER,
    FOREIGN_DEV_MIN,
    ROW_DEV,
    SMOOTH_SHARE,
    SMOOTHER_SHARE,
    RoadAppearance,
    SurfaceMaps,
    coloured_unlike_road,
    row_references,
    row_roughness,
)

INSET = 0.15  # [-] of the lane width on each side: the interior searched (the boundaries' paint stays out)
MIN_SHARE = 0.2  # [-] of the interior width: foreign pixels on a row that make it an object row ...
MIN_PX = 3  # [px] ... and at least this many
SHADE_SAT_GATE = 0.6  # [-] of the road's grey: darker patches are not judged by their saturation
MIN_ROWS = 4  # [rows] consecutive object rows that make an object (one row is noise)
CONFIRM_FRAMES = 3  # [frames] over time an object counts once seen this many frames in a row (0.1 s at 30 Hz): a single
#   frame's foreign patch — a tile seam beside a boundary the lane model placed a little off — is no object
CONFIRM_AGREE = 0.25  # [-] ... each sighting's range within this share of the one before (the same object, approaching)
SPILL_M = 0.03  # [m] read as flat ground at its row: a foreign run that reaches the lane interior's edge and goes on this
#   far past it, over ground that is not road (foreign, or the white edge line's paint; yellow paint stops it), spills
#   out of the lane on that row ...
SPILL_FILL = 0.75  # [-] ... (this share of the pixels there: the patch maps blur a tape's edges) ...
SPILL_SHARE = 0.5  # [-] ... and a candidate spilling out on one side on this share of its rows is the lane's edge (tape
#   or verge the interior let in where the lane model did not see the edge line), not an object standing in the lane
EDGE_PASSES = 3  # [-] the search looks again without such an edge at most this often (then what is left is judged as it is)
BAND_COVER = 0.8  # [-] of the interior width: a band of foreign rows this full on most of its rows spans the lane ...
BAND_ROWS_FULL = 0.8  # [-] ... (this share of its rows) ...
BAND_DEPTH = 1.0  # [-] ... and no deeper on the ground than this × the interior's width there is paint across the lane (a stop
#   line, a crossing's edge), not an object: anything standing projects far deeper onto the ground plane than it is wide
STRIP_THIN = 0.35  # [-] a stretch whose foreign patch lies on the ground as a strip no thicker than this × its length ...
STRIP_ACROSS_DEG = 45.0  # [deg] ... running across the way (within this of square to the heading; anything standing
#   projects along the rays from the camera, which run ahead) and as long as BAND_COVER of the interior is a line seen
#   askew: each row of it covers only part of the width (robotarium2: a red stop line crossed at 15 deg)


PATH_CAR_WIDTHS = 1.25  # [-] a route's path is searched this many car widths wide (after the INSET): its swept path with an
#   eighth of a car width to spare each side


@dataclass(frozen=True)
class RoutePath:
    """Where a route steers the car, for the object search when no lane boundary is seen: the arc of curvature
    ``curvature_per_m`` (+ = left) from the camera, tangent to its heading, searched PATH_CAR_WIDTHS × ``width_m`` wide.

    Without it the search looks along the straight lane prior (``lanes.default_lines``): turning into a roundabout on
    its route (MetaDrive), the car read the central island straight ahead as an object in its path at 10.9 m and stopped
    in the roundabout's mouth."""

    curvature_per_m: float
    width_m: float

    def bounds_px(self, camera: CameraModel, region: RoadRegion, scale: float, reach_m: float = math.inf) -> tuple[np.ndarray, np.ndarray]:
        """Per road row of the working image: the (left, right) columns of a lane whose interior (INSET of its width
        inside each side) is the path; NaN on rows whose ground lies beyond ``reach_m`` from the camera (how far the route's
        steering is known to hold: its aim point; past it a roundabout's S-bend leaves the arc), beyond a half turn, or in
        the sky."""
        rows = np.arange(region.top_v_px, region.bottom_v_px + 1, dtype=np.float64)
        x = np.array([camera.ground_range_m(float(v)) or math.nan for v in (rows + 0.5) * scale])
        k = self.curvature_per_m
        turned = np.abs(k) * x
        ok = np.isfinite(x) & (turned < 1.0) & (x <= reach_m)
        x = np.where(ok, x, 1.0)
        centre = k * x * x / (1.0 + np.sqrt(1.0 - np.minimum(turned, 0.999) ** 2))  # the arc's lateral offset, stably
        half = 0.5 * PATH_CAR_WIDTHS * self.width_m / (1.0 - 2.0 * INSET)
        u_left, _, front_l = camera.project_ground(x, centre + half)
        u_right, _, front_r = camera.project_ground(x, centre - half)
        keep = ok & front_l & front_r
        return np.where(keep, u_left / scale, np.nan), np.where(keep, u_right / scale, np.nan)


@dataclass(frozen=True)
class Obstacle:
    """An object in the ego lane: its columns and the row it stands on (frame pixels), bearing and range."""

    u_left_px: float
    u_right_px: float
    v_bottom_px: float
    bearing_deg: float
    range_m: float | None  # None without the camera's mounting height


def foreign_mask(
    maps: SurfaceMaps, road: RoadAppearance, columns: slice = slice(None), *, smooth_objects: bool = True,
    rows_alike: tuple[np.ndarray, np.ndarray, np.ndarray] | None = None, smoother: float = SMOOTHER_SHARE,
) -> np.ndarray:
    """bool over the maps' band (those columns): patches that do not look like the road (any colour, any size).

    ``smooth_objects=False``: a patch smoother than the road but of its grey and colour is not foreign. On a tiled
    floor (Duckietown's curve tiles are ~3× rougher than its straight ones) that is the next tile, not an object; the
    objects there are coloured (ducks, cones), dark or pale. A smooth object of the road's own grey is then missed:
    it is the range sensor's to see.

    ``rows_alike``: each band row's grey across the road (or the lane), whether the row is one surface
    (``occlusion.row_references``) and its roughness (``occlusion.row_roughness``): on such a row an uncoloured patch
    of the row's grey and no smoother than SMOOTH_SHARE of the row's roughness is road — smooth asphalt ahead of rough
    concrete, a shadow across the road — as occlusion judges the boundaries' samples; a box of the road's grey is still
    smoother than its row. ``smoother``: a brighter patch is foreign when smoother than this share of the road's
    roughness."""
    grey, sat, rough = maps.grey[:, columns], maps.saturation[:, columns], maps.roughness[:, columns]
    ref = max(road.grey, 1.0)
    off = np.abs(grey - ref) >= FOREIGN_DEV_MIN
    lit = grey >= SHADE_SAT_GATE * ref  # HLS saturation of dark pixels is unstable: a shadow is no coloured object
    coloured = lit & coloured_unlike_road(sat, maps.hue[:, columns], road)
    foreign = off & (grey < DARKER * ref)
    if road.textured:
        if smooth_objects:
            foreign |= rough < SMOOTH_SHARE * road.roughness
        foreign |= off & (grey > BRIGHTER * ref) & (rough < smoother * road.roughness)
    if rows_alike is not None:
        row_grey, uniform, row_rough = (r[:, None] for r in rows_alike)
        like_row = uniform & (np.abs(grey - row_grey) <= np.maximum(FOREIGN_DEV_MIN, ROW_DEV * row_grey))
        foreign &= ~(like_row & ~(rough < SMOOTH_SHARE * row_rough))  # NaN roughness: never smoother
    return foreign | coloured


@dataclass(frozen=True)
class LaneSearch:
    """What the search of the ego lane found: the nearest object, and the nearest band of paint across the lane."""

    obstacle: Obstacle | None
    stop_line_m: float | None = None  # [m] ground range to the near edge of a painted band across the lane (a stop line)


def detect_obstacle(
    maps: SurfaceMaps, road: RoadAppearance, region: RoadRegion, left: LaneLine, right: LaneLine, camera: CameraModel,
    scale: float, *, interior: np.ndarray | None = None, smooth_objects: bool = True, edge_paint: np.ndarray | None = None,
) -> Obstacle | None:
    """The nearest object in the ego lane of a working image (None when the lane interior looks like road)."""
    return search_lane(maps, road, region, left, right, camera, scale, interior=interior, smooth_objects=smooth_objects,
                       edge_paint=edge_paint).obstacle


def search_lane(
    maps: SurfaceMaps, road: RoadAppearance, region: RoadRegion, left: LaneLine, right: LaneLine, camera: CameraModel,
    scale: float, *, interior: np.ndarray | None = None, smooth_objects: bool = True, edge_paint: np.ndarray | None = None,
    bounds: tuple[np.ndarray, np.ndarray] | None = None, within: tuple[np.ndarray, np.ndarray] | None = None,
) -> LaneSearch:
    """The nearest object in the ego lane of a working image, and the nearest stop line (a painted band across it).

    The interior lies between the straight boundaries, inset by INSET of the lane width — or between ``bounds`` (each
    road row's left and right column, NaN: nothing searched there: ``RoutePath.bounds_px``) — or, when the lane model
    bends, is given: ``interior``, bool over the road rows (``ground_lanes.lane_interior``). ``within``: the route's path
    (as ``bounds``): the lane is searched only where the route takes the car too (rows where the path is NaN, beyond its
    aim point, are searched across the lane) — the caller gives it for a lane seen on one side only, whose other side is
    a guess: at a junction the interior extended from one boundary takes in the crossing road's stop line, paint beside
    the car's way. ``smooth_objects``: see ``foreign_mask``."""
    line_m: float | None = None
    rows = np.arange(region.top_v_px, region.bottom_v_px + 1)
    if interior is None:
        if bounds is None:
            a, b = left.u_at(rows.astype(float)), right.u_at(rows.astype(float))
        else:
            a, b = np.nan_to_num(bounds[0], nan=0.0), np.nan_to_num(bounds[1], nan=0.0)
        c0, c1, inside, width = _inset_interior(a, b, region.width_px)
        if within is not None:
            inside = inside & _path_mask(within, region.width_px)[:, c0:c1]
            width = inside.sum(axis=1)
        foreign = foreign_mask(maps, road, slice(c0, c1), smooth_objects=smooth_objects) & inside
    else:
        spans = np.flatnonzero(interior.any(axis=0))
        c0, c1 = (int(spans[0]), int(spans[-1]) + 1) if len(spans) else (0, 0)  # only the columns the interior covers
        inside = interior[:, c0:c1] if within is None else interior[:, c0:c1] & _path_mask(within, region.width_px)[:, c0:c1]
        width = inside.sum(axis=1)
        every = foreign_mask(maps, road, smooth_objects=smooth_objects)  # the whole width: the edge test looks beyond it
        foreign = every[:, c0:c1] & inside
    for k in range(EDGE_PASSES + 1):
        count = foreign.sum(axis=1)
        hit = (width > 0) & (count >= np.maximum(MIN_PX, MIN_SHARE * width))
        bottom = _lowest_stretch_end(hit, MIN_ROWS)
        for _ in range(EDGE_PASSES):  # painted bands across the lane are skipped: the search goes on beyond them
            band_top = None if bottom is None else _painted_band(hit, count, width, bottom, rows, camera, scale)
            askew = band_top is None and bottom is not None
            if askew:  # paint seen askew (no row full) is skipped too
                band_top = _painted_strip(foreign, hit, width, bottom, rows, c0, camera, scale)
            if band_top is None or bottom is None:
                break
            on_band = foreign[band_top : bottom + 1]
            band = maps.grey[band_top : bottom + 1, c0:c1][on_band]
            # paint is brighter than the road (a shadow is not); seen askew only a red line is a stop line: a curve's
            # white outer tape runs across the view at its entry
            line = not askew or _red_share(maps, band_top, bottom, c0, c1, on_band) >= 0.5
            if line_m is None and line and band.size and float(band.mean()) > road.grey:
                line_m = camera.range_ahead_m((rows[bottom] + 1.0) * scale)
            hit[band_top : bottom + 1] = False
            bottom = _lowest_stretch_end(hit, MIN_ROWS)
        if bottom is None:
            return LaneSearch(None, line_m)
        if interior is None or k == EDGE_PASSES:
            break
        edge = _edge_runs(maps, every, interior, edge_paint, hit, bottom, (c0, c1), camera, scale)
        if edge is None:
            break
        foreign &= ~edge  # the lane's edge let in: look again without it (an object may stand beside it)
    u = c0 + np.flatnonzero(foreign[bottom - MIN_ROWS + 1 : bottom + 1].any(axis=0))
    v_frame = (rows[bottom] + 1.0) * scale  # the object stands on the lower edge of its lowest row
    u_left, u_right = u.min() * scale, (u.max() + 1.0) * scale
    range_m = camera.range_ahead_m(v_frame)
    return LaneSearch(Obstacle(float(u_left), float(u_right), float(v_frame), camera.bearing_deg(0.5 * (u_left + u_right)),
                               range_m if range_m is not None and math.isfinite(range_m) else None), line_m)


def _edge_runs(
    maps: SurfaceMaps, every: np.ndarray, interior: np.ndarray, edge_paint: np.ndarray | None, hit: np.ndarray,
    bottom: int, columns: tuple[int, int], camera: CameraModel, scale: float,
) -> np.ndarray | None:
    """Is the candidate ending on row ``bottom`` the lane's own edge rather than an object standing in the lane? Then
    the foreign runs it is made of at that edge (bool over the band rows and the searched ``columns`` [c0, c1)), else
    None. ``every``: ``foreign_mask`` over the band's whole width (the ground beyond the interior's edge is judged too).

    An object standing in the lane is bounded inside it: on its rows the road shows on both sides of it. Where the lane
    model did not see the edge line (the next tile's tape under another tint, a fit that strays at a tape corner) the
    interior can take in the tape and the verge beyond it: flat ground that enters from the interior's edge and goes on
    past it. So a row *spills* when its foreign run reaches one lateral edge of the interior (not both: an object wider
    than the lane, a car, reaches both; the picture's border is no edge of the lane) and the ground beyond that edge
    goes on foreign, or white edge-line paint (``edge_paint``), for SPILL_M (SPILL_FILL of it), read as flat ground at
    that row. Yellow paint and road stop it: a yellow duck may stand by the centre line, and one in the lane leaves the
    road beside it. A candidate spilling on one side on SPILL_SHARE of its rows (those not covered from edge to edge;
    a row whose ground beyond lies outside the picture counts as not spilling) is that side's edge: its runs at that
    edge, and where the interior meets the picture's border on that side, its runs there too, are returned."""
    top = bottom
    while top > 0 and hit[top - 1]:
        top -= 1
    width_px = interior.shape[1]
    spilled: dict[bool, list[int]] = {True: [], False: []}  # rows spilling at the left edge / at the right edge
    judged = 0  # rows not covered from edge to edge (those say nothing about a side)
    runs: dict[tuple[int, bool], tuple[int, int]] = {}  # (row, left?) -> the edge run's columns [lo, hi)
    for i in range(top, bottom + 1):
        cols = np.flatnonzero(interior[i])
        x = camera.ground_range_m((maps.top_v_px + i + 0.5) * scale)
        if len(cols) == 0 or x is None:
            continue
        a0, a1 = int(cols[0]), int(cols[-1])
        foreign = every[i]
        touch_left, touch_right = bool(foreign[a0]), bool(foreign[a1])  # a run reaches that end of the interior's row
        at_left, at_right = touch_left and a0 > 0, touch_right and a1 < width_px - 1  # ... an edge of the lane, not the
        if at_left and at_right:  # picture's border
            continue  # as wide as the interior: says nothing about a side
        judged += 1
        if touch_left == touch_right and not (at_left or at_right):
            continue  # bounded inside the interior, or from border to border of the picture
        left_side = at_left or (touch_left and not at_right)
        run = foreign[a0 : a1 + 1] & interior[i, a0 : a1 + 1]
        n = len(run) if run.all() else int(np.argmin(run if left_side else run[::-1]))  # the run's width from that end
        runs[(i, left_side)] = (a0, a0 + n) if left_side else (a1 + 1 - n, a1 + 1)
        if not (at_left or at_right):
            continue  # it runs out of the picture there: the edge's continuation, if any, is not seen
        m_per_px = _lateral_m_per_px(camera, x, scale)  # lateral ground per px there
        reach = max(1, math.ceil(SPILL_M / m_per_px))
        lo, hi = (a0 - reach, a0) if left_side else (a1 + 1, a1 + 1 + reach)
        if lo < 0 or hi > width_px:
            continue  # beyond the edge lies outside the picture: unknown
        pi = maps.paint_integral  # the marking pixels of that row, lo..hi-1
        paint = np.diff(pi[i + 1, lo : hi + 1] - pi[i, lo : hi + 1]) > 0
        white = edge_paint[i, lo:hi] if edge_paint is not None else np.zeros(hi - lo, bool)
        goes_on = (foreign[lo:hi] & ~(paint & ~white)) | white  # yellow paint (a marking, not white) stops it
        if goes_on.mean() >= SPILL_FILL:
            spilled[left_side].append(i)
    side = len(spilled[True]) >= len(spilled[False])
    if not spilled[side] or len(spilled[side]) < SPILL_SHARE * judged:
        return None
    c0, c1 = columns
    edge = np.zeros((interior.shape[0], c1 - c0), bool)
    for (i, left_side), (lo, hi) in runs.items():
        if left_side == side:
            edge[i, lo - c0 : hi - c0] = True
    return edge


def _painted_band(hit: np.ndarray, count: np.ndarray, width: np.ndarray, bottom: int, rows: np.ndarray, camera: CameraModel,
                  scale: float) -> int | None:
    """The first row of the stretch of object rows ending at ``bottom`` when it is paint lying across the lane (a stop line):
    it fills the interior's width and is shallow on the ground plane. None when it may stand (or without a mounting height).
    Its first and last rows are where its edges cross the pixel rows — on a line seen a few degrees askew they cover only
    part of the width (TTIC_ripltown: a red line 0.14 m ahead, 6 of its 8 rows full) — so with three rows or more only
    the rows between them are judged full or not."""
    top = bottom
    while top > 0 and hit[top - 1]:
        top -= 1
    full = count[top : bottom + 1] >= BAND_COVER * np.maximum(width[top : bottom + 1], 1)
    full = full[1:-1] if len(full) >= 3 else full
    near, far = camera.ground_range_m((rows[bottom] + 1.0) * scale), camera.ground_range_m(rows[top] * scale)
    if near is None or far is None or not (math.isfinite(near) and math.isfinite(far)) or full.mean() < BAND_ROWS_FULL:
        return None
    interior_m = float(width[bottom]) * scale * near / camera.fx_px  # flat-ground width of the interior at the band
    return top if far - near <= BAND_DEPTH * interior_m else None


RED_HUES = (10, 170)  # [OpenCV hue 0..180] at most the first or at least the second: red (Duckietown's stop lines)


def _lateral_m_per_px(camera: CameraModel, x_m: float | np.ndarray, scale: float) -> float | np.ndarray:
    """Metres of flat ground across the view per working-image pixel at ground range ``x_m`` (``scale``: frame px per
    working px); a mounting height is assumed known (1 m without one, as the callers' guards make moot)."""
    pitch = math.radians(camera.pitch_deg)
    height = camera.mount_height_m if camera.mount_height_m is not None else 1.0
    return (x_m * math.cos(pitch) + height * math.sin(pitch)) * scale / camera.fx_px


def _red_share(maps: SurfaceMaps, top: int, bottom: int, c0: int, c1: int, on: np.ndarray) -> float:
    """Share of the band's pixels (``on``: bool over rows top..bottom, columns c0..c1) that are coloured red."""
    hue = maps.hue[top : bottom + 1, c0:c1][on]
    sat = maps.saturation[top : bottom + 1, c0:c1][on]
    red = ((hue <= RED_HUES[0]) | (hue >= RED_HUES[1])) & (sat >= COLOUR_SAT_MIN)
    return float(red.mean()) if red.size else 0.0


def _painted_strip(foreign: np.ndarray, hit: np.ndarray, width: np.ndarray, bottom: int, rows: np.ndarray, c0: int,
                   camera: CameraModel, scale: float) -> int | None:
    """The first row of the patch ending the stretch of object rows at ``bottom`` (the largest connected foreign patch on
    its lowest row; ``foreign``: bool over the road rows and the searched columns from ``c0``) when it lies on the
    ground as a thin strip across the way: paint seen askew, which ``_painted_band`` misses because no row is full.
    None when it may stand (or without a mounting height)."""
    top = bottom
    while top > 0 and hit[top - 1]:
        top -= 1
    if camera.mount_height_m is None or bottom - top + 1 < MIN_ROWS:
        return None
    patch = foreign[top : bottom + 1].astype(np.uint8)
    n, labels = cv2.connectedComponents(patch, connectivity=8)
    if n < 2:
        return None
    on_bottom = labels[-1][labels[-1] > 0]
    if on_bottom.size == 0:
        return None
    ii, uu = np.nonzero(labels == np.bincount(on_bottom).argmax())
    row_x = [camera.ground_range_m((v + 0.5) * scale) for v in rows[top : bottom + 1]]
    if any(x is None for x in row_x):
        return None
    x = np.array(row_x, dtype=np.float64)[ii]
    y = -((c0 + uu + 0.5) * scale - camera.cx_px) * _lateral_m_per_px(camera, x, 1.0)
    pts = np.column_stack([x, y])
    centred = pts - pts.mean(axis=0)
    _, _, axes = np.linalg.svd(centred, full_matrices=False)
    along, across = centred @ axes[0], centred @ axes[1]
    length = float(np.percentile(along, 98) - np.percentile(along, 2))
    thick = float(np.percentile(across, 98) - np.percentile(across, 2))
    lane_m = float(np.median(width[top : bottom + 1])) * _lateral_m_per_px(camera, float(np.median(x)), scale)
    square = abs(float(axes[0][0])) <= math.sin(math.radians(STRIP_ACROSS_DEG))  # the strip's direction vs the heading (x)
    # its own first row, not the stretch's: an object standing beyond the line (another patch) keeps its rows
    return top + int(ii.min()) if square and thick <= STRIP_THIN * length and length >= BAND_COVER * lane_m else None


def lane_hidden_beyond(
    gray: np.ndarray, maps: SurfaceMaps, road: RoadAppearance, region: RoadRegion, left: LaneLine, right: LaneLine,
    boxes: tuple[tuple[int, int, int, int], ...] = (),
) -> float:
    """The share of the lane's length (road-region rows, from the object's lowest row to the region's top) hidden behind
    the nearest object standing in the lane interior, for a camera without a mounting height (no range, so
    ``search_lane`` does not run): found as ``search_lane`` finds one, by foreign patches over ``MIN_SHARE`` of a row
    and ``MIN_ROWS`` rows. 0 when the interior looks like road (``road``: the road model's appearance). What is
    foreign here, and why it is stricter than for ``search_lane`` (docs/perception.md, "occlusion"):
    - coloured, darker than any shadow, or brighter and smoother than SMOOTH_SHARE of the road's roughness (a white
      body, a box); smooth alone is not enough (sunlit or wet asphalt is as smooth as a grey box);
    - not of its row's grey and texture on a row that is one surface across the lane (``foreign_mask``'s
      ``rows_alike`` over ``occlusion.ACROSS_LANE``): the whole road turning brighter under an open sky, while the road
      model lags a second behind, stays road;
    - not paint (the maps' marking pixels), not inside a known vehicle's box (the lead: ranged and followed)."""
    rows = np.arange(region.top_v_px, region.bottom_v_px + 1)
    a, b = left.u_at(rows.astype(float)), right.u_at(rows.astype(float))
    c0, c1, inside, width = _inset_interior(np.minimum(a, b), np.maximum(a, b), region.width_px)  # lines that cross: as they lie
    if c1 <= c0:
        return 0.0
    pi = maps.paint_integral
    paint = (pi[1:, c0 + 1 : c1 + 1] - pi[:-1, c0 + 1 : c1 + 1] - pi[1:, c0:c1] + pi[:-1, c0:c1]) > 0  # each pixel's own
    for x, y, w, h in boxes:
        inside[max(0, y - region.top_v_px) : max(0, y + h - region.top_v_px), max(0, x - c0) : max(0, x + w - c0)] = False
    need = np.maximum(MIN_PX, MIN_SHARE * width)
    judged = (inside & ~paint)[:, ::2]
    bottom = None
    alike = None
    for _ in range(2):  # the rows' own references only when some stretch of rows is a candidate (a clean road: none)
        foreign = foreign_mask(maps, road, slice(c0, c1, 2), smooth_objects=False, rows_alike=alike, smoother=SMOOTH_SHARE)
        counted = 2 * (foreign & judged).sum(axis=1)  # every second column: the patches are 13 columns wide
        bottom = _lowest_stretch_end((width > 0) & (counted >= need), MIN_ROWS)
        if bottom is None or alike is not None:
            break
        lane = (left, right)
        alike = (*row_references(gray, region, rows, lane, ACROSS_LANE), row_roughness(maps, region, rows, lane, ACROSS_LANE))
    return 0.0 if bottom is None else (bottom + 1) / len(rows)


def _inset_interior(a: np.ndarray, b: np.ndarray, width_px: int) -> tuple[int, int, np.ndarray, np.ndarray]:
    """The lane interior between each row's left and right column (a, b), INSET of the lane width inside each: the
    columns [c0, c1) some row's interior covers, bool (rows, c1 − c0) inside it, and each row's interior width."""
    inset = INSET * (b - a)
    lo = np.clip(np.ceil(a + inset), 0, width_px).astype(np.int64)
    hi = np.clip(np.floor(b - inset), 0, width_px).astype(np.int64)
    c0, c1 = int(lo.min()), int(max(hi.max(), lo.min()))  # only the columns some row's interior covers are judged
    cols = np.arange(c0, c1)[None, :]
    return c0, c1, (cols >= lo[:, None]) & (cols < hi[:, None]), np.maximum(hi - lo, 0)


def _path_mask(bounds: tuple[np.ndarray, np.ndarray], width_px: int) -> np.ndarray:
    """bool (road rows, width_px): inside the route's path (its bounds inset as a lane's); every column on rows where
    the path is not known (NaN)."""
    a, b = bounds
    known = np.isfinite(a) & np.isfinite(b)
    c0, c1, inside, _ = _inset_interior(np.where(known, a, 0.0), np.where(known, b, 0.0), width_px)
    out = np.zeros((len(a), width_px), bool)
    out[:, c0:c1] = inside
    out[~known] = True
    return out


def _lowest_stretch_end(hit: np.ndarray, min_rows: int) -> int | None:
    """Index of the last row of the lowest stretch of ≥ min_rows consecutive True rows, or None."""
    change = np.diff(np.concatenate([[0], hit.astype(np.int8), [0]]))
    first, after = np.flatnonzero(change == 1), np.flatnonzero(change == -1)  # each stretch's first row, one past its last
    long = after[after - first >= min_rows]
    return int(long[-1]) - 1 if len(long) else None


class ObstacleTrack:
    """An object in the lane is believed once CONFIRM_FRAMES consecutive frames saw it at consistent ranges."""

    def __init__(self) -> None:
        self._last: Obstacle | None = None
        self._run = 0

    def update(self, seen: Obstacle | None) -> Obstacle | None:
        last = self._last
        same = seen is not None and last is not None and (
            seen.range_m is None or last.range_m is None or abs(seen.range_m - last.range_m) <= CONFIRM_AGREE * last.range_m)
        self._run = 0 if seen is None else (self._run + 1 if same else 1)
        self._last = seen
        return seen if self._run >= CONFIRM_FRAMES else None
