"""filterpy's Kalman filter and process noise, imported on first use.

``import filterpy.kalman`` imports filterpy.stats and with it scipy.stats (about 0.7 s): fearguard's
trackers get their filters here, so ``import fearguard`` does not pay that and a car pays it once, when
its first filter is made.
"""

from __future__ import annotations

from typing import TYPE_CHECKING

import numpy as np

if TYPE_CHECKING:
    from filterpy.kalman import KalmanFilter


def kalman_filter(dim_x: int, dim_z: int) -> KalmanFilter:
    """A new ``filterpy.kalman.KalmanFilter(dim_x, dim_z)``."""
    from filterpy.kalman import KalmanFilter

    return KalmanFilter(dim_x=dim_x, dim_z=dim_z)


def white_noise_q(dim: int, dt: float, var: float) -> np.ndarray:
    """``filterpy.common.Q_discrete_white_noise(dim, dt, var)``: process noise of a piecewise white acceleration."""
    from filterpy.common import Q_discrete_white_noise

    return Q_discrete_white_noise(dim=dim, dt=dt, var=var)
