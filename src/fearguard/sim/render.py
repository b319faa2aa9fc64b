"""Forward-camera renderer: a flat world drawn with OpenCV polygons through the CameraModel's pinhole.

Projection is ``CameraModel.project_points`` (intrinsics, mount height, pitch): the same model perception
inverts with ``ground_range_m`` and ``bearing_deg``.

Per frame: copy the precomputed sky/verge background; draw the road surface (textured through a mask),
lane markings (solid strips and dashes on the ground plane, real widths and dash lengths), tree shadows,
then boxes (cars with a dark underside, a shadow on the ground and two tail lights; obstacles) and QR
boards (the encoder's image warped onto the board's projected quad) from far to near; then exposure
(night, glare, tunnel exit) and sensor noise. Every polygon is clipped against a near plane in front
of the camera before projection, so points behind the camera never fold into the image. Vertices are
drawn in fixed point (``SHIFT`` bits) so thin far markings keep their sub-pixel position.
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
from fearguard.sim.lighting import LightState
from fearguard.sim.qr import QrBoard, board_image, modules_across, place_boards
from fearguard.sim.road import Road
from fearguard.sim.scenario import Marking, Scenario

SHIFT = 4  # [bits] fixed-point fraction of polygon vertices (1/16 px)
COORD_LIMIT_PX = 30_000.0  # [px] vertices are clamped here (far outside any image; keeps int32 safe)
NEAR_PLANE_FRACTION = 0.3  # [-] near plane depth as a share of the camera's mount height
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
CAR_SHADOW_BGR = (28, 28, 30)
UNDERSIDE_BGR = (32, 32, 34)
GLASS_BGR = (62, 52, 46)
TAIL_LIGHT_BGR = (30, 22, 235)  # brighter and purer than a red body (40, 40, 185)
TAIL_LIGHT_LIT_BGR = (90, 90, 255)
POST_BGR = (70, 70, 72)
BOX_BGR = {
    "red": (40, 40, 185), "blue": (150, 70, 30), "white": (225, 225, 225), "black": (40, 40, 40), "silver": (175, 175, 170),
    "green": (60, 130, 40), "yellow": (40, 200, 220), "orange": (30, 120, 235), "grey": (120, 120, 120),
}
FACE_SHADE = (1.0, 1.0, 0.72, 0.72, 1.15)  # rear, front, right, left, top
# box corners: index = 4·ix + 2·iy + iz (ix 0 rear / 1 front, iy 0 right / 1 left, iz 0 bottom / 1 top)
FACES = ((0, 2, 3, 1), (4, 5, 7, 6), (0, 1, 5, 4), (2, 6, 7, 3), (1, 3, 7, 5))
FACE_NORMALS = np.array([(-1, 0, 0), (1, 0, 0), (0, -1, 0), (0, 1, 0), (0, 0, 1)], dtype=float)
_FACE_INDEX = np.array(FACES)
_CORNER_X = np.repeat([-0.5, 0.5], 4)  # × length
_CORNER_Y = np.tile(np.repeat([-0.5, 0.5], 2), 2)  # × width
_CORNER_Z = np.tile([0.0, 1.0], 4)  # × height
# rear-face details as (a across from right to left, b up) rectangles: underside band, window, two tail lights
_DETAILS = ((0.0, 1.0, 0.0, 0.2), (0.1, 0.9, 0.62, 0.94), (0.04, 0.2, 0.38, 0.54), (0.8, 0.96, 0.38, 0.54))
_DETAIL_A = np.array([[a0, a1, a1, a0] for a0, a1, _, _ in _DETAILS])
_DETAIL_B = np.array([[b0, b0, b1, b1] for _, _, b0, b1 in _DETAILS])
_SHADOW_X = np.array([-0.5, 0.5, 0.5, -0.5])  # × length
_SHADOW_Y = np.array([-0.5, -0.5, 0.5, 0.5])  # × width
CAR_SHADOW_GROWTH = 1.12  # [-] ground shadow / footprint size
QR_MIN_PX_PER_MODULE = 2.5  # [px] a board at least this sharp counts as readable (qr_visible)
QR_MIP_LEVELS = (1, 2, 4, 8)  # [px per module] board images kept at these sharpnesses
QR_CODE_SHARE = 0.8  # [-] the code's share of the board side (inside the quiet zone and frame)
NOISE_SHEET_PAD = 64  # [px] noise is cropped from a larger sheet at a random offset each frame
NIGHT_FLOOR = 0.07  # [-] brightness of the unlit night scene
HEADLIGHT_PEAK = 0.6  # [-] brightness of the headlights' pool on the road, relative to daylight
NIGHT_REACH = 6.0  # [mount heights] headlight pool: full light out to this ground range
HEADLIGHT_SPREAD_DEG = 28.0  # [deg] sigma of the headlights' horizontal spread
BLOOM_RADIUS = 0.45  # [-] of the image width


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
        self.near_m = NEAR_PLANE_FRACTION * (camera.mount_height_m or 1.0)
        self.far_m = scenario.render_far_m
        self.horizon_v = camera.horizon_v_px()
        self._rng = noise_rng
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
        self._noise_unit = rng.standard_normal((self.h + NOISE_SHEET_PAD, self.w + NOISE_SHEET_PAD)).astype(np.float32)
        self._noise: dict[float, tuple[np.ndarray, np.ndarray]] = {}
        self._night: dict[float, np.ndarray] = {}
        self._bloom = self._make_bloom()
        self._lines = self._marking_lines()
        self._behind_m = BEHIND_FRACTION * 2 * self._half_road_m
        self._sample_t = np.linspace(0.0, 1.0, ROAD_SAMPLES) ** SAMPLE_POWER
        self._pale_segment = np.array([seg.surface == "pale" for seg in spec.segments])
        self._any_pale = bool(self._pale_segment.any())
        self._face_colours = {name: [tuple(int(v) for v in np.clip(np.array(bgr) * k, 0, 255)) for k in FACE_SHADE]
                              for name, bgr in BOX_BGR.items()}

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

    def _make_bloom(self) -> np.ndarray:
        u0, v0 = 0.62 * self.w, self.horizon_v - 0.06 * self.h
        v, u = np.mgrid[0 : self.h, 0 : self.w].astype(np.float32)
        r = np.hypot(u - u0, v - v0) / (BLOOM_RADIUS * self.w)
        glow = 255.0 * np.exp(-(r**2) * 2.0)
        return np.repeat(glow[:, :, None], 3, axis=2).astype(np.uint8)

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

    def _noise_pair(self, sigma: float) -> tuple[np.ndarray, np.ndarray]:
        key = round(sigma, 1)
        if key not in self._noise:
            n = self._noise_unit * key
            pos = np.clip(n, 0, 255).astype(np.uint8)
            neg = np.clip(-n, 0, 255).astype(np.uint8)
            self._noise[key] = (np.repeat(pos[:, :, None], 3, axis=2), np.repeat(neg[:, :, None], 3, axis=2))
        return self._noise[key]

    def _night_map(self, strength: float) -> np.ndarray:
        key = round(strength, 2)
        if key not in self._night:
            cam = self.camera
            v, u = np.mgrid[0 : self.h, 0 : self.w].astype(np.float64)
            angle = math.radians(cam.pitch_deg) + np.arctan2(v - cam.cy_px, cam.fy_px)
            h = cam.mount_height_m or 1.0
            ground = np.where(angle > 1e-3, h / np.tan(np.maximum(angle, 1e-3)), np.inf)
            reach = NIGHT_REACH * h
            pool = np.minimum(1.0, (reach / ground) ** 2)
            bearing = np.degrees(np.arctan2(u - cam.cx_px, cam.fx_px))
            pool *= np.exp(-0.5 * (bearing / HEADLIGHT_SPREAD_DEG) ** 2)
            lit = NIGHT_FLOOR + (HEADLIGHT_PEAK - NIGHT_FLOOR) * pool
            gain = 1.0 - key * (1.0 - lit)
            self._night[key] = np.repeat((255.0 * gain)[:, :, None], 3, axis=2).astype(np.uint8)
        return self._night[key]

    # -- geometry ------------------------------------------------------------------------------
    def _to_camera(self, pose: tuple[float, float, float], x: np.ndarray, y: np.ndarray, z: np.ndarray | float) -> np.ndarray:
        """World points → (..., 3) camera-relative (forward, left, up)."""
        cx, cy, yaw = pose
        c, s = math.cos(yaw), math.sin(yaw)
        dx, dy = x - cx, y - cy
        out = np.empty((*np.shape(dx), 3))
        out[..., 0] = dx * c + dy * s
        out[..., 1] = dy * c - dx * s
        out[..., 2] = z
        out[..., 2] -= self.camera.mount_height_m or 1.0
        return out

    def _depth(self, p: np.ndarray) -> np.ndarray:
        pitch = math.radians(self.camera.pitch_deg)
        return p[..., 0] * math.cos(pitch) - p[..., 2] * math.sin(pitch)

    def _fixed(self, p: np.ndarray) -> np.ndarray:
        """Camera-relative points (..., 3), all in front of the near plane → fixed-point int32 pixels (..., 2)."""
        u, v, _ = self.camera.project_points(p[..., 0], p[..., 1], p[..., 2])
        uv = np.stack([u, v], axis=-1)
        np.clip(uv, -COORD_LIMIT_PX, COORD_LIMIT_PX, out=uv)
        return np.rint(uv * (1 << SHIFT)).astype(np.int32)

    def _polys_px(self, polys: np.ndarray) -> list[np.ndarray | None]:
        """Camera-relative polygons (P, n, 3) → fixed-point image polygons, near-clipped (None when wholly behind)."""
        if len(polys) == 0:
            return []
        depth = self._depth(polys)
        front = depth >= self.near_m
        whole = front.all(axis=1)
        out: list[np.ndarray | None] = list(self._fixed(polys))
        if whole.all():
            return out
        partial = front.any(axis=1) & ~whole
        clipped: list[tuple[int, list[list[float]]]] = []
        for k in np.flatnonzero(~whole):
            out[k] = None
            if partial[k]:
                pts = _clip_near(polys[k].tolist(), depth[k].tolist(), self.near_m)
                if len(pts) >= 3:
                    clipped.append((int(k), pts))
        if clipped:  # project every clipped polygon in one call
            flat = self._fixed(np.array([p for _, pts in clipped for p in pts]))
            start = 0
            for k, pts in clipped:
                out[k] = flat[start : start + len(pts)]
                start += len(pts)
        return out

    def _fill(self, img: np.ndarray, polys: Sequence[np.ndarray | None], colour: tuple[int, ...] | int) -> None:
        drawn = [p for p in polys if p is not None]
        if drawn:
            cv2.fillPoly(img, drawn, colour, cv2.LINE_8, SHIFT)

    def _samples(self, s0: float, s1: float) -> np.ndarray:
        """s samples over [s0, s1], denser near s0, with the segment boundaries inside."""
        s = s0 + (s1 - s0) * self._sample_t
        breaks = self.road.breaks_m
        inner = breaks[(breaks > s0) & (breaks < s1)]
        return np.unique(np.concatenate([s, inner])) if len(inner) else s

    # -- drawing -------------------------------------------------------------------------------
    def render(self, cam_pose: tuple[float, float, float], s_m: float, boxes: Sequence[Box], light: LightState) -> Frame:
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
        ground = self._to_camera(cam_pose, x[:n] - lats[:, None] * sn[:n], y[:n] + lats[:, None] * cs[:n], 0.0)  # (R, n, 3)
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
            polys = self._polys_px(self._to_camera(cam_pose, px, py, 0.0))
            for colour_index, poly in zip(dashes[:, 3], polys, strict=True):
                by_colour["yellow" if colour_index else "white"].append(poly)
        for colour, polys in by_colour.items():
            self._fill(frame, polys, PAINT_BGR[colour])
        self._draw_shadows(frame, cam_pose, light, s0, s1)
        emissive: list[np.ndarray] = []
        board_geo = (x[n + 3 * d :], y[n + 3 * d :], h[n + 3 * d :])
        qr_visible = self._draw_objects(frame, cam_pose, boxes, boards, board_geo, emissive)
        self._expose(frame, cam_pose, light)
        if light.night > 0.3 or light.tunnel > 0.3:
            self._fill(frame, emissive, TAIL_LIGHT_LIT_BGR)
        self._add_noise(frame, light.noise_sigma)
        return Frame(frame, tuple(qr_visible))

    def _draw_surface(self, frame: np.ndarray, strips: _Strips, samples: np.ndarray) -> None:
        if not self._any_pale:
            mask = np.zeros((self.h, self.w), np.uint8)
            self._fill(mask, [strips.polygon(0, 1, samples[0], samples[-1])], 255)
            cv2.copyTo(self._asphalt, mask, frame)
            return
        pale = self._pale_segment[self.road.segment_index(samples)]
        for texture, selected in ((self._asphalt, ~pale), (self._pale, pale)):
            if not selected.any():
                continue
            mask = np.zeros((self.h, self.w), np.uint8)
            self._fill(mask, [strips.polygon(0, 1, samples[run[0]], samples[run[-1]]) for run in _runs(selected)], 255)
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

    def _draw_shadows(self, frame: np.ndarray, pose: tuple[float, float, float], light: LightState, s0: float, s1: float) -> None:
        polys = []
        for i in light.shadow_zones:
            blobs = self._shadows[i]
            if blobs is None:
                continue
            s, world = blobs
            keep = (s > s0 - 1.0) & (s < s1)
            if keep.any():
                pts = world[keep]
                polys.append(self._to_camera(pose, pts[..., 0], pts[..., 1], 0.0))
        if not polys:
            return
        mask = np.zeros((self.h, self.w), np.uint8)
        self._fill(mask, self._polys_px(np.concatenate(polys)), 255)
        cv2.copyTo(cv2.convertScaleAbs(frame, alpha=SHADOW_FACTOR), mask, frame)

    def _draw_objects(self, frame: np.ndarray, pose: tuple[float, float, float], boxes: Sequence[Box], boards: np.ndarray,
                      board_geo: tuple[np.ndarray, np.ndarray, np.ndarray], emissive: list[np.ndarray]) -> list[str]:
        """Boxes and boards from far to near; returns the readable boards' payloads."""
        cx, cy, _ = pose
        order: list[tuple[float, int, int]] = []  # (distance, kind 0 box / 1 board, index)
        box_polys = self._box_polys(pose, boxes) if boxes else None
        for i, b in enumerate(boxes):
            order.append((math.hypot(b.x_m - cx, b.y_m - cy), 0, i))
        board_polys = self._board_polys(pose, boards, board_geo) if len(boards) else None
        if board_polys is not None:
            for j in range(len(boards)):
                order.append((math.hypot(float(board_polys[0][j][0]) - cx, float(board_polys[0][j][1]) - cy), 1, j))
        order.sort(key=lambda item: -item[0])
        visible: list[str] = []
        for _, kind, i in order:
            if kind == 0 and box_polys is not None:
                self._draw_box(frame, boxes[i], i, box_polys, emissive)
            elif board_polys is not None:
                board = self._boards[int(boards[i])]
                if self._draw_board(frame, board, board_polys[1][i], board_polys[2][i], board_polys[3][i]):
                    visible.append(board.payload)
        return sorted(visible)

    def _box_polys(self, pose: tuple[float, float, float], boxes: Sequence[Box]) -> tuple[list, np.ndarray, int]:
        """Every box's faces (5), rear details (4) and ground shadow (1), projected in one batch; face visibility."""
        b = len(boxes)
        bx, by, yaw, length, width, height = (np.array(v, dtype=float) for v in zip(
            *[(o.x_m, o.y_m, o.yaw_rad, o.length_m, o.width_m, o.height_m) for o in boxes], strict=True))
        c, s = np.cos(yaw)[:, None], np.sin(yaw)[:, None]
        lx, ly = _CORNER_X[None] * length[:, None], _CORNER_Y[None] * width[:, None]
        corners = self._to_camera(pose, bx[:, None] + lx * c - ly * s, by[:, None] + lx * s + ly * c, _CORNER_Z[None] * height[:, None])
        faces = corners[:, _FACE_INDEX]  # (B, 5, 4, 3)
        rel = yaw - pose[2]
        rc, rs = np.cos(rel)[:, None], np.sin(rel)[:, None]
        normals = np.stack([FACE_NORMALS[None, :, 0] * rc - FACE_NORMALS[None, :, 1] * rs,
                            FACE_NORMALS[None, :, 0] * rs + FACE_NORMALS[None, :, 1] * rc,
                            np.broadcast_to(FACE_NORMALS[None, :, 2], (b, 5))], axis=-1)
        visible = (normals * faces.mean(axis=2)).sum(axis=-1) < 0.0  # (B, 5)
        rear = faces[:, 0]  # BR, BL, TL, TR
        br, bl, tr = rear[:, None, None, 0], rear[:, None, None, 1], rear[:, None, None, 3]
        details = br + _DETAIL_A[None, :, :, None] * (bl - br) + _DETAIL_B[None, :, :, None] * (tr - br)  # (B, 4, 4, 3)
        grow = np.where([o.is_vehicle for o in boxes], CAR_SHADOW_GROWTH, 1.05)[:, None]
        sx, sy = _SHADOW_X[None] * length[:, None] * grow, _SHADOW_Y[None] * width[:, None] * grow
        shadow = self._to_camera(pose, bx[:, None] + sx * c - sy * s, by[:, None] + sx * s + sy * c, 0.0)  # (B, 4, 3)
        polys = self._polys_px(np.concatenate([faces.reshape(-1, 4, 3), details.reshape(-1, 4, 3), shadow]))
        return polys, visible, b

    def _draw_box(self, frame: np.ndarray, box: Box, i: int, batch: tuple[list, np.ndarray, int], emissive: list[np.ndarray]) -> None:
        polys, visible, b = batch
        self._fill(frame, [polys[9 * b + i]], CAR_SHADOW_BGR)
        colours = self._face_colours[box.colour]
        for f in range(5):
            if visible[i, f]:
                self._fill(frame, [polys[5 * i + f]], colours[f])
        if box.is_vehicle and visible[i, 0]:
            base = 5 * b + 4 * i
            self._fill(frame, [polys[base]], UNDERSIDE_BGR)
            self._fill(frame, [polys[base + 1]], GLASS_BGR)
            lights = [p for p in polys[base + 2 : base + 4] if p is not None]
            self._fill(frame, lights, TAIL_LIGHT_BGR)
            emissive.extend(lights)

    def _board_polys(self, pose: tuple[float, float, float], boards: np.ndarray,
                     geo: tuple[np.ndarray, np.ndarray, np.ndarray]) -> tuple[np.ndarray, list, list, np.ndarray]:
        """Board centres (world), board quads (TL, TR, BR, BL as seen by the car), posts, and which face the car."""
        x, y, h = geo
        lateral = np.array([self._boards[k].lateral_m for k in boards])
        size = np.array([self._boards[k].size_m for k in boards])
        elev = np.array([self._boards[k].elevation_m for k in boards])
        nx, ny = -np.sin(h)[:, None], np.cos(h)[:, None]
        lat = lateral[:, None] + size[:, None] * np.array([[0.5, -0.5, -0.5, 0.5]])
        z = elev[:, None] + size[:, None] * np.array([[1.0, 1.0, 0.0, 0.0]])
        quad = self._to_camera(pose, x[:, None] + lat * nx, y[:, None] + lat * ny, z)  # (K, 4, 3)
        post_lat = lateral[:, None] + size[:, None] * np.array([[0.04, -0.04, -0.04, 0.04]])
        post_z = elev[:, None] * np.array([[1.0, 1.0, 0.0, 0.0]])
        post = self._to_camera(pose, x[:, None] + post_lat * nx, y[:, None] + post_lat * ny, post_z)
        facing = (np.cross(quad[:, 1] - quad[:, 0], quad[:, 3] - quad[:, 0]) * quad.mean(axis=1)).sum(axis=-1) > 0
        whole = (self._depth(quad) >= self.near_m).all(axis=1) & facing
        polys = self._polys_px(np.concatenate([quad, post]))
        k = len(boards)
        centres = np.column_stack([x - lateral * np.sin(h), y + lateral * np.cos(h)])
        return centres, [polys[j] if whole[j] else None for j in range(k)], polys[k:], elev > 0

    def _draw_board(self, frame: np.ndarray, board: QrBoard, quad_px: np.ndarray | None, post_px: np.ndarray | None,
                    has_post: bool) -> bool:
        """Draw one QR board (and its post); True when it is sharp and whole enough to read."""
        if quad_px is None:
            return False
        if has_post:
            self._fill(frame, [post_px], POST_BGR)
        dst = quad_px.astype(np.float32) / (1 << SHIFT)
        lo = np.floor(dst.min(axis=0)).astype(int)
        hi = np.ceil(dst.max(axis=0)).astype(int) + 1
        x0, y0, x1, y1 = max(lo[0], 0), max(lo[1], 0), min(hi[0], self.w), min(hi[1], self.h)
        if x1 <= x0 or y1 <= y0:
            return False
        side_px = float(np.linalg.norm(dst - np.roll(dst, -1, axis=0), axis=1).min())
        modules = modules_across(board.payload)
        if side_px < modules:  # under a pixel per module: the code is a grey blur inside a white frame
            cv2.fillConvexPoly(frame, quad_px, (235, 235, 235), cv2.LINE_8, SHIFT)
            centre = quad_px.mean(axis=0)
            inner = np.rint(centre + (quad_px - centre) * QR_CODE_SHARE).astype(np.int32)
            cv2.fillConvexPoly(frame, inner, (140, 140, 140), cv2.LINE_8, SHIFT)
            return False
        level = next((k for k in QR_MIP_LEVELS if k * modules >= side_px), QR_MIP_LEVELS[-1])
        image = board_image(board.payload, level)
        n = float(image.shape[0])
        src = np.array([[0, 0], [n, 0], [n, n], [0, n]], np.float32)
        matrix = cv2.getPerspectiveTransform(src, dst - np.array([x0, y0], np.float32))
        cv2.warpPerspective(image, matrix, (x1 - x0, y1 - y0), dst=frame[y0:y1, x0:x1], flags=cv2.INTER_LINEAR,
                            borderMode=cv2.BORDER_TRANSPARENT)
        inside = bool((lo >= 0).all() and hi[0] <= self.w and hi[1] <= self.h)
        return inside and side_px >= QR_MIN_PX_PER_MODULE * modules

    # -- exposure and noise ----------------------------------------------------------------------
    def _expose(self, frame: np.ndarray, pose: tuple[float, float, float], light: LightState) -> None:
        if light.tunnel > 0:
            self._tunnel(frame, pose, light)
        if light.night > 0:
            cv2.multiply(frame, self._night_map(light.night), dst=frame, scale=1.0 / 255.0)
        if light.gain != 1.0 or light.offset != 0.0:
            cv2.convertScaleAbs(frame, dst=frame, alpha=light.gain, beta=light.offset)
        if light.bloom > 0:
            cv2.add(frame, cv2.convertScaleAbs(self._bloom, alpha=light.bloom), dst=frame)

    def _tunnel(self, frame: np.ndarray, pose: tuple[float, float, float], light: LightState) -> None:
        """Inside a tunnel: everything dark except the exit portal, which is blown out."""
        k = light.tunnel
        dark = cv2.convertScaleAbs(frame, alpha=1.0 - k * (1.0 - 0.3))
        if light.portal_s_m is None:
            frame[:] = dark
            return
        x, y, h = self.road.pose_at(light.portal_s_m)
        nx, ny = -math.sin(float(h)), math.cos(float(h))
        lat = np.array([self._left_edge_m, self._right_edge_m, self._right_edge_m, self._left_edge_m]) * 1.15
        height = 2.2 * self._half_road_m
        quad = self._to_camera(pose, float(x) + lat * nx, float(y) + lat * ny, np.array([height, height, 0.0, 0.0]))
        mask = np.zeros((self.h, self.w), np.uint8)
        self._fill(mask, self._polys_px(quad[None]), 255)
        bright = cv2.convertScaleAbs(frame, alpha=1.0 + 1.6 * k, beta=70.0 * k)
        cv2.copyTo(bright, mask, dark)
        frame[:] = dark

    def _add_noise(self, frame: np.ndarray, sigma: float) -> None:
        if sigma <= 0:
            return
        pos, neg = self._noise_pair(sigma)
        du, dv = (int(k) for k in self._rng.integers(0, NOISE_SHEET_PAD, 2))
        cv2.add(frame, pos[dv : dv + self.h, du : du + self.w], dst=frame)
        cv2.subtract(frame, neg[dv : dv + self.h, du : du + self.w], dst=frame)


