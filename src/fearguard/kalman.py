"""filterpy's Kalman filter and process noise, imported on first use and without scipy.stats.

``import filterpy.kalman`` imports ``filterpy.stats``, which imports scipy.stats (0.5–0.8 s here, several seconds on a
Raspberry Pi) for one function the filters call: ``logpdf``, behind the ``likelihood`` properties fearguard never
reads. fearguard's trackers get their filters here: filterpy is imported when the first filter is made, with
``filterpy.stats`` standing in as a module whose ``logpdf`` imports the real one when first called. The stand-in is
removed once filterpy is imported, so ``import filterpy.stats`` anywhere else gets the real module.
"""

from __future__ import annotations

import importlib
import sys
import types
from typing import TYPE_CHECKING, Any

import numpy as np

if TYPE_CHECKING:
    from filterpy.kalman import KalmanFilter

_STATS = "filterpy.stats"


def _logpdf(*args: Any, **kwargs: Any) -> Any:
    """``filterpy.stats.logpdf``, imported when first called (a filter's likelihood is asked for)."""
    return importlib.import_module(_STATS).logpdf(*args, **kwargs)


def _import_filterpy() -> None:
    """Import filterpy with ``filterpy.stats`` (and so scipy.stats) left for later, unless either is already loaded."""
    if "filterpy" in sys.modules or _STATS in sys.modules or "scipy.stats" in sys.modules:
        importlib.import_module("filterpy.kalman")
        return
    stand_in = types.ModuleType(_STATS, "filterpy.stats, imported on first use (fearguard.kalman)")
    stand_in.logpdf = _logpdf  # type: ignore[attr-defined]  # the one name filterpy's filters take from it
    sys.modules[_STATS] = stand_in
    try:
        importlib.import_module("filterpy.kalman")
    finally:
        if sys.modules.get(_STATS) is stand_in:
            del sys.modules[_STATS]
        package = sys.modules.get("filterpy")
        if package is not None and getattr(package, "stats", None) is stand_in:
            del package.stats  # ``filterpy.stats`` resolves to the real module when it is first imported


def kalman_filter(dim_x: int, dim_z: int) -> KalmanFilter:
    """A new ``filterpy.kalman.KalmanFilter(dim_x, dim_z)``."""
    if "filterpy.kalman" not in sys.modules:
        _import_filterpy()
    from filterpy.kalman import KalmanFilter

    return KalmanFilter(dim_x=dim_x, dim_z=dim_z)


def white_noise_q(dim: int, dt: float, var: float) -> np.ndarray:
    """``filterpy.common.Q_discrete_white_noise(dim, dt, var)``: process noise of a piecewise white acceleration."""
    if "filterpy.kalman" not in sys.modules:
        _import_filterpy()
    from filterpy.common import Q_discrete_white_noise

    return Q_discrete_white_noise(dim=dim, dt=dt, var=var)
