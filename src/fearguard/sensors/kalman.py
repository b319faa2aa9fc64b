"""filterpy's Kalman filter and process noise, imported on first use and without scipy.stats, scipy.ndimage or
scipy.linalg.

``import filterpy.kalman`` imports the whole filterpy package. Three imports in it cost a start-up for nothing here:
``filterpy.stats`` imports scipy.stats (0.5–0.8 s here, several seconds on a Raspberry Pi) for one function the
filters call, ``logpdf``, behind the ``likelihood`` properties fearguard never reads; ``filterpy.discrete_bayes``
imports scipy.ndimage (~0.1 s) and no filter uses it; the other filters (UKF, EKF, square-root, ...) and
``filterpy.common`` take functions from scipy.linalg (~0.25 s) that the linear ``KalmanFilter`` never calls.
fearguard's trackers get their filters here: filterpy is imported when the first filter is made, with those three
standing in as modules (``logpdf``, and any scipy.linalg function filterpy took, import the real module when first
called). The stand-ins are removed once filterpy is imported, so ``import filterpy.stats``, ``scipy.linalg`` or
``filterpy.discrete_bayes`` anywhere else gets the real module.
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
_DEFERRED = (_STATS, "filterpy.discrete_bayes")  # imported by filterpy's __init__, used by no filter fearguard makes
_LINALG = "scipy.linalg"  # imported by filterpy's other filters and filterpy.common, called by none fearguard makes


def _logpdf(*args: Any, **kwargs: Any) -> Any:
    """``filterpy.stats.logpdf``, imported when first called (a filter's likelihood is asked for)."""
    return importlib.import_module(_STATS).logpdf(*args, **kwargs)


class _LinalgStandIn(types.ModuleType):
    """scipy.linalg while filterpy imports: every name taken from it (filterpy takes only functions: cholesky, qr,
    inv, pinv, expm, block_diag) is a function that imports the real module when first called."""

    def __getattr__(self, name: str) -> Any:
        if name.startswith("__"):
            raise AttributeError(name)

        def call(*args: Any, **kwargs: Any) -> Any:
            return getattr(importlib.import_module(_LINALG), name)(*args, **kwargs)

        call.__name__ = call.__qualname__ = name
        return call


def _import_filterpy() -> None:
    """Import filterpy with ``filterpy.stats``, ``filterpy.discrete_bayes`` and scipy.linalg left for later, unless
    filterpy or scipy.stats is already loaded (then nothing is saved); scipy.linalg when it is not loaded yet."""
    if "filterpy" in sys.modules or "scipy.stats" in sys.modules:
        importlib.import_module("filterpy.kalman")
        return
    stand_ins = {name: types.ModuleType(name, f"{name}, imported on first use (fearguard.sensors.kalman)") for name in _DEFERRED}
    stand_ins[_STATS].logpdf = _logpdf  # type: ignore[attr-defined]  # the one name filterpy's filters take from it
    if _LINALG not in sys.modules:
        stand_ins[_LINALG] = _LinalgStandIn(_LINALG, f"{_LINALG}, imported on first use (fearguard.sensors.kalman)")
    sys.modules.update(stand_ins)
    try:
        importlib.import_module("filterpy.kalman")
    finally:
        for name, stand_in in stand_ins.items():
            if sys.modules.get(name) is stand_in:
                del sys.modules[name]
            parent, _, attr = name.rpartition(".")
            package = sys.modules.get(parent)
            if package is not None and package.__dict__.get(attr) is stand_in:
                delattr(package, attr)  # ``<parent>.<attr>`` resolves to the real module when it is first imported


def kalman_filter(dim_x: int, dim_z: int) -> KalmanFilter:
    """A new ``filterpy.kalman.KalmanFilter(dim_x, dim_z)``."""
    if "filterpy.kalman" not in sys.modules:
        _import_filterpy()
    from filterpy.kalman import KalmanFilter

    return KalmanFilter(dim_x=dim_x, dim_z=dim_z)


def white_noise_q(dim: int, dt: float, var: float) -> np.ndarray:
    """``filterpy.common.Q_discrete_white_noise(dim, dt, var)``: process noise of a piecewise white acceleration.

    ``order_by_dim=False``: for one block the same matrix, built without scipy.linalg's ``block_diag``."""
    if "filterpy.kalman" not in sys.modules:
        _import_filterpy()
    from filterpy.common import Q_discrete_white_noise

    return Q_discrete_white_noise(dim=dim, dt=dt, var=var, order_by_dim=False)
