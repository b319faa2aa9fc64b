"""Boxes standing on the ground (cars, obstacles): footprints, overlap tests and range-sensor rays.

Overlap of two footprints uses OpenCV's rotated-rectangle intersection. Ray casting is written by hand
(no library casts 2-D rays against rectangles): every ray against every footprint edge in one array
operation (ray origin o, direction r, edge p→q: solve o + t·r = p + u·(q − p), keep 0 ≤ u ≤ 1, t > 0).
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass

import cv2
import numpy as np


@dataclass(frozen=True)
class Box:
    """A box on the ground: centre (world m), heading (rad), size (m), colour name, and what it is."""

    x_m: float
    y_m: float
    yaw_rad: float
    length_m: float
    width_m: float
    height_m: float
    colour: str
    is_vehicle: bool

    def corners(self) -> np.ndarray:
        """Footprint corners (4, 2) in world x, y: rear-right, front-right, front-left, rear-left."""
        return footprint(self.x_m, self.y_m, self.yaw_rad, -self.length_m / 2, self.length_m / 2, self.width_m)


def footprint(x_m: float, y_m: float, yaw_rad: float, back_m: float, front_m: float, width_m: float) -> np.ndarray:
    """Corners (4, 2) of a rectangle from ``back_m`` to ``front_m`` along the heading around (x, y)."""
    c, s = math.cos(yaw_rad), math.sin(yaw_rad)
    local = np.array([[back_m, -width_m / 2], [front_m, -width_m / 2], [front_m, width_m / 2], [back_m, width_m / 2]])
    return np.column_stack([x_m + local[:, 0] * c - local[:, 1] * s, y_m + local[:, 0] * s + local[:, 1] * c])


def footprints(boxes: Sequence[Box]) -> np.ndarray:
    """Corners (B, 4, 2) of every box's footprint, in the order of ``Box.corners``."""
    x, y, yaw, length, width = (np.array(v, dtype=float) for v in zip(
        *[(b.x_m, b.y_m, b.yaw_rad, b.length_m, b.width_m) for b in boxes], strict=True))
    lx = np.array([-0.5, 0.5, 0.5, -0.5])[None] * length[:, None]
    ly = np.array([-0.5, -0.5, 0.5, 0.5])[None] * width[:, None]
    c, s = np.cos(yaw)[:, None], np.sin(yaw)[:, None]
    return np.stack([x[:, None] + lx * c - ly * s, y[:, None] + lx * s + ly * c], axis=-1)


def _rotated_rect(corners: np.ndarray) -> tuple[tuple[float, float], tuple[float, float], float]:
    centre = corners.mean(axis=0)
    along = corners[1] - corners[0]
    across = corners[3] - corners[0]
    angle = math.degrees(math.atan2(along[1], along[0]))
    return (float(centre[0]), float(centre[1])), (float(np.hypot(*along)), float(np.hypot(*across))), angle


def overlaps(a: np.ndarray, b: np.ndarray) -> bool:
    """True when two rectangles (corners (4, 2) each, in order) share area or touch."""
    kind, _ = cv2.rotatedRectangleIntersection(_rotated_rect(a), _rotated_rect(b))
    return kind != cv2.INTERSECT_NONE


def ray_ranges(origin: tuple[float, float], angles_rad: np.ndarray, boxes: Sequence[Box]) -> np.ndarray:
    """Distance along each ray (world angle) to the first footprint edge it meets; inf if none."""
    if not boxes:
        return np.full(len(angles_rad), np.inf)
    corners = footprints(boxes)
    p = corners.reshape(-1, 2)
    q = np.roll(corners, -1, axis=1).reshape(-1, 2)
    e = q - p  # (E, 2)
    r = np.column_stack([np.cos(angles_rad), np.sin(angles_rad)])  # (R, 2)
    w = p - np.asarray(origin, dtype=float)  # (E, 2)
    denom = r[:, None, 0] * e[None, :, 1] - r[:, None, 1] * e[None, :, 0]  # r × e
    parallel = np.abs(denom) < 1e-12
    safe = np.where(parallel, 1.0, denom)
    t = (w[None, :, 0] * e[None, :, 1] - w[None, :, 1] * e[None, :, 0]) / safe  # (w × e) / (r × e)
    u = (w[None, :, 0] * r[:, None, 1] - w[None, :, 1] * r[:, None, 0]) / safe  # (w × r) / (r × e)
    hit = ~parallel & (t >= 0.0) & (u >= 0.0) & (u <= 1.0)
    return np.where(hit, t, np.inf).min(axis=1)
