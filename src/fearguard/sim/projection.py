"""World → image for the renderer: camera-relative points, near-plane clipping, fixed-point pixels.

Projection is ``CameraModel.project_points`` (intrinsics, mount height, pitch): the same model perception
inverts with ``ground_range_m`` and ``bearing_deg``. Every polygon is clipped against a near plane in
front of the camera before projection, so points behind the camera never fold into the image. Vertices
are returned in fixed point (``SHIFT`` bits) so thin far markings keep their sub-pixel position.
"""

from __future__ import annotations

import math
from collections.abc import Sequence

import cv2
import numpy as np

from fearguard.camera import CameraModel

SHIFT = 4  # [bits] fixed-point fraction of polygon vertices (1/16 px)
COORD_LIMIT_PX = 30_000.0  # [px] vertices are clamped here (far outside any image; keeps int32 safe)
NEAR_PLANE_FRACTION = 0.3  # [-] near plane depth as a share of the camera's mount height

Pose = tuple[float, float, float]  # camera position in the world (x_m, y_m) and yaw [rad]


class Projector:
    """The camera's view of world points: camera-relative (forward, left, up), depth, fixed-point pixels."""

    def __init__(self, camera: CameraModel) -> None:
        self.camera = camera
        self.mount_height_m = camera.mount_height_m or 1.0
        self.near_m = NEAR_PLANE_FRACTION * self.mount_height_m
        pitch = math.radians(camera.pitch_deg)
        self._cos_pitch, self._sin_pitch = math.cos(pitch), math.sin(pitch)

    def to_camera(self, pose: Pose, x: np.ndarray, y: np.ndarray, z: np.ndarray | float) -> np.ndarray:
        """World points → (..., 3) camera-relative (forward, left, up)."""
        cx, cy, yaw = pose
        c, s = math.cos(yaw), math.sin(yaw)
        dx, dy = x - cx, y - cy
        out = np.empty((*np.shape(dx), 3))
        out[..., 0] = dx * c + dy * s
        out[..., 1] = dy * c - dx * s
        out[..., 2] = z
        out[..., 2] -= self.mount_height_m
        return out

    def depth(self, p: np.ndarray) -> np.ndarray:
        """Distance along the optical axis of camera-relative points (..., 3)."""
        return p[..., 0] * self._cos_pitch - p[..., 2] * self._sin_pitch

    def fixed(self, p: np.ndarray) -> np.ndarray:
        """Camera-relative points (..., 3), all in front of the near plane → fixed-point int32 pixels (..., 2)."""
        u, v, _ = self.camera.project_points(p[..., 0], p[..., 1], p[..., 2])
        uv = np.stack([u, v], axis=-1)
        np.clip(uv, -COORD_LIMIT_PX, COORD_LIMIT_PX, out=uv)
        return np.rint(uv * (1 << SHIFT)).astype(np.int32)

    def polys_px(self, polys: np.ndarray) -> list[np.ndarray | None]:
        """Camera-relative polygons (P, n, 3) → fixed-point image polygons, near-clipped (None when wholly behind)."""
        if len(polys) == 0:
            return []
        depth = self.depth(polys)
        front = depth >= self.near_m
        whole = front.all(axis=1)
        out: list[np.ndarray | None] = list(self.fixed(polys))
        if whole.all():
            return out
        partial = front.any(axis=1) & ~whole
        clipped: list[tuple[int, list[list[float]]]] = []
        for k in np.flatnonzero(~whole):
            out[k] = None
            if partial[k]:
                pts = clip_near(polys[k].tolist(), depth[k].tolist(), self.near_m)
                if len(pts) >= 3:
                    clipped.append((int(k), pts))
        if clipped:  # project every clipped polygon in one call
            flat = self.fixed(np.array([p for _, pts in clipped for p in pts]))
            start = 0
            for k, pts in clipped:
                out[k] = flat[start : start + len(pts)]
                start += len(pts)
        return out


def fill(img: np.ndarray, polys: Sequence[np.ndarray | None], colour: tuple[int, ...] | int) -> None:
    """Fill the fixed-point polygons that are in view (None entries are behind the camera)."""
    drawn = [p for p in polys if p is not None]
    if drawn:
        cv2.fillPoly(img, drawn, colour, cv2.LINE_8, SHIFT)


def clip_near(poly: list[list[float]], depth: list[float], near: float) -> list[list[float]]:
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
