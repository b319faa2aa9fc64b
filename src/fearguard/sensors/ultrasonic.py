"""HC-SR04-style ultrasonic readings → the ``obstacle_range_m`` cue, its closing speed and time to collision.

A reading is converted (d[cm] = 17150 × echo[s]), checked (impossible values are rejected with a reason;
at/beyond the maximum range, or ``inf``, means "nothing in range"), gated against the track, and smoothed by a
filterpy Kalman filter with a constant-velocity model, state [range m, range rate m/s], over the real time step.
Safety asymmetry: a reading outside the gate is a candidate, not noise. A *closer* one is confirmed as soon as
2 of the last 3 readings agree (a box dropped in front of the car), a *farther* one (or "nothing in range") needs
all 3 (a lost echo must not clear a real obstacle); a confirmed candidate re-initialises the track there. With no
track (start-up, after a long gap) a range starts one at once, while "nothing in range" needs 2 agreeing readings.
Short gaps (no reading, or only rejected ones, for ≤ ``dropout_hold_s``) are bridged by the prediction, never
farther than the last accepted reading; longer ones give NaN = unknown, which the supervisor counts as worst (0 m),
while the track still gates new readings for up to ``memory_s``.
"""

from __future__ import annotations

import math
from collections import deque
from dataclasses import dataclass
from enum import Enum

import numpy as np

from fearguard import readings
from fearguard.sensors.kalman import kalman_filter, white_noise_q

HALF_SPEED_OF_SOUND_MPS = 171.5  # [m/s] 343 m/s at 20 °C, halved: the echo travels there and back (17150 cm/s)
HC_SR04_MIN_RANGE_M = 0.15  # [m] 6 in (0.1524 m), lower end of the usable range reported for the HC-SR04
HC_SR04_MAX_RANGE_M = 3.96  # [m] 156 in (3.9624 m), upper end; readings at/beyond it mean "nothing in range"
DROPOUT_HOLD_S = 0.3  # [s] longest gap bridged by the prediction (about 1.5 frames at the Pi car's 5 frames/s)
MEASUREMENT_STD_M = 0.02  # [m] reading noise: 3 mm resolution, ~1-2 cm spread on real surfaces
ACCEL_STD_MPS2 = 1.0  # [m/s²] white-noise relative acceleration of the model (3 m/s² braking still tracked, see docs)
INIT_SPEED_STD_MPS = 1.0  # [m/s] uncertainty of the range rate when a track starts
GATE_SIGMA = 4.0  # innovation gate in standard deviations of the innovation
MIN_GATE_M = 0.2  # [m] the gate is never narrower than this (10 × the reading noise)
AGREE_M = 0.3  # [m] two readings taken at the same time "agree" within this
MAX_CLOSING_SPEED_MPS = 3.0  # [m/s] fastest plausible range change (model car ≤ 2 m/s): agreement widens by this × Δt,
#                               and a new track's range rate (from two readings) is bounded by it
CONFIRM_WINDOW = 3  # readings looked back at when confirming a candidate
CONFIRM_CLOSER = 2  # of the window: agreeing readings that confirm a closer obstacle
CONFIRM_FARTHER = 3  # of the window: agreeing readings that confirm a farther one or "nothing in range"
TIME_EPS_S = 1e-9  # [s] slack in time comparisons, so that 3 steps of 0.1 s count as 0.3 s
MEMORY_S = 1.0  # [s] a track is forgotten, and readings stop counting towards a confirmation, after this long


class ReadingKind(Enum):
    """What one raw reading is, before any tracking."""

    NONE = "none"  # no reading this frame (driver timeout / dropout)
    INVALID = "invalid"  # impossible: rejected with a reason
    CLEAR = "clear"  # at/beyond the maximum range or inf: nothing in range
    RANGE = "range"  # a usable distance


@dataclass(frozen=True)
class Reading:
    """One classified reading: ``value_m`` is the number given (NaN when none or not a number)."""

    kind: ReadingKind
    value_m: float
    reason: str = ""

    @property
    def track_m(self) -> float:
        """The value the tracker uses: inf for "nothing in range", NaN for no/impossible readings."""
        return {ReadingKind.CLEAR: math.inf, ReadingKind.RANGE: self.value_m}.get(self.kind, math.nan)


