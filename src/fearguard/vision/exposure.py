"""Exposure of the road region: mean luminance (the brightness cue) and the clipped pixel shares.

The review behind fearguard names the mean pixel value as the quick check of exposure; the shares of
saturated and black pixels say *why* a brightness is risky (glare washes markings out, night hides them).
"""

from __future__ import annotations

from dataclasses import dataclass

import cv2
import numpy as np

SATURATED_MIN = 250  # [grey level] at or above: clipped white
BLACK_MAX = 10  # [grey level] at or below: crushed black


@dataclass(frozen=True)
class Exposure:
    """Mean luminance of the road region (0..255) and the shares of clipped pixels in it."""

    brightness: float
    saturated_share: float
    black_share: float


def road_exposure(gray: np.ndarray, mask: np.ndarray) -> Exposure:
    """Exposure over the mask (uint8 0/255) of a grey image; an empty mask gives NaN (unknown)."""
    n = cv2.countNonZero(mask)
    if n == 0:
        return Exposure(float("nan"), float("nan"), float("nan"))
    brightness = cv2.mean(gray, mask)[0]
    saturated = cv2.countNonZero(cv2.bitwise_and(cv2.inRange(gray, SATURATED_MIN, 255), mask)) / n
    black = cv2.countNonZero(cv2.bitwise_and(cv2.inRange(gray, 0, BLACK_MAX), mask)) / n
    return Exposure(float(brightness), float(saturated), float(black))
