"""Exposure of the road region: mean luminance (the brightness cue), the clipped pixel shares and the noise.

The review behind fearguard names the mean pixel value as the quick check of exposure; the shares of
saturated and black pixels say *why* a brightness is risky (glare washes markings out, night hides them).
The noise level tells dim light with a clean picture (deep shade by day) from a dark, noisy one (night):

    noise_grey = sqrt(π/2) · mean |I ∗ N| / 6,   N = [[1, −2, 1], [−2, 4, −2], [1, −2, 1]]

(Immerkær 1996, "Fast noise variance estimation": N is the difference of two Laplacians, blind to
linear brightness gradients; texture counts as noise, so the estimate errs on the noisy side.)
Written by hand: one OpenCV filter and a masked mean; no library ships this estimator for a masked region.
"""

from __future__ import annotations

from dataclasses import dataclass

import cv2
import numpy as np

SATURATED_MIN = 250  # [grey level] at or above: clipped white
BLACK_MAX = 10  # [grey level] at or below: crushed black
_LEVELS = np.arange(256, dtype=np.float64)


@dataclass(frozen=True)
class Exposure:
    """Mean luminance of the road region (0..255) and the shares of clipped pixels in it."""

    brightness: float
    saturated_share: float
    black_share: float
    noise_grey: float = float("nan")  # [grey levels] standard deviation of the sensor noise (NaN: unknown)

    @property
    def signal_to_noise(self) -> float:
        """Mean luminance over noise (ISO 12232's S/N: 10 is an "acceptable", 40 an "excellent" picture); inf if noiseless."""
        if not self.noise_grey > 0.0:
            return float("inf") if self.noise_grey == 0.0 else float("nan")
        return self.brightness / self.noise_grey


def road_exposure(gray: np.ndarray, mask: np.ndarray) -> Exposure:
    """Exposure over the mask (uint8 0/255) of a grey image; an empty mask gives NaN (unknown)."""
    hist = cv2.calcHist([gray], [0], mask, [256], [0, 256]).ravel()  # one pass gives the mean and both clipped shares
    n = float(hist.sum())  # counts are exact in float32 up to 2²⁴ pixels
    if n == 0:
        return Exposure(float("nan"), float("nan"), float("nan"))
    brightness = float(hist.astype(np.float64) @ _LEVELS) / n
    saturated = float(hist[SATURATED_MIN:].sum()) / n
    black = float(hist[: BLACK_MAX + 1].sum()) / n
    return Exposure(brightness, saturated, black, noise_grey(gray, mask))


def noise_grey(gray: np.ndarray, mask: np.ndarray) -> float:
    """Immerkær's noise estimate (grey levels) over the mask's pixels; NaN if the image is too small for the 3×3 kernel."""
    if min(gray.shape[:2]) < 3:
        return float("nan")
    # N is the separable second-derivative Sobel kernel (∂²/∂u²∂v², 3×3): OpenCV's Sobel computes it exactly in 16-bit
    # integers (|I ∗ N| ≤ 16 · 255) at ~0.4 of a general filter2D's cost
    response = np.abs(cv2.Sobel(gray, cv2.CV_16S, 2, 2, ksize=3, borderType=cv2.BORDER_REPLICATE))
    return float(np.sqrt(np.pi / 2.0) * cv2.mean(response, mask)[0] / 6.0)
