"""The risk cues: names, units, physical ranges and their worst values.

Five are measured on every car; the sixth, ``familiarity``, exists only with a learnt track profile
(``fearguard learn``, docs/learning.md): a car without one has no such cue, and it reads 1 (like the recordings,
calm), as QR staleness reads 0 on a car without QR localisation.

A cue that is NaN, outside its physical range, or not a number is *unknown*, and unknown is the
worst case (docs/architecture.md, invariant 4). This module is the one place that decides what unknown means;
what counts as a number at all is decided by ``readings.py``.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from enum import Enum

import numpy as np

from fearguard.errors import describe
from fearguard.readings import cue_value, reading

CUE_NAMES: tuple[str, ...] = (
    "lane_confidence",
    "brightness",
    "occlusion",
    "obstacle_range_m",
    "qr_staleness_s",
    "familiarity",
)


class Worsens(Enum):
    """How a cue gets worse: which direction raises fear."""

    WHEN_LOWER = "lower"  # e.g. lane_confidence, obstacle_range_m
    WHEN_HIGHER = "higher"  # e.g. occlusion, qr_staleness_s
    AWAY_FROM_BAND = "band"  # brightness: too dark and glare are both risky


@dataclass(frozen=True)
class CueSpec:
    """Every fact about one cue, in one place: everything else (checks, samplers, plots, calm pictures) derives from it.

    ``worst`` and ``calm`` are None for brightness: they depend on the rule file's normal band (its two ends are both
    worst; its middle is calm). ``span``: how far an open-ended cue is worth sampling when a rule file has no variable
    for it. ``panel``: the timeline panel it is drawn on.
    """

    name: str
    low: float
    high: float
    worsens: Worsens
    worst: float | None
    unit: str = ""
    calm: float | None = None
    span: float = 1.0
    panel: str = "share"


CUE_SPECS: tuple[CueSpec, ...] = (
    CueSpec("lane_confidence", 0.0, 1.0, Worsens.WHEN_LOWER, 0.0, unit="0..1", calm=1.0, panel="share"),
    CueSpec("brightness", 0.0, 255.0, Worsens.AWAY_FROM_BAND, None, unit="grey level 0..255", span=255.0, panel="light"),
    CueSpec("occlusion", 0.0, 1.0, Worsens.WHEN_HIGHER, 1.0, unit="share hidden 0..1", calm=0.0, panel="share"),
    CueSpec("obstacle_range_m", 0.0, math.inf, Worsens.WHEN_LOWER, 0.0, unit="m", calm=math.inf, span=10.0, panel="range"),
    CueSpec("qr_staleness_s", 0.0, math.inf, Worsens.WHEN_HIGHER, math.inf, unit="s", calm=0.0, span=40.0, panel="staleness"),
    CueSpec("familiarity", 0.0, 1.0, Worsens.WHEN_LOWER, 0.0, unit="0..1 like the learnt track", calm=1.0, panel="share"),
)
assert tuple(s.name for s in CUE_SPECS) == CUE_NAMES  # one order: the contract of evaluate_batch
BRIGHTNESS = CUE_NAMES.index("brightness")
OBSTACLE_RANGE = CUE_NAMES.index("obstacle_range_m")
QR_STALENESS = CUE_NAMES.index("qr_staleness_s")
FAMILIARITY = CUE_NAMES.index("familiarity")
MEASURED_CUES = FAMILIARITY  # the five cues every car has come first: an (N, 5) batch is a car without a track profile
_LOWS = [s.low for s in CUE_SPECS]
_HIGHS = [s.high for s in CUE_SPECS]
_LOW = np.array(_LOWS)
_HIGH = np.array([s.high for s in CUE_SPECS])
# brightness has two worst values (0 and 255); the fuzzy engine tries both and keeps the larger fear
_WORST = np.array([s.worst if s.worst is not None else np.nan for s in CUE_SPECS])


@dataclass(frozen=True)
class Cues:
    """One frame's cues in their physical units; any field may be NaN (= unknown = worst).

    ``familiarity`` defaults to 1.0 (like the learnt track): the five-field ``Cues(...)`` of a car without a track
    profile, for which the cue does not apply."""

    lane_confidence: float
    brightness: float
    occlusion: float
    obstacle_range_m: float
    qr_staleness_s: float
    familiarity: float = 1.0

    def values(self) -> list[float]:
        """The cues as floats in CUE_NAMES order; a field that is not a reading (readings.py: text, bytes,
        bools, Decimal, arrays, ...) becomes NaN, which is unknown = worst. The fields are read as they are
        (``dataclasses.astuple`` would deep-copy each one: slower, and a hostile object's ``__deepcopy__`` could raise)."""
        return [cue_value(getattr(self, name)) for name in CUE_NAMES]

    def as_array(self) -> np.ndarray:
        """The cues as a float vector in CUE_NAMES order (non-numbers become NaN)."""
        return np.array(self.values(), dtype=float)


def calm_values(brightness_band: tuple[float, float]) -> tuple[float, ...]:
    """The calmest picture, in CUE_NAMES order: each cue at its calm value, brightness in the middle of the band."""
    middle = (brightness_band[0] + brightness_band[1]) / 2.0
    return tuple(middle if spec.calm is None else spec.calm for spec in CUE_SPECS)


def unknown_note(name: str, raw: object) -> str | None:
    """Why one cue's value counts as its worst (None when it is a valid reading): the one sentence for every caller.

    ``raw`` is the value as given (the note names it); what is a number is ``readings.reading``'s decision, what is
    inside the cue's range this module's ``CUE_SPECS``.
    """
    spec = CUE_SPECS[CUE_NAMES.index(name)]
    value = reading(raw)
    if value is None:
        return f"{name} {describe(raw)} is not a number: counted as its worst value"
    if math.isnan(value):
        return f"{name} unknown (NaN): counted as its worst value"
    if not spec.low <= value <= spec.high:
        high = "inf" if math.isinf(spec.high) else f"{spec.high:g}"
        return f"{name} {value!r} is outside {spec.low:g}..{high}: counted as its worst value"
    return None


def worst_filled(values: list[float], brightness_worst: float) -> tuple[list[float], list[bool]]:
    """Scalar twin of ``with_worst`` for the per-frame path: (values with unknowns replaced, unknown flags)."""
    unknown = [not (lo <= v <= hi) for lo, hi, v in zip(_LOWS, _HIGHS, values, strict=True)]
    if not any(unknown):
        return values, unknown
    filled = [
        (brightness_worst if spec.worst is None else spec.worst) if bad else v
        for spec, v, bad in zip(CUE_SPECS, values, unknown, strict=True)
    ]
    return filled, unknown


def unknown_mask(x: np.ndarray) -> np.ndarray:
    """True where a cue is unknown: NaN or outside its physical range (inf is valid only as a range)."""
    x = np.asarray(x, dtype=float)
    with np.errstate(invalid="ignore"):
        return np.isnan(x) | (x < _LOW) | (x > _HIGH)


def with_worst(x: np.ndarray, brightness_worst: float) -> np.ndarray:
    """Replace unknown cues by their worst value (brightness by the given extreme, 0 or 255)."""
    x = np.array(x, dtype=float)
    worst = _WORST.copy()
    worst[BRIGHTNESS] = brightness_worst
    bad = unknown_mask(x)
    return np.where(bad, np.broadcast_to(worst, x.shape), x)