@dataclass(frozen=True)
class RangeEstimate:
    """One frame's filtered range (inf = nothing in range, NaN = unknown = worst), closing speed (+ = approaching), TTC."""

    range_m: float
    closing_speed_mps: float
    ttc_s: float
    raw_m: float
    accepted: bool
    reason: str
    gate_m: float = math.nan  # innovation gate used this frame (NaN when there was no track to gate against)


# -- pure helpers ---------------------------------------------------------------------------
def echo_to_range_m(echo_s: object) -> float | None:
    """Echo pulse width (s) → range (m) = 171.5 × echo; None for NaN, ≤ 0 or non-numbers (inf stays inf)."""
    echo = readings.reading(echo_s)
    if echo is None or math.isnan(echo) or echo <= 0:
        return None
    return HALF_SPEED_OF_SOUND_MPS * echo


def classify_reading(range_m: object, min_range_m: float = HC_SR04_MIN_RANGE_M, max_range_m: float = HC_SR04_MAX_RANGE_M) -> Reading:
    """Sort a raw range into none / invalid (with the reason) / clear (nothing in range) / a usable range."""
    if range_m is None:
        return Reading(ReadingKind.NONE, math.nan, "no reading")
    value = readings.reading(range_m)
    if value is None:
        return Reading(ReadingKind.INVALID, math.nan, f"reading {_short(range_m)} is not a number")
    if math.isnan(value):
        return Reading(ReadingKind.INVALID, math.nan, "reading is NaN")
    if value <= 0:
        return Reading(ReadingKind.INVALID, value, f"reading {value:g} m is not a positive distance")
    if value < min_range_m:
        return Reading(ReadingKind.INVALID, value, f"reading {value:.3f} m is below the minimum range {min_range_m:.2f} m")
    if value >= max_range_m:
        return Reading(ReadingKind.CLEAR, value, "nothing in range")
    return Reading(ReadingKind.RANGE, value)


def time_to_collision_s(range_m: float, closing_speed_mps: float) -> float:
    """Range / closing speed; inf when not closing or nothing in range, NaN when either is unknown."""
    if math.isnan(range_m) or math.isnan(closing_speed_mps):
        return math.nan
    if closing_speed_mps <= 0 or math.isinf(range_m):
        return math.inf
    return range_m / closing_speed_mps


def _short(value: object) -> str:
    """A garbage value shown in a reason, never very long (repr of anything may fail: then its type)."""
    try:
        text = repr(value)
    except Exception:  # a foreign object's __repr__ is arbitrary code
        text = f"<{type(value).__name__}>"
    return text if len(text) <= 40 else text[:37] + "..."


def _agree(a: float, b: float, tolerance_m: float) -> bool:
    """Two readings agree: both "nothing in range", or both finite and within the tolerance."""
    if math.isinf(a) or math.isinf(b):
        return math.isinf(a) and math.isinf(b)
    return abs(a - b) <= tolerance_m


class _Track(Enum):
    NONE = "none"  # nothing known: a range starts a track at once, "nothing in range" must be confirmed
    CLEAR = "clear"  # nothing in range (no Kalman state)
    RANGE = "range"  # Kalman track of an obstacle


