"""What counts as a reading: the one decision, for every number fearguard takes in, of what is a number.

A *reading* is a real number (``numbers.Real``): ``int``, ``float``, numpy integer and floating scalars,
``Fraction`` (a real number, exactly; ``Lead(bearing_deg=Fraction(1, 3))`` is a bearing of 1/3°).
NaN and ±inf are readings (they mean unknown, or "nothing in range", to whoever reads them).

Not readings, whatever ``float()`` would make of them:

- ``bool`` and ``numpy.bool_``: a flag is not a measurement (``True`` is not 1 m);
- ``str`` and ``bytes``: text is not a measurement (``"inf"`` must not read as a clear road);
- ``Decimal``: not a ``numbers.Real`` (decimal arithmetic does not mix with floats; a caller converts);
- arrays, also 0-d ones, and every other container or object: a measurement is one scalar;
- a real number that cannot become a float (an ``int`` of 310 digits, an object whose ``__float__``
  raises): no float can stand for it.

A value that is not a reading is *unknown* to its user, which for a cue means its worst value.
"""

from __future__ import annotations

import math
from numbers import Real

import numpy as np


def reading(value: object) -> float | None:
    """The value as a float (NaN and ±inf kept) if it is a reading, else None."""
    if isinstance(value, bool | np.bool_) or not isinstance(value, Real):
        return None
    try:
        return float(value)
    except Exception:  # a Real whose conversion fails (overflow, a broken __float__) is no reading
        return None


def finite_reading(value: object) -> float | None:
    """The value as a finite float if it is a reading, else None (NaN and ±inf are not finite)."""
    f = reading(value)
    return f if f is not None and math.isfinite(f) else None


def cue_value(value: object) -> float:
    """A cue field as a float: its reading, NaN (unknown = worst) when it is not one."""
    f = reading(value)
    return math.nan if f is None else f


def whole_number(value: object) -> int | None:
    """An ``int`` or numpy integer as an int (bools are not whole numbers here), else None."""
    if isinstance(value, bool | np.bool_) or not isinstance(value, int | np.integer):
        return None
    return int(value)

