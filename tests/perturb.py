"""Synthetic perturbations of real frames (over-exposure, darkness, an occluding vehicle) for perception tests, and a
supervisor watching them (``watched``)."""

from __future__ import annotations

import cv2
import numpy as np

import fearguard as fg


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


OCCLUDER_COLOURS = {  # BGR: the colours trucks, vans and cars come in, and a red one
    "black": (12, 12, 12), "grey": (110, 110, 110), "white": (240, 240, 240), "silver": (190, 192, 195), "red": (40, 40, 200),
}
OCCLUDER_BOXES = {  # (u0, v0, u1, v1) shares of the frame
    "middle": (0.25, 0.60, 0.78, 0.86),  # over the middle of the road, both boundaries (a vehicle ahead)
    "right": (0.55, 0.66, 0.95, 0.90),  # over the right boundary (a vehicle cutting in)
    "bottom": (0.10, 0.72, 0.90, 1.00),  # reaching the frame bottom (something right in front of the camera)
}


def with_box(frame: np.ndarray, box: tuple[float, float, float, float], colour: tuple[int, int, int]) -> np.ndarray:
    """A filled box over the frame; box = (u0, v0, u1, v1) shares."""
    out = frame.copy()
    h, w = out.shape[:2]
    cv2.rectangle(out, (int(box[0] * w), int(box[1] * h)), (int(box[2] * w), int(box[3] * h)), colour, -1)
    return out


def garbage_frames(seed: int = 1, size: tuple[int, int] = (640, 480)) -> dict[str, np.ndarray]:
    """What a broken camera or a wrong pixel format emits: uniform and Gaussian noise, blocky and smooth random
    textures at three scales (fixed seed)."""
    rng = np.random.default_rng(seed)
    w, h = size
    frames = {f"uniform noise {i}": rng.integers(0, 256, (h, w, 3), dtype=np.uint8) for i in range(5)}
    frames.update({f"gaussian noise {i}": np.clip(rng.normal(128, 40, (h, w, 3)), 0, 255).astype(np.uint8) for i in range(3)})
    for cell in (3, 7, 15):
        tile = rng.integers(0, 256, (h // cell + 1, w // cell + 1, 3), dtype=np.uint8)
        frames[f"blocks {cell} px"] = cv2.resize(tile, (w, h), interpolation=cv2.INTER_NEAREST)
        frames[f"smooth texture {cell} px"] = cv2.resize(tile, (w, h), interpolation=cv2.INTER_CUBIC)
    return frames


def not_frozen(frame: np.ndarray, i: int) -> np.ndarray:
    """The frame with one corner pixel changed: a real camera never sends the same bytes twice (the frozen check)."""
    out = frame.copy()
    out[0, 0] = i % 256
    return out


def watched(guard: fg.FearGuard, frames: list[np.ndarray], start: int = 0) -> fg.Command:
    """The guard's command after it watched the frames at 20 Hz, 1 m/s (``not_frozen`` each: frame ``start`` first)."""
    cmd = None
    for i, frame in enumerate(frames, start):
        cmd = guard.step(fg.Observation(t_s=0.05 * i, speed_mps=1.0, frame=not_frozen(frame, i)))
    assert cmd is not None
    return cmd