class _Strips:
    """Ground strips over the shared route samples: rows of projected points, two rows per strip."""

    def __init__(self, renderer: Renderer, ground: np.ndarray, samples: np.ndarray) -> None:
        self.r, self.ground, self.samples = renderer, ground, samples
        depth = renderer._depth(ground)
        front = (depth >= renderer.near_m).all(axis=0)
        behind = np.flatnonzero(~front)
        # common case: only the first few samples (behind the camera) are cut; they lie below the image
        self.first = int(behind[-1]) + 1 if len(behind) else 0
        self.simple = len(behind) == 0 or int(behind[-1]) == len(behind) - 1
        self.px = renderer._fixed(ground) if self.simple else None

    def polygon(self, lo_row: int, hi_row: int, s_a: float, s_b: float) -> np.ndarray | None:
        """The strip between two rows over samples in [s_a, s_b]."""
        ia = max(int(np.searchsorted(self.samples, s_a)), self.first if self.simple else 0)
        ib = int(np.searchsorted(self.samples, s_b, side="right"))
        if ib - ia < 2:
            return None
        if self.px is not None:
            return np.concatenate([self.px[hi_row, ia:ib], self.px[lo_row, ia:ib][::-1]])
        poly = np.concatenate([self.ground[hi_row, ia:ib], self.ground[lo_row, ia:ib][::-1]])
        return self.r._polys_px(poly[None])[0]


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


def _clip_near(poly: list[list[float]], depth: list[float], near: float) -> list[list[float]]:
    """Sutherland–Hodgman against the plane depth = near; by hand, in plain Python: one plane and a few vertices
    (no library clips polygons in 3-D, and per-vertex array calls would cost more than the arithmetic)."""
    out: list[list[float]] = []
    n = len(poly)
    for i in range(n):
        p, d = poly[i], depth[i]
        q, e = poly[(i + 1) % n], depth[(i + 1) % n]
        if d >= near:
            out.append(p)
        if (d >= near) != (e >= near):
            t = (near - d) / (e - d)
            out.append([p[0] + t * (q[0] - p[0]), p[1] + t * (q[1] - p[1]), p[2] + t * (q[2] - p[2])])
    return out
