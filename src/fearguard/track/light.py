"""The learnt light: the shape of a room's or road's light on the recordings, and how far a frame's is from it.

A mean brightness band cannot tell a frame facing a bright window (the floor dark below, the window blown out above)
from the same room with the lights switched off: both are dark on average. Their *shape* differs. A frame's light is
its grey levels at ``LIGHT_PERCENTILES`` on a log scale (log(1 + g) / log(256), 0..1): auto exposure moves them
together, a window lifts the top ones, and light taken away lowers every one alike by the same step — a shape no
recording of the lit room has. On the shared model-car recordings and the development corpus (learn the first half,
the second half ×0.3), the light alone reads every darkened frame unfamiliar (< 0.5) on 14 of 16 sources, and 0–2.4 %
of the lit second half there (docs/learning.md, "The light").

Pure functions of the pixels, and one frozen value: the learnt frames' light and the recordings' own distances, which
``TrackProfile`` reads with the same nearest-frames distance and calibrated mapping as its familiarity (its reference
never below ``REFERENCE_MIN``).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

LIGHT_PERCENTILES = (10.0, 50.0, 90.0, 99.0)  # [%] of the grey levels: the dark part, the middle, the bright part, highlights
LOG_GREY = math.log(256.0)  # log(1 + 255): the light's scale, 0..1
REFERENCE_MIN = math.log(1.25) / LOG_GREY  # [-] a light a quarter brighter or darker than the nearest learnt is never
#   unfamiliar on its own: a camera's exposure and a room's daylight move that much (a steady indoor room's own distances
#   are 0.01-0.03, so that a cloud would otherwise count)


@dataclass(frozen=True, eq=False)  # eq=False: holds arrays
class LightModel:
    """The learnt light: each learnt frame's light, and the recordings' own distances (sorted) that calibrate it."""

    levels: np.ndarray  # (M, len(LIGHT_PERCENTILES)) learnt frames' light, 0..1
    calibration: np.ndarray  # (C,) sorted: each calibration frame's distance to learnt frames away from it in time

    def nearest(self, light: np.ndarray) -> np.ndarray:
        """The learnt frame's light nearest to this one (for the reasons)."""
        return self.levels[int(np.argmin(((self.levels - light) ** 2).sum(axis=1)))]


def light_of(grey: np.ndarray) -> np.ndarray:
    """The light of a frame's grey at ``features.WORK_PX`` (``features.shrink``; uint8): the lowest grey level reached
    by each of ``LIGHT_PERCENTILES`` of its pixels, on the log scale (a histogram's cumulative count: 20 µs where
    np.percentile takes 66)."""
    counts = np.cumsum(np.bincount(np.asarray(grey, dtype=np.uint8).ravel(), minlength=256))
    levels = np.searchsorted(counts, np.array(LIGHT_PERCENTILES) / 100.0 * counts[-1], side="left")
    return np.log1p(levels.astype(np.float64)) / LOG_GREY


def grey_levels(light: np.ndarray) -> np.ndarray:
    """The grey levels (0..255) a light stands for."""
    return np.expm1(np.asarray(light) * LOG_GREY)


def light_words(light: np.ndarray, learnt: np.ndarray) -> str:
    """How a frame's light differs from the nearest learnt one, in grey levels (for the reasons)."""
    now, then = grey_levels(light), grey_levels(learnt)
    way = "darker" if float(np.mean(light - learnt)) < 0.0 else "brighter"
    pct = "/".join(f"{p:g}" for p in LIGHT_PERCENTILES)
    return (f"{way} than every learnt frame (grey {'/'.join(f'{g:.0f}' for g in now)} at the {pct}th percentiles; "
            f"the nearest learnt {'/'.join(f'{g:.0f}' for g in then)})")
