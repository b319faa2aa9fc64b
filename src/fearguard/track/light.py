"""The learnt light: the shape of a room's or road's light on the recordings, and how far a frame's is from it.

A mean brightness band cannot tell a frame facing a bright window (the floor dark below, the window blown out above)
from the same room with the lights switched off: both are dark on average. Their *shape* differs. A frame's light is
its grey levels at ``LIGHT_PERCENTILES`` on a log scale (log(1 + g) / log(256), 0..1): auto exposure moves them
together, a window lifts the top ones, and light taken away lowers every one alike by the same step — a shape no
recording of the lit room has. On the shared model-car recordings and the development corpus (learn the first half,
the second half ×0.3), the light alone finds the darkened frames unlike every learnt one on 14 of 16 sources, and calls
1–7 % of the lit second half so (docs/learning.md, "The light").

Pure functions of the pixels, and one frozen value: the learnt frames' light and the recordings' own distances, which
``TrackProfile`` reads with the same calibrated mapping as its familiarity.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import cv2
import numpy as np

from fearguard.track.features import WORK_PX, as_bgr

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

    def distance(self, light: np.ndarray, neighbours: int) -> float:
        """Mean distance of one frame's light to its ``neighbours`` nearest learnt frames' (NaN for a non-finite one)."""
        if not np.all(np.isfinite(light)):
            return math.nan
        d2 = ((self.levels - light) ** 2).sum(axis=1)
        k = min(neighbours, d2.size)
        return float(np.sqrt(np.partition(d2, k - 1)[:k]).mean())

    def reference(self, percentile: float) -> float:
        """The distance up to which a frame's light is as familiar as the recordings' (never below ``REFERENCE_MIN``)."""
        return max(float(np.percentile(self.calibration, percentile)), REFERENCE_MIN)

    def nearest(self, light: np.ndarray) -> np.ndarray:
        """The learnt frame's light nearest to this one (for the reasons)."""
        return self.levels[int(np.argmin(((self.levels - light) ** 2).sum(axis=1)))]


def frame_light(frame: object) -> np.ndarray | None:
    """One frame's light (``LIGHT_PERCENTILES`` of its grey levels, log scale 0..1), or None when it is not a picture."""
    bgr = as_bgr(frame)
    if bgr is None:
        return None
    grey = cv2.cvtColor(cv2.resize(bgr, WORK_PX, interpolation=cv2.INTER_AREA), cv2.COLOR_BGR2GRAY)
    return np.log1p(np.percentile(grey, LIGHT_PERCENTILES)) / LOG_GREY


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