class UltrasonicFilter:
    """Stateful filter: one ``update`` per frame (time passed in) → RangeEstimate. Never raises on bad input."""

    def __init__(
        self,
        min_range_m: float = HC_SR04_MIN_RANGE_M,
        max_range_m: float = HC_SR04_MAX_RANGE_M,
        dropout_hold_s: float = DROPOUT_HOLD_S,
        memory_s: float = MEMORY_S,
        measurement_std_m: float = MEASUREMENT_STD_M,
        accel_std_mps2: float = ACCEL_STD_MPS2,
        gate_sigma: float = GATE_SIGMA,
        min_gate_m: float = MIN_GATE_M,
        agree_m: float = AGREE_M,
        max_closing_speed_mps: float = MAX_CLOSING_SPEED_MPS,
        confirm_closer: int = CONFIRM_CLOSER,
        confirm_farther: int = CONFIRM_FARTHER,
    ) -> None:
        if not (0 < min_range_m < max_range_m < math.inf):
            raise ValueError(f"need 0 < min_range_m < max_range_m < inf, got {min_range_m!r}, {max_range_m!r}")
        for name, value in (("dropout_hold_s", dropout_hold_s), ("measurement_std_m", measurement_std_m),
                            ("accel_std_mps2", accel_std_mps2), ("gate_sigma", gate_sigma), ("min_gate_m", min_gate_m),
                            ("agree_m", agree_m), ("max_closing_speed_mps", max_closing_speed_mps)):
            if not (math.isfinite(value) and value > 0):
                raise ValueError(f"{name} must be a finite number > 0, got {value!r}")
        if not memory_s >= dropout_hold_s:
            raise ValueError(f"memory_s ({memory_s!r}) must be at least dropout_hold_s ({dropout_hold_s!r})")
        if not (1 <= confirm_closer <= CONFIRM_WINDOW and 1 <= confirm_farther <= CONFIRM_WINDOW):
            raise ValueError(f"confirm_closer/confirm_farther must be in 1..{CONFIRM_WINDOW}, got {confirm_closer}, {confirm_farther}")
        self.min_range_m, self.max_range_m, self.dropout_hold_s, self.memory_s = min_range_m, max_range_m, dropout_hold_s, memory_s
        self.measurement_std_m, self.accel_std_mps2 = measurement_std_m, accel_std_mps2
        self.gate_sigma, self.min_gate_m = gate_sigma, min_gate_m
        self.agree_m, self.max_closing_speed_mps = agree_m, max_closing_speed_mps
        self.confirm_closer, self.confirm_farther = confirm_closer, confirm_farther
        self.reset()

    def reset(self) -> None:
        """Forget everything (track, readings, clock): the next call starts as at power-up.

        The filter (and with it filterpy and scipy.linalg, about a second on a Pi) is made here, when the FearGuard is
        built, on purpose: made on first use, that import stalled the first frame of a 20 Hz Donkey loop
        past the watchdog (EMERGENCY on 20 % of the easy drive)."""
        self._kf = kalman_filter(dim_x=2, dim_z=1)
        self._kf.H = np.array([[1.0, 0.0]])
        self._kf.R = np.array([[self.measurement_std_m**2]])
        self._track = _Track.NONE
        self._last_t_s: float | None = None  # last call with a valid time
        self._kf_t_s = math.nan  # time of the Kalman state
        self._accepted_t_s = math.nan  # time of the last accepted reading
        self._accepted_m = math.nan  # value of the last accepted reading
        # the last readings as (t_s, value_m, on_track): NaN = impossible; on_track = consistent with the track then
        self._recent: deque[tuple[float, float, bool]] = deque(maxlen=CONFIRM_WINDOW)

    # -- the frame ----------------------------------------------------------------------------
    def update(self, t_s: float, range_m: float | None = None, echo_s: float | None = None) -> RangeEstimate:
        """One frame: ``range_m`` (m) or, when it is None, ``echo_s`` (s); both None = no reading this frame."""
        try:
            return self._update(t_s, range_m, echo_s)
        except Exception as exc:  # last line of defence: a bug here must not crash the car's loop
            self.reset()  # the state may be half-updated: start again from nothing known
            return _unknown(math.nan, f"ultrasonic: internal error {type(exc).__name__}: {exc}: range unknown, filter reset")

    def _update(self, t_s: object, range_m: object, echo_s: object) -> RangeEstimate:
        reading = self._reading(range_m, echo_s)
        t = readings.reading(t_s)
        if t is None or not math.isfinite(t):
            return _unknown(reading.value_m, f"ultrasonic: time t_s={_short(t_s)} is not a finite number: range unknown")
        if self._last_t_s is not None and t <= self._last_t_s:
            last = self._last_t_s
            self.reset()  # the clock restarts at t (as the supervisor's does): a wild time stamp cannot stop it for good
            self._last_t_s = t
            return _unknown(reading.value_m, f"ultrasonic: time did not increase ({last:.3f} s → {t:.3f} s): range unknown, "
                                             "filter restarted")
        self._last_t_s = t
        if self._track is not _Track.NONE and t - self._accepted_t_s > self.memory_s + TIME_EPS_S:
            self._track = _Track.NONE  # too old to gate against: the next readings start afresh
        if self._track is _Track.RANGE:
            self._predict(t)
        if reading.kind is ReadingKind.INVALID:  # impossible readings take a place in the window but agree with nothing
            self._recent.append((t, math.nan, False))
        if reading.kind in (ReadingKind.RANGE, ReadingKind.CLEAR):
            estimate = self._use(t, reading)
            if estimate is not None:
                return estimate
            why = self._candidate_reason(reading)
        else:
            why = reading.reason
        return self._hold(t, reading, why)

    def _reading(self, range_m: object, echo_s: object) -> Reading:
        if range_m is None and echo_s is not None:
            converted = echo_to_range_m(echo_s)
            if converted is None:
                return Reading(ReadingKind.INVALID, math.nan, f"echo {_short(echo_s)} s is not a positive number")
            range_m = converted
        return classify_reading(range_m, self.min_range_m, self.max_range_m)

    def _use(self, t: float, reading: Reading) -> RangeEstimate | None:
        """Accept a valid reading (gate, confirmation or acquisition) and return the estimate; None if it is a spike."""
        z = reading.track_m
        if self._track is _Track.RANGE and math.isfinite(z):
            gate = self._gate_m()
            if abs(z - self._kf.x[0, 0]) <= gate:
                self._recent.append((t, z, True))
                self._kf.update(np.array([[z]]))
                reason = f"ultrasonic: {z:.2f} m accepted (innovation {self._kf.y[0, 0]:+.2f} m, gate {gate:.2f} m)"
                return self._accept(t, z, reading.value_m, reason, gate)
        if self._track is _Track.CLEAR and math.isinf(z):
            self._recent.append((t, z, True))
            return self._accept(t, z, reading.value_m, "ultrasonic: nothing in range", math.nan)
        if self._track is _Track.NONE:
            # nothing known: an obstacle is believed at once; "nothing in range" too on the very first reading (a car
            # must be able to start on an empty road), but after a silence it needs a second agreeing reading
            first = math.isnan(self._accepted_t_s)
            needed, what = (1 if math.isfinite(z) or first else self.confirm_closer), "track started"
        elif self._is_closer(z):
            needed, what = self.confirm_closer, "closer obstacle confirmed, track re-initialised"
        else:
            needed, what = self.confirm_farther, "farther reading confirmed, track re-initialised"
        self._recent.append((t, z, False))
        # readings that agreed with the track cannot confirm a departure from it
        agreeing = [(ti, zi) for ti, zi, on_track in self._recent if not on_track and t - ti <= self.memory_s
                    and _agree(zi, z, self.agree_m + self.max_closing_speed_mps * (t - ti))]
        if len(agreeing) < needed:
            return None
        votes = f"{len(agreeing)} of the last {len(self._recent)} readings agree"
        self._start(t, z, agreeing[0])
        shown = "nothing in range" if math.isinf(z) else f"{z:.2f} m"
        return self._accept(t, z, reading.value_m, f"ultrasonic: {shown}: {what} ({votes})", math.nan)

    def _is_closer(self, z: float) -> bool:
        if self._track is _Track.CLEAR:
            return math.isfinite(z)
        return z < self._kf.x[0, 0]

    def _candidate_reason(self, reading: Reading) -> str:
        z = reading.track_m
        shown = "nothing in range" if math.isinf(z) else f"{z:.2f} m"
        if self._track is _Track.NONE:
            return f"{shown} not yet confirmed by a second agreeing reading"
        if self._track is _Track.CLEAR:
            return f"{shown} is a closer candidate while nothing was in range: waiting for a second agreeing reading"
        track = self._kf.x[0, 0]
        if self._is_closer(z):
            return f"{shown} is {track - z:.2f} m closer than the track ({track:.2f} m): waiting for a second agreeing reading"
        return f"{shown} is far from the track ({track:.2f} m): dropped unless the next readings agree"

    # -- Kalman filter -------------------------------------------------------------------------
    def _predict(self, t: float) -> None:
        dt = t - self._kf_t_s
        self._kf.F = np.array([[1.0, dt], [0.0, 1.0]])
        self._kf.Q = white_noise_q(dim=2, dt=dt, var=self.accel_std_mps2**2)
        self._kf.predict()
        self._kf_t_s = t

    def _gate_m(self) -> float:
        """Innovation gate: GATE_SIGMA standard deviations of z − Hx (S = P₀₀ + R), at least MIN_GATE_M."""
        innovation_var = self._kf.P[0, 0] + self._kf.R[0, 0]
        return max(self.min_gate_m, self.gate_sigma * math.sqrt(innovation_var))

    def _start(self, t: float, z: float, oldest: tuple[float, float]) -> None:
        """(Re)start the track at z; the range rate from the oldest agreeing reading when there is one."""
        self._recent.clear()
        self._recent.append((t, z, True))
        if math.isinf(z):
            self._track = _Track.CLEAR
            return
        t_old, z_old = oldest
        rate = (z - z_old) / (t - t_old) if t > t_old and math.isfinite(z_old) else 0.0
        rate = min(max(rate, -self.max_closing_speed_mps), self.max_closing_speed_mps)
        self._kf.x = np.array([[z], [rate]])
        self._kf.P = np.diag([self.measurement_std_m**2, INIT_SPEED_STD_MPS**2])
        self._kf_t_s = t
        self._track = _Track.RANGE

    # -- outputs -------------------------------------------------------------------------------
    def _accept(self, t: float, z: float, raw_m: float, reason: str, gate: float) -> RangeEstimate:
        self._accepted_t_s, self._accepted_m = t, z
        if self._track is _Track.CLEAR:
            return RangeEstimate(math.inf, 0.0, math.inf, raw_m, True, reason, gate)
        return self._estimate(self._kf.x[0, 0], raw_m, True, reason, gate)

    def _hold(self, t: float, reading: Reading, why: str) -> RangeEstimate:
        """No usable reading this frame: bridge a short gap with the prediction, else unknown (the track still gates)."""
        gap = t - self._accepted_t_s
        if self._track is _Track.NONE or not gap <= self.dropout_hold_s + TIME_EPS_S:
            since = f"no valid reading for {gap:.2f} s" if math.isfinite(gap) else "no valid reading yet"
            return _unknown(reading.value_m, f"ultrasonic: {since} ({why}): range unknown")
        if self._track is _Track.CLEAR:
            reason = f"ultrasonic: {why}; holding 'nothing in range' for {gap:.2f} s"
            return RangeEstimate(math.inf, 0.0, math.inf, reading.value_m, False, reason)
        # during a gap the obstacle may come closer on the prediction, never farther than it was last seen
        predicted = min(self._kf.x[0, 0], self._accepted_m)
        return self._estimate(predicted, reading.value_m, False, f"ultrasonic: {why}; predicted over a {gap:.2f} s gap", self._gate_m())

    def _estimate(self, range_m: float, raw_m: float, accepted: bool, reason: str, gate: float) -> RangeEstimate:
        shown = min(max(float(range_m), self.min_range_m), self.max_range_m)  # the sensor cannot tell beyond these
        closing = 0.0 - float(self._kf.x[1, 0])  # 0.0 - x: no "-0.0" in reports
        return RangeEstimate(shown, closing, time_to_collision_s(shown, closing), raw_m, accepted, reason, gate)


def _unknown(raw_m: float, reason: str) -> RangeEstimate:
    """Range unknown (NaN): the supervisor counts it as its worst value, 0 m."""
    return RangeEstimate(math.nan, math.nan, math.nan, raw_m, False, reason)
