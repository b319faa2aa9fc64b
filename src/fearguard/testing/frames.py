"""Frames for frame-level histories, rebuilt exactly from a ``FrameSpec``.

- ``render``: a frame of one of the bundled scenarios drawn by the project's own simulator renderer
  (``sim/render.py``: road, markings, traffic, lighting, camera noise), car driving straight at the
  scenario's speed, frame ``index`` of a small pool rendered once per process (same seed: byte-identical).
- ``synthetic``: a small drawn road (grey asphalt, two white boundaries converging to a vanishing
  point) with the lane centre shifted by ``offset_px``; cheap, and a real lane for the Hough steering.
- ``garbage``: what a broken camera driver hands over: None, an empty array, one channel, four
  channels, floats with NaN, int16, a 1×1 image, a reversed (non-contiguous) view, a string, a list.

``effect`` then degrades a picture (dark, glare, noise, black, half_black), and ``reuse_buffer``
writes the pixels into the previous frame's array, as a driver that refills one buffer does.
"""

from __future__ import annotations

from functools import lru_cache
from typing import Any

import cv2
import numpy as np

from fearguard.testing.history import FrameSpec

RENDER_SCENARIOS = ("clear_straight", "night", "tunnel_exit_glare", "occluding_traffic_follow_lead")
RENDER_POOL = 6  # [frames] per scenario, one every RENDER_EVERY steps of the world
RENDER_EVERY = 5  # [steps]
SYNTHETIC_SIZE = (120, 160)  # [px] height, width of a synthetic road frame
EFFECTS = ("", "dark", "glare", "noise", "black", "half_black")
GARBAGE = ("none", "empty", "grey_2d", "four_channels", "float_nan", "int16", "one_pixel", "reversed_view", "text", "list")


@lru_cache(maxsize=len(RENDER_SCENARIOS))
def _render_pool(name: str) -> tuple[np.ndarray, ...]:
    """RENDER_POOL frames of a bundled scenario (its own seed), driving straight at its start speed."""
    from importlib import resources

    from fearguard.sim.scenario import load_scenario
    from fearguard.sim.world import World

    scenario = load_scenario(str(resources.files("fearguard") / "scenarios" / f"{name}.toml"))
    world = World(scenario)
    speed = max(scenario.ego.speed_mps, 0.5)
    pool = []
    for k in range(RENDER_POOL * RENDER_EVERY):
        if k % RENDER_EVERY == 0:
            frame = world.sense().frame_bgr.copy()
            frame.flags.writeable = False
            pool.append(frame)
        world.advance(0.0, speed)
    return tuple(pool)


@lru_cache(maxsize=256)
def _synthetic(seed: int, offset_px: float) -> np.ndarray:
    h, w = SYNTHETIC_SIZE
    rng = np.random.default_rng(seed)
    img = np.empty((h, w, 3), np.uint8)
    img[: h // 3] = (200, 170, 140)  # sky
    img[h // 3 :] = (95, 95, 95)  # asphalt
    vx, vy = w / 2 + offset_px * 0.3, h // 3
    for bottom_x in (w * 0.15 + offset_px, w * 0.85 + offset_px):
        cv2.line(img, (round(bottom_x), h - 1), (round(vx), vy), (235, 235, 235), 3, cv2.LINE_AA)
    noise = rng.normal(0.0, 3.0, img.shape)
    img = np.clip(img + noise, 0, 255).astype(np.uint8)
    img.flags.writeable = False
    return img


def _effect(img: np.ndarray, effect: str, seed: int) -> np.ndarray:
    if effect == "":
        return img.copy()
    if effect == "dark":
        return (img * 0.08).astype(np.uint8)
    if effect == "glare":
        return np.clip(img.astype(np.int16) + 170, 0, 255).astype(np.uint8)
    if effect == "noise":
        rng = np.random.default_rng(seed)
        return np.clip(img + rng.normal(0.0, 40.0, img.shape), 0, 255).astype(np.uint8)
    if effect == "black":
        return np.zeros_like(img)
    if effect == "half_black":
        out = img.copy()
        out[:, : img.shape[1] // 2] = 0
        return out
    raise ValueError(f"unknown frame effect {effect!r}; known: {', '.join(e for e in EFFECTS if e)}")


def _garbage(what: str) -> Any:
    if what == "none":
        return None
    if what == "empty":
        return np.zeros((0, 0, 3), np.uint8)
    if what == "grey_2d":
        return np.full((120, 160), 90, np.uint8)
    if what == "four_channels":
        return np.full((120, 160, 4), 90, np.uint8)
    if what == "float_nan":
        img = np.full((120, 160, 3), 0.5)
        img[::3] = np.nan
        return img
    if what == "int16":
        return np.full((120, 160, 3), -3000, np.int16)
    if what == "one_pixel":
        return np.full((1, 1, 3), 128, np.uint8)
    if what == "reversed_view":
        return _synthetic(0, 0.0)[::-1, ::-1]
    if what == "text":
        return "frame.jpg"
    if what == "list":
        return [[0, 1], [2, 3]]
    raise ValueError(f"unknown garbage frame {what!r}; known: {', '.join(GARBAGE)}")


def frame_pixels(spec: FrameSpec | None, previous: Any = None) -> Any:
    """The frame a spec describes (a fresh array, or ``previous`` refilled when ``reuse_buffer``)."""
    if spec is None:
        return None
    if spec.kind == "render":
        if spec.source not in RENDER_SCENARIOS:
            raise ValueError(f"unknown render source {spec.source!r}; known: {', '.join(RENDER_SCENARIOS)}")
        pool = _render_pool(spec.source)
        img = _effect(pool[spec.index % len(pool)], spec.effect, spec.index)
    elif spec.kind == "synthetic":
        img = _effect(_synthetic(spec.index, float(spec.offset_px)), spec.effect, spec.index)
    elif spec.kind == "garbage":
        return _garbage(spec.source)
    else:
        raise ValueError(f"unknown frame kind {spec.kind!r}; known: render, synthetic, garbage")
    if spec.reuse_buffer and isinstance(previous, np.ndarray) and previous.shape == img.shape and previous.dtype == img.dtype \
            and previous.flags.writeable:
        np.copyto(previous, img)
        return previous
    return img
