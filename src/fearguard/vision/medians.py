"""The median of a frame's small arrays, equal to ``np.median`` but without its per-call overhead.

``np.median`` goes through several layers of wrappers (``_ureduce``, a NaN check, ``np.mean`` of the middle
elements): on the few hundred values a frame's road model or a confidence history holds, that overhead is most of
its cost (~20-40 µs a call, several calls a frame). One ``np.partition`` does the work; the result is the same
number (the mean of the two middle elements for an even count, computed as ``np.median`` does; NaN if any value is
NaN). Written by hand because numpy has no cheaper exact median.
"""

from __future__ import annotations

import numpy as np


def median(values: np.ndarray, axis: int | None = None) -> np.ndarray | np.generic:
    """``np.median(values, axis)`` (axis None: over all values); NaN over no values, as np.median (without its warning)."""
    x = np.asarray(values)
    if axis is None:
        x, axis = x.reshape(-1), 0
    n = x.shape[axis]
    if n == 0:
        return np.full(np.delete(x.shape, axis), np.nan)[()]
    k = (n - 1) // 2
    floats = x.dtype.kind == "f"
    # the middle element(s); for floats the last too: a NaN sorts last, and any NaN makes the median NaN (as np.median)
    kth = [k] + ([k + 1] if n % 2 == 0 else []) + ([n - 1] if floats and n - 1 > k + 1 else [])
    part = np.partition(x, kth, axis=axis)
    mid = part.take(k, axis)
    if not floats:  # integers (and bools) average in float64, as np.mean does
        mid = mid.astype(np.float64)
    if n % 2 == 0:
        mid = (mid + part.take(k + 1, axis).astype(mid.dtype)) / 2
    if floats:
        nan = np.isnan(part.take(n - 1, axis))
        if nan.any():
            mid = np.where(nan, np.nan, mid).astype(x.dtype)
    return mid
