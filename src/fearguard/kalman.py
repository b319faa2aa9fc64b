"""filterpy's Kalman filter and process noise, imported on first use and without scipy.stats or scipy.ndimage.

``import filterpy.kalman`` imports the whole filterpy package. Two of its parts cost a start-up for nothing here:
``filterpy.stats`` imports scipy.stats (0.5–0.8 s here, several seconds on a Raspberry Pi) for one function the
filters call, ``logpdf``, behind the ``likelihood`` properties fearguard never reads; ``filterpy.discrete_bayes``
imports scipy.ndimage (~0.1 s) and no filter uses it. fearguard's trackers get their filters here: filterpy is
imported when the first filter is made, with those two standing in as modules (``logpdf`` imports the real one when
first called). The stand-ins are removed once filterpy is imported, so ``import filterpy.stats`` or
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


def _logpdf(*args: Any, **kwargs: Any) -> Any:
    """``filterpy.stats.logpdf``, imported when first called (a filter's likelihood is asked for)."""
    return importlib.import_module(_STATS).logpdf(*args, **kwargs)


def _import_filterpy() -> None:
    """Import filterpy with ``filterpy.stats`` and ``filterpy.discrete_bayes`` left for later, unless filterpy or
    scipy.stats is already loaded (then nothing is saved)."""
    if "filterpy" in sys.modules or "scipy.stats" in sys.modules:
        importlib.import_module("filterpy.kalman")
        return
    stand_ins = {name: types.ModuleType(name, f"{name}, imported on first use (fearguard.kalman)") for name in _DEFERRED}
    stand_ins[_STATS].logpdf = _logpdf  # type: ignore[attr-defined]  # the one name filterpy's filters take from it
    sys.modules.update(stand_ins)
    try:
        importlib.import_module("filterpy.kalman")
    finally:
        package = sys.modules.get("filterpy")
        for name, stand_in in stand_ins.items():
            if sys.modules.get(name) is stand_in:
                del sys.modules[name]
            attr = name.rpartition(".")[2]
            if package is not None and getattr(package, attr, None) is stand_in:
                delattr(package, attr)  # ``filterpy.<attr>`` resolves to the real module when it is first imported


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
