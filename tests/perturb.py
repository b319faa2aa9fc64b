"""Synthetic perturbations of real frames (over-exposure, darkness, an occluding vehicle) for perception tests."""

from __future__ import annotations

import cv2
import numpy as np


def over_exposed(frame: np.ndarray, gain: float = 3.0, offset: float = 60.0) -> np.ndarray:
    """Glare: gain and offset, clipped at 255 like a sensor."""
    return np.clip(frame.astype(np.float32) * gain + offset, 0, 255).astype(np.uint8)


def darkened(frame: np.ndarray, gain: float = 0.1, noise: float = 2.0, seed: int = 0) -> np.ndarray:
    """Night: gain well below 1 plus the sensor noise that comes with it (fixed seed)."""
    rng = np.random.default_rng(seed)
    return np.clip(frame.astype(np.float32) * gain + rng.normal(0.0, noise, frame.shape), 0, 255).astype(np.uint8)


def with_vehicle(
    frame: np.ndarray, box: tuple[float, float, float, float] = (0.25, 0.55, 0.75, 0.86), colour: tuple[int, int, int] = (60, 60, 170)
) -> np.ndarray:
    """A vehicle's rear drawn over the lane: body, dark underside band, two red tail lights. box = (u0, v0, u1, v1) shares."""
    out = frame.copy()
    h, w = out.shape[:2]
    x0, y0, x1, y1 = int(box[0] * w), int(box[1] * h), int(box[2] * w), int(box[3] * h)
    cv2.rectangle(out, (x0, y0), (x1, y1), colour, -1)
    cv2.rectangle(out, (x0, int(y1 - 0.12 * (y1 - y0))), (x1, y1), (18, 18, 18), -1)
    lw, ly = int(0.12 * (x1 - x0)), int(y0 + 0.45 * (y1 - y0))
    cv2.rectangle(out, (x0 + lw // 2, ly), (x0 + lw // 2 + lw, ly + lw // 2), (40, 40, 230), -1)
    cv2.rectangle(out, (x1 - lw // 2 - lw, ly), (x1 - lw // 2, ly + lw // 2), (40, 40, 230), -1)
    return out
