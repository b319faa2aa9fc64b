"""Forward-camera renderer: a flat world painted with OpenCV polygons through the CameraModel's pinhole.

This module holds the painting; ``projection.py`` takes world points to fixed-point pixels (near-plane
clipped) and ``exposure.py`` applies the light and the sensor noise to the painted frame.

Per frame: copy the precomputed sky/verge background; draw the road surface (textured through a mask),
lane markings (solid strips and dashes on the ground plane, real widths and dash lengths), tree shadows,
then boxes (cars with a dark underside, a shadow on the ground and two tail lights; obstacles) and QR
boards (the encoder's image warped onto the board's projected quad) from far to near; then exposure
(night, glare, tunnel exit) and sensor noise.
Speed: everything per frame is a handful of cv2 calls on uint8 images; no per-pixel Python.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass

import cv2
import numpy as np

from fearguard.camera import CameraModel
from fearguard.sim.boxes import Box
from fearguard.sim.exposure import Exposure
from fearguard.sim.lighting import LightState
from fearguard.sim.paint_objects import ObjectPainter
from fearguard.sim.projection import Pose, Projector, fill
from fearguard.sim.qr import QrBoard, place_boards
from fearguard.sim.road import Road
from fearguard.sim.scenario_values import Marking, Scenario

ROAD_SAMPLES = 40  # [-] samples of the visible route (denser near the car)
SAMPLE_POWER = 1.8  # [-] spacing exponent: s = s0 + span·(i/N)^p puts most samples near the car
BEHIND_FRACTION = 0.5  # [-] the route is sampled from this share of the road width behind the camera

SKY_TOP_BGR = (215, 175, 135)  # pale blue
SKY_HORIZON_BGR = (232, 222, 212)  # haze near the horizon
VERGE_BGR = (68, 112, 86)  # grass verge, about as light as asphalt in grey (a weak edge, like real roads)
ASPHALT_GREY = 104  # [grey level] dark road surface
PALE_GREY = 168  # [grey level] pale, worn asphalt or concrete
TEXTURE_SIGMA = 5.0  # [grey levels] fine surface texture
PAINT_BGR = {"white": (226, 228, 228), "yellow": (45, 185, 222)}
LANE_DIVIDER = Marking("dashed", "white")  # lines between extra lanes
SHADOW_FACTOR = 0.45  # [-] shade / sunlit brightness under trees
SHADOW_VERTICES = 12  # [-] corners of a shadow blob (radii jittered: ragged, leafy outlines)
TAIL_LIGHT_LIT_BGR = (90, 90, 255)  # tail lights at night or in a tunnel (painted after the exposure)


@dataclass(frozen=True)
class Frame:
    """One rendered frame and the QR payloads readable in it (ground truth)."""

    bgr: np.ndarray
    qr_visible: tuple[str, ...]


class Renderer:
    """Draws the scenario's world as the ego camera sees it."""

    def __init__(self, scenario: Scenario, road: Road, camera: CameraModel, scenery_rng: np.random.Generator,
                 noise_rng: np.random.Generator) -> None:
        """``scenery_rng`` places textures and tree shadows once; ``noise_rng`` draws each frame's sensor noise."""
        rng = scenery_rng
        self.scenario, self.road, self.camera = scenario, road, camera
        self.w, self.h = camera.width_px, camera.height_px
        self.proj = Projector(camera)
        self.far_m = scenario.render_far_m
        self.horizon_v = camera.horizon_v_px()
        spec = road.spec
        self._half_road_m = (spec.lane_width_m / 2 + max(spec.lanes_left, spec.lanes_right) * spec.lane_width_m + spec.shoulder_m)
        self._left_edge_m = spec.lane_width_m / 2 + spec.lanes_left * spec.lane_width_m + spec.shoulder_m
        self._right_edge_m = -(spec.lane_width_m / 2 + spec.lanes_right * spec.lane_width_m + spec.shoulder_m)
        self._background = self._make_background(rng)
        self._asphalt = self._make_texture(ASPHALT_GREY, rng)
        self._pale = self._make_texture(PALE_GREY, rng)
        self._boards: tuple[QrBoard, ...] = tuple(b for g in scenario.qr_boards for b in place_boards(g, spec))
        self._board_s = np.array([b.s_m for b in self._boards], dtype=float)
        self._shadows = [self._make_shadows(i, rng) if z.kind == "shadows" else None for i, z in enumerate(scenario.lighting)]
        # drawn from the scenery generator after the shadows (the order fixes every seeded frame)
        self.exposure = Exposure(self.proj, road, (self._left_edge_m, self._right_edge_m), self._half_road_m, rng, noise_rng)
        self._lines = self._marking_lines()
        self._behind_m = BEHIND_FRACTION * 2 * self._half_road_m
        self._sample_t = np.linspace(0.0, 1.0, ROAD_SAMPLES) ** SAMPLE_POWER
        self._pale_segment = np.array([seg.surface == "pale" for seg in spec.segments])
        self._any_pale = bool(self._pale_segment.any())
        self.objects = ObjectPainter(self.proj, self._boards)

    # -- precomputed layers ----------------------------------------------------------------------
    def _make_background(self, rng: np.random.Generator) -> np.ndarray:
        img = np.empty((self.h, self.w, 3), np.uint8)
        hv = int(np.clip(math.ceil(self.horizon_v), 0, self.h))
        if hv > 0:
            t = np.linspace(0.0, 1.0, hv)[:, None]
            sky = (1 - t) * np.array(SKY_TOP_BGR) + t * np.array(SKY_HORIZON_BGR)
            img[:hv] = sky[:, None, :].astype(np.uint8)
        if hv < self.h:
            rows = self.h - hv
            coarse = rng.normal(0.0, 10.0, (max(2, rows // 6), max(2, self.w // 6), 1)).astype(np.float32)
            blotch = cv2.resize(coarse, (self.w, rows), interpolation=cv2.INTER_LINEAR)[:, :, None]
            fine = rng.normal(0.0, 4.0, (rows, self.w, 1)).astype(np.float32)
            img[hv:] = np.clip(np.array(VERGE_BGR, np.float32) + blotch + fine, 0, 255).astype(np.uint8)
        return img

    def _make_texture(self, grey: int, rng: np.random.Generator) -> np.ndarray:
        noise = rng.normal(0.0, TEXTURE_SIGMA, (self.h, self.w, 1)).astype(np.float32)
        tint = np.array([grey + 2, grey, grey - 1], np.float32)  # asphalt is a hair bluish
        return np.clip(tint + noise, 0, 255).astype(np.uint8)

    def _make_shadows(self, index: int, rng: np.random.Generator) -> tuple[np.ndarray, np.ndarray]:
        """Tree-shadow blobs of one zone: their s (for culling) and world polygons (n, SHADOW_VERTICES, 2)."""
        zone = self.scenario.lighting[index]
        if zone.from_m is not None and zone.to_m is not None:
            s_lo, s_hi = zone.from_m, zone.to_m
        else:
            s_lo, s_hi = -self.far_m, self.road.length_m + self.far_m
        r_lo, r_hi = self.scenario.shadow_radius_m
        lat_lo, lat_hi = self._right_edge_m - 2 * r_hi, self._left_edge_m + 2 * r_hi
        mean_area = math.pi * ((r_lo + r_hi) / 2) ** 2
        count = min(5000, int(zone.density * (s_hi - s_lo) * (lat_hi - lat_lo) / mean_area))
        s = rng.uniform(s_lo, s_hi, count)
        lat = rng.uniform(lat_lo, lat_hi, count)
        radius = rng.uniform(r_lo, r_hi, count)
        angles = np.linspace(0, 2 * math.pi, SHADOW_VERTICES, endpoint=False)[None, :] + rng.uniform(0, 2 * math.pi, (count, 1))
        radii = radius[:, None] * rng.uniform(0.6, 1.2, (count, SHADOW_VERTICES))
        ps = s[:, None] + radii * np.cos(angles)
        pl = lat[:, None] + radii * np.sin(angles)
        x, y = self.road.point_at(ps, pl)
        return s, np.stack([x, y], axis=-1)

    def _marking_lines(self) -> list[tuple[float, str]]:
        """(lateral, which) of every painted line: 'left'/'right' follow the segments, else a fixed Marking."""
        spec = self.road.spec
        lines: list[tuple[float, str]] = [(spec.lane_width_m / 2, "left"), (-spec.lane_width_m / 2, "right")]
        for side, count in ((1.0, spec.lanes_left), (-1.0, spec.lanes_right)):
            for k in range(1, count + 1):
                lines.append((side * (spec.lane_width_m / 2 + k * spec.lane_width_m), "outer" if k == count else "divider"))
        return lines

    def _samples(self, s0: float, s1: float) -> np.ndarray:
        """s samples over [s0, s1], denser near s0, with the segment boundaries inside."""
        s = s0 + (s1 - s0) * self._sample_t
        breaks = self.road.breaks_m
        inner = breaks[(breaks > s0) & (breaks < s1)]
        return np.unique(np.concatenate([s, inner])) if len(inner) else s

    # -- drawing -------------------------------------------------------------------------------
    def render(self, cam_pose: Pose, s_m: float, boxes: Sequence[Box], light: LightState) -> Frame:
        """The frame seen from camera pose (world x, y, yaw rad) at route distance s_m."""
        frame = self._background.copy()
        s0, s1 = s_m - self._behind_m, s_m + self.far_m
        samples = self._samples(s0, s1)
        n = len(samples)
        solid, dashes = self._marking_pieces(s0, s1)
        d = len(dashes)
        boards = np.flatnonzero((self._board_s > s_m) & (self._board_s < s1)) if len(self._boards) else np.empty(0, int)
        dash_s = np.concatenate([dashes[:, 0], 0.5 * (dashes[:, 0] + dashes[:, 1]), dashes[:, 1]]) if d else np.empty(0)
        x, y, h = self.road.pose_at(np.concatenate([samples, dash_s, self._board_s[boards]]))
        sn, cs = np.sin(h), np.cos(h)
        # ground strips: every lateral offset over the shared samples, projected once
        half = self.road.spec.marking_width_m / 2
        lats = np.array([self._right_edge_m, self._left_edge_m, *[v for p in solid for v in (p[2] - half, p[2] + half)]])
        ground = self.proj.to_camera(cam_pose, x[:n] - lats[:, None] * sn[:n], y[:n] + lats[:, None] * cs[:n], 0.0)  # (R, n, 3)
        strips = _Strips(self, ground, samples)
        self._draw_surface(frame, strips, samples)
        by_colour: dict[str, list[np.ndarray | None]] = {"white": [], "yellow": []}
        for k, (a, b, _lat, colour) in enumerate(solid):
            by_colour[colour].append(strips.polygon(2 + 2 * k, 3 + 2 * k, a, b))
        if d:  # each dash: start, middle and end on both edges (6 vertices, bending with arcs)
            xs, ys = x[n : n + 3 * d].reshape(3, d).T, y[n : n + 3 * d].reshape(3, d).T
            ss, cc = sn[n : n + 3 * d].reshape(3, d).T, cs[n : n + 3 * d].reshape(3, d).T
            lo, hi = (dashes[:, 2] - half)[:, None], (dashes[:, 2] + half)[:, None]
            px = np.concatenate([xs - hi * ss, (xs - lo * ss)[:, ::-1]], axis=1)
            py = np.concatenate([ys + hi * cc, (ys + lo * cc)[:, ::-1]], axis=1)
            polys = self.proj.polys_px(self.proj.to_camera(cam_pose, px, py, 0.0))
            for colour_index, poly in zip(dashes[:, 3], polys, strict=True):
                by_colour["yellow" if colour_index else "white"].append(poly)
        for colour, polys in by_colour.items():
            fill(frame, polys, PAINT_BGR[colour])
        self._draw_shadows(frame, cam_pose, light, s0, s1)
        emissive: list[np.ndarray] = []
        board_geo = (x[n + 3 * d :], y[n + 3 * d :], h[n + 3 * d :])
        qr_visible = self.objects.draw(frame, cam_pose, boxes, boards, board_geo, emissive)
        self.exposure.expose(frame, cam_pose, light)
        if light.night > 0.3 or light.tunnel > 0.3:
            fill(frame, emissive, TAIL_LIGHT_LIT_BGR)
        self.exposure.add_noise(frame, light.noise_sigma)
        return Frame(frame, tuple(qr_visible))

    def _draw_surface(self, frame: np.ndarray, strips: _Strips, samples: np.ndarray) -> None:
        if not self._any_pale:
            mask = np.zeros((self.h, self.w), np.uint8)
            fill(mask, [strips.polygon(0, 1, samples[0], samples[-1])], 255)
            cv2.copyTo(self._asphalt, mask, frame)
            return
        pale = self._pale_segment[self.road.segment_index(samples)]
        for texture, selected in ((self._asphalt, ~pale), (self._pale, pale)):
            if not selected.any():
                continue
            mask = np.zeros((self.h, self.w), np.uint8)
            fill(mask, [strips.polygon(0, 1, samples[run[0]], samples[run[-1]]) for run in _runs(selected)], 255)
            cv2.copyTo(texture, mask, frame)

    def _marking_pieces(self, s0: float, s1: float) -> tuple[list[tuple[float, float, float, str]], np.ndarray]:
        """Solid pieces (s_a, s_b, lateral, colour) and dashes (D, 4: s_a, s_b, lateral, 1 if yellow) over [s0, s1]."""
        spec = self.road.spec
        period = spec.dash_length_m + spec.dash_gap_m
        solid: list[tuple[float, float, float, str]] = []
        dashes: list[np.ndarray] = []
        for lateral, which in self._lines:
            for a, b, marking in self._marking_runs(which, s0, s1):
                if marking.style == "solid":
                    solid.append((a, b, lateral, marking.colour))
                elif marking.style == "dashed":
                    start = np.arange(math.floor(a / period), math.floor(b / period) + 1) * period
                    da, db = np.maximum(start, a), np.minimum(start + spec.dash_length_m, b)
                    keep = db > da
                    yellow = 1.0 if marking.colour == "yellow" else 0.0
                    dashes.append(np.column_stack([da[keep], db[keep], np.full(keep.sum(), lateral), np.full(keep.sum(), yellow)]))
        return solid, (np.concatenate(dashes) if dashes else np.empty((0, 4)))

    def _marking_runs(self, which: str, s0: float, s1: float) -> list[tuple[float, float, Marking]]:
        """(s_a, s_b, marking) pieces of one line over [s0, s1]."""
        if which in ("outer", "divider"):
            return [(s0, s1, self.road.spec.outer if which == "outer" else LANE_DIVIDER)]
        segs = self.road.spec.segments
        breaks = self.road.breaks_m
        first, last = int(self.road.segment_index(s0)), int(self.road.segment_index(s1))
        runs = []
        for i in range(first, last + 1):
            a = s0 if i == 0 else max(s0, float(breaks[i]))
            b = s1 if i == len(segs) - 1 else min(s1, float(breaks[i + 1]))
            if b > a:
                runs.append((a, b, segs[i].left if which == "left" else segs[i].right))
        return runs

    def _draw_shadows(self, frame: np.ndarray, pose: Pose, light: LightState, s0: float, s1: float) -> None:
        polys = []
        for i in light.shadow_zones:
            blobs = self._shadows[i]
            if blobs is None:
                continue
            s, world = blobs
            keep = (s > s0 - 1.0) & (s < s1)
            if keep.any():
                pts = world[keep]
                polys.append(self.proj.to_camera(pose, pts[..., 0], pts[..., 1], 0.0))
        if not polys:
            return
        mask = np.zeros((self.h, self.w), np.uint8)
        fill(mask, self.proj.polys_px(np.concatenate(polys)), 255)
        cv2.copyTo(cv2.convertScaleAbs(frame, alpha=SHADOW_FACTOR), mask, frame)


class _Strips:
    """Ground strips over the shared route samples: rows of projected points, two rows per strip."""

    def __init__(self, renderer: Renderer, ground: np.ndarray, samples: np.ndarray) -> None:
        self.r, self.ground, self.samples = renderer, ground, samples
        depth = renderer.proj.depth(ground)
        front = (depth >= renderer.proj.near_m).all(axis=0)
        behind = np.flatnonzero(~front)
        # common case: only the first few samples (behind the camera) are cut; they lie below the image
        self.first = int(behind[-1]) + 1 if len(behind) else 0
        self.simple = len(behind) == 0 or int(behind[-1]) == len(behind) - 1
        self.px = renderer.proj.fixed(ground) if self.simple else None

    def polygon(self, lo_row: int, hi_row: int, s_a: float, s_b: float) -> np.ndarray | None:
        """The strip between two rows over samples in [s_a, s_b]."""
        ia = max(int(np.searchsorted(self.samples, s_a)), self.first if self.simple else 0)
        ib = int(np.searchsorted(self.samples, s_b, side="right"))
        if ib - ia < 2:
            return None
        if self.px is not None:
            return np.concatenate([self.px[hi_row, ia:ib], self.px[lo_row, ia:ib][::-1]])
        poly = np.concatenate([self.ground[hi_row, ia:ib], self.ground[lo_row, ia:ib][::-1]])
        return self.r.proj.polys_px(poly[None])[0]


def _runs(selected: np.ndarray) -> list[tuple[int, int]]:
    """(first, last) sample indices of consecutive selected samples, each run extended by one so strips join."""
    runs, start, n = [], None, len(selected)
    for i, flag in enumerate(selected):
        if flag and start is None:
            start = i
        if (not flag or i == n - 1) and start is not None:
            end = i if flag else i - 1
            lo, hi = max(0, start - 1), min(n - 1, end + 1)
            if hi > lo:
                runs.append((lo, hi))
            start = None
    return runs
