"""Road geometry from straight and arc segments: the pose at a distance s along the route, and back.

The route is the centre line of the ego lane. It starts at (0, 0) heading along +x; lateral offsets are
+ to the left. A segment of curvature κ (1/radius, + = left) starting at pose (x0, y0, h0) gives, at a
distance d into it, heading h0 + κ·d and position (x0 + (sin h − sin h0)/κ, y0 − (cos h − cos h0)/κ)
(a straight line when κ = 0). Before the start and past the end the road continues straight, so the
camera always sees road. ``project`` finds, for each world point, the nearest point of every segment
(closed form for lines and arcs) and keeps the closest: a few array operations for any number of points.
"""

from __future__ import annotations

import math

import numpy as np

from fearguard.sim.scenario_values import RoadSpec, Segment

_EPS_CURVATURE = 1e-12  # [1/m] below this a segment is treated as straight


class Road:
    """Poses along the route of a RoadSpec, vectorised over arrays of s."""

    def __init__(self, spec: RoadSpec) -> None:
        self.spec = spec
        segs = spec.segments
        self.length_m = float(sum(s.length_m for s in segs))
        kappa = [s.curvature_per_m for s in segs]
        lengths = [s.length_m for s in segs]
        starts = np.concatenate([[0.0], np.cumsum(lengths)[:-1]])
        x, y, h = 0.0, 0.0, 0.0
        poses = []
        for k, d in zip(kappa, lengths, strict=True):
            poses.append((x, y, h))
            x, y, h = _advance(x, y, h, k, d)
        self.end_pose = (x, y, h)
        # padded tables: a straight run-in before s = 0 and a straight run-out after the end
        self._start_s = np.concatenate([[0.0], starts, [self.length_m]])
        self._d_low = np.array([-math.inf] + [0.0] * len(segs) + [0.0])  # d range inside each padded segment
        self._d_high = np.array([0.0, *lengths, math.inf])
        self._kappa = np.array([0.0, *kappa, 0.0])
        pose_table = np.array([(0.0, 0.0, 0.0), *poses, self.end_pose])
        self._x0, self._y0, self._h0 = pose_table[:, 0], pose_table[:, 1], pose_table[:, 2]
        self.breaks_m = np.concatenate([starts, [self.length_m]])  # s where segments start, and the end

    def segment_index(self, s_m: np.ndarray | float) -> np.ndarray:
        """Index into spec.segments for each s (clamped to the first/last segment outside the route)."""
        i = np.searchsorted(self.breaks_m, np.asarray(s_m, dtype=float), side="right") - 1
        return np.clip(i, 0, len(self.spec.segments) - 1)

    def segment_at(self, s_m: float) -> Segment:
        return self.spec.segments[int(self.segment_index(s_m))]

    def _padded_index(self, s: np.ndarray) -> np.ndarray:
        return np.searchsorted(self.breaks_m, s, side="right")  # 0: run-in, 1..n: segments, n+1: run-out

    def pose_at(self, s_m: np.ndarray | float) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """World x, y (m) and heading (rad) of the route at each s."""
        s = np.asarray(s_m, dtype=float)
        i = self._padded_index(s)
        return _pose(self._x0[i], self._y0[i], self._h0[i], self._kappa[i], s - self._start_s[i])

    def point_at(self, s_m: np.ndarray | float, lateral_m: np.ndarray | float) -> tuple[np.ndarray, np.ndarray]:
        """World x, y of the point ``lateral_m`` to the left of the route at s."""
        x, y, h = self.pose_at(s_m)
        lat = np.asarray(lateral_m, dtype=float)
        return x - lat * np.sin(h), y + lat * np.cos(h)

    def heading_at(self, s_m: np.ndarray | float) -> np.ndarray:
        return self.pose_at(s_m)[2]

    def project(self, x_m: np.ndarray | float, y_m: np.ndarray | float) -> tuple[np.ndarray, np.ndarray]:
        """(s, lateral) of world points: the nearest point of the route (lateral + = left)."""
        px = np.asarray(x_m, dtype=float)[..., None]
        py = np.asarray(y_m, dtype=float)[..., None]
        x0, y0, h0, k = self._x0, self._y0, self._h0, self._kappa
        curved = np.abs(k) > _EPS_CURVATURE
        safe_k = np.where(curved, k, 1.0)
        # straight: distance along the direction; arc: angle swept around the centre
        d_line = (px - x0) * np.cos(h0) + (py - y0) * np.sin(h0)
        cx, cy = x0 - np.sin(h0) / safe_k, y0 + np.cos(h0) / safe_k
        phi = np.arctan2(py - cy, px - cx) - np.arctan2(y0 - cy, x0 - cx)
        mid = k * np.where(curved, self._d_high, 0.0) / 2.0  # wrap the swept angle around the arc's middle
        swept = _wrap(phi - mid) + mid
        d = np.clip(np.where(curved, swept / safe_k, d_line), self._d_low, self._d_high)
        fx, fy, fh = _pose(x0, y0, h0, k, d)
        dx, dy = px - fx, py - fy
        lateral = -dx * np.sin(fh) + dy * np.cos(fh)
        dist2 = dx * dx + dy * dy
        best = np.argmin(dist2, axis=-1)[..., None]
        s = np.take_along_axis(self._start_s + d, best, axis=-1)[..., 0]
        lat = np.take_along_axis(lateral, best, axis=-1)[..., 0]
        return s, lat


def _advance(x: float, y: float, h: float, k: float, d: float) -> tuple[float, float, float]:
    px, py, ph = _pose(np.array(x), np.array(y), np.array(h), np.array(k), np.array(d))
    return float(px), float(py), float(ph)


def _pose(x0: np.ndarray, y0: np.ndarray, h0: np.ndarray, k: np.ndarray, d: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Pose a distance d along a constant-curvature path from (x0, y0, h0)."""
    h = h0 + k * d
    curved = np.abs(k) > _EPS_CURVATURE
    safe_k = np.where(curved, k, 1.0)
    x = np.where(curved, x0 + (np.sin(h) - np.sin(h0)) / safe_k, x0 + d * np.cos(h0))
    y = np.where(curved, y0 - (np.cos(h) - np.cos(h0)) / safe_k, y0 + d * np.sin(h0))
    return x, y, h


def _wrap(angle: np.ndarray) -> np.ndarray:
    """Angle wrapped into [−π, π)."""
    return (angle + math.pi) % (2.0 * math.pi) - math.pi
