"""QR track markers: the payload format, and the ``qr_staleness_s`` cue from markers read along a route.

Payload (version FG1), e.g. ``FG1;route=campus;sector=3;pos_m=12.5``: the prefix ``FG1``, then
``key=value`` fields separated by ``;``. ``route`` is a name of letters, digits, ``_`` or ``-``;
``sector`` an integer ≥ 0; ``pos_m`` the board's position along the route in metres (decimal ≥ 0, no
sign or exponent). Extra keys are ignored (room for later fields); empty fields are ignored.

Localisation: a marker read is a *fix* when it is plausible — on the expected route (``route=``, or the
first route seen), within the route's length if known, and, after an earlier fix, within
``max(position_tolerance_m, odometer_rel_tol × |driven|)`` of where the odometer says the car is (last fix
+ distance driven since). The first fix has nothing to compare with and is accepted. Without odometer the
position is unknown and a fix may lie at most ``max_speed_mps`` × time (+ tolerance) from the last one.
The last fix's board read again is a fix while at most one spacing was driven since its first reading.
A rejected marker refreshes nothing. ``staleness_s`` is the time since the last fix (``inf`` before the
first); an update whose time is NaN or runs backwards is ignored, so staleness never decreases except at
a fix. Two distinct markers that agree with each other by odometer but not with the old fix re-localise
the car (it was carried elsewhere, the odometer slipped): one spoofed board alone never can.
"""

from __future__ import annotations

import math
import re
from collections.abc import Sequence
from dataclasses import dataclass, replace

from fearguard.readings import finite_reading, whole_number

MARKER_VERSION = "FG1"  # payload prefix; a later incompatible format gets a new version
ROUTE_PATTERN = re.compile(r"[A-Za-z0-9_-]+")
SECTOR_PATTERN = re.compile(r"[0-9]{1,9}")
POS_PATTERN = re.compile(r"[0-9]{1,9}(?:\.[0-9]{1,6})?")  # no sign, no exponent, no inf/nan
MAX_PAYLOAD_CHARS = 512  # [chars] longer text is not a track marker (a QR code can hold ~3 kB)
REASON_PAYLOAD_CHARS = 40  # [chars] a rejected payload is quoted in reasons up to this length

MARKER_SPACING_M = 5.0  # [m] spacing of boards along the route (EMO vehicle paper: best 5 m)
POSITION_TOLERANCE_M = 1.5  # [m] accepted disagreement with the odometer (board-to-board reading distance varies)
TOLERANCE_PER_SPACING = 0.3  # [-] ... but at most this share of the spacing, so neighbouring boards stay apart
ODOMETER_REL_TOL = 0.1  # [-] odometer error per metre driven (wheel slip, tyre wear): tolerance grows with it
MAX_SPEED_MPS = 5.0  # [m/s] without odometer a fix may move at most this fast (+ tolerance) since the last one


@dataclass(frozen=True)
class TrackMarker:
    """A parsed track marker: which route, which sector, where along the route (m)."""

    route: str
    sector: int
    pos_m: float


def format_marker(route: str, sector: int, pos_m: float, decimals: int = 1) -> str:
    """The FG1 payload for a board (``decimals`` digits of ``pos_m``); ValueError for values it cannot encode."""
    if not isinstance(route, str) or not ROUTE_PATTERN.fullmatch(route):
        raise ValueError(f"route must be letters, digits, '_' or '-', got {route!r}")
    if whole_number(sector) is None or not 0 <= sector <= 999_999_999:
        raise ValueError(f"sector must be an integer 0..999999999, got {sector!r}")
    pos = finite_reading(pos_m)
    if pos is None or pos < 0 or pos >= 1e9:
        raise ValueError(f"pos_m must be a finite number 0 ≤ pos_m < 1e9, got {pos_m!r}")
    if whole_number(decimals) is None or not 0 <= decimals <= 6:
        raise ValueError(f"decimals must be an integer 0..6, got {decimals!r}")
    return f"{MARKER_VERSION};route={route};sector={sector};pos_m={pos:.{decimals}f}"


def parse_marker(payload: object) -> TrackMarker | str:
    """The track marker in a QR payload, or the reason (a string) why it is not one. Never raises."""
    if not isinstance(payload, str):
        return f"not text ({type(payload).__name__})"
    if len(payload) > MAX_PAYLOAD_CHARS:
        return f"not a track marker (longer than {MAX_PAYLOAD_CHARS} characters)"
    fields = [f.strip() for f in payload.strip().split(";")]
    if fields[0] != MARKER_VERSION:
        if re.fullmatch(r"FG[0-9]+", fields[0]):
            return f"unsupported marker version {fields[0]!r} (this reader knows {MARKER_VERSION})"
        return "not a track marker"
    values: dict[str, str] = {}
    for field in fields[1:]:
        if not field:
            continue
        key, sep, value = field.partition("=")
        key = key.strip()
        if not sep or not key:
            return f"malformed field {_quote(field)} (expected key=value)"
        if key in values:
            return f"key {key!r} given twice"
        values[key] = value.strip()
    for key in ("route", "sector", "pos_m"):
        if key not in values:
            return f"missing key {key!r}"
    route, sector, pos = values["route"], values["sector"], values["pos_m"]
    if not ROUTE_PATTERN.fullmatch(route):
        return f"route {_quote(route)} is not a name of letters, digits, '_' or '-'"
    if not SECTOR_PATTERN.fullmatch(sector):
        return f"sector {_quote(sector)} is not an integer ≥ 0"
    if not POS_PATTERN.fullmatch(pos):
        return f"pos_m {_quote(pos)} is not a decimal number ≥ 0"
    return TrackMarker(route, int(sector), float(pos))


def _quote(text: str) -> str:
    short = text if len(text) <= REASON_PAYLOAD_CHARS else text[: REASON_PAYLOAD_CHARS - 1] + "…"
    return repr(short)


# -- pure parts of localisation ----------------------------------------------------------------------
def fix_tolerance_m(
    since_fix_m: float, position_tolerance_m: float = POSITION_TOLERANCE_M, odometer_rel_tol: float = ODOMETER_REL_TOL
) -> float:
    """How far a marker may disagree with the odometer after driving ``since_fix_m`` (either direction)."""
    return max(position_tolerance_m, odometer_rel_tol * abs(since_fix_m))


def plausible_fix(
    marker: TrackMarker,
    last: TrackMarker | None,
    since_fix_m: float | None,
    elapsed_s: float | None,
    route: str | None = None,
    route_length_m: float | None = None,
    position_tolerance_m: float = POSITION_TOLERANCE_M,
    odometer_rel_tol: float = ODOMETER_REL_TOL,
    max_speed_mps: float = MAX_SPEED_MPS,
    marker_spacing_m: float = MARKER_SPACING_M,
) -> str | None:
    """None if ``marker`` is a plausible fix after ``last`` (odometer ``since_fix_m``, ``elapsed_s`` later), else why not.

    ``route``: the expected route (None: any). ``since_fix_m`` None: odometer unknown, the bound is
    ``elapsed_s`` × ``max_speed_mps`` + tolerance. No ``last``: plausible if on the route and within its length.
    ``last`` read again (the car still approaching it): plausible until a whole spacing was driven since its first reading.
    """
    if route is not None and marker.route != route:
        return f"QR marker route {marker.route!r} rejected: expected route {route!r}"
    if route_length_m is not None and marker.pos_m > route_length_m + position_tolerance_m:
        return f"QR marker at {marker.pos_m:.1f} m rejected: beyond the route's length {route_length_m:.1f} m"
    if last is None:
        return None
    if marker == last and since_fix_m is not None:
        if -position_tolerance_m <= since_fix_m <= marker_spacing_m:
            return None
        return (f"QR marker at {marker.pos_m:.1f} m rejected: the last fix's board, but {since_fix_m:.1f} m driven since "
                f"its first reading (a board is read over at most one spacing, {marker_spacing_m:.1f} m)")
    if since_fix_m is not None:
        expected = last.pos_m + since_fix_m
        tol = fix_tolerance_m(since_fix_m, position_tolerance_m, odometer_rel_tol)
        jump = abs(marker.pos_m - expected)
        if jump > tol:
            return (f"QR marker at {marker.pos_m:.1f} m rejected: implausible jump of {jump:.1f} m "
                    f"(odometer says {expected:.1f} ± {tol:.1f} m)")
        return None
    reach = position_tolerance_m + max_speed_mps * (elapsed_s if elapsed_s is not None and elapsed_s > 0 else 0.0)
    jump = abs(marker.pos_m - last.pos_m)
    if jump > reach:
        return (f"QR marker at {marker.pos_m:.1f} m rejected: {jump:.1f} m from the last fix at {last.pos_m:.1f} m, "
                f"farther than {reach:.1f} m reachable without odometer")
    return None


def staleness_s(t_s: float | None, fix_t_s: float | None) -> float:
    """Seconds since the last fix at ``t_s`` (the latest valid time); ``inf`` if never localised."""
    if fix_t_s is None or t_s is None:
        return math.inf
    return max(0.0, t_s - fix_t_s)


# -- the stateful localiser ----------------------------------------------------------------------------
@dataclass(frozen=True)
class LocalisationState:
    """One update's result: the ``qr_staleness_s`` cue, the position estimate, and why.

    ``position_m`` = last fix + odometer since (None if unknown); ``since_fix_m`` the odometer distance
    since the fix (signed, None if unknown); ``missed_markers`` = floor(|since_fix_m| / spacing) (None if unknown).
    """

    staleness_s: float
    position_m: float | None
    since_fix_m: float | None
    missed_markers: int | None
    last_marker: TrackMarker | None
    reasons: tuple[str, ...]
    fix_t_s: float | None = None


@dataclass(frozen=True)
class _Fix:
    marker: TrackMarker
    t_s: float
    odometer_m: float | None


NEVER = LocalisationState(math.inf, None, None, None, None, ("never localised by QR: staleness inf",))


class QrLocaliser:
    """Tracks QR fixes along a route; ``update`` once per frame with the time, payloads read and odometer.

    The same board read again refreshes the time of the fix but keeps the odometer anchor of its first
    reading: every board is then first read from about the same distance, so board-to-board odometer
    checks compare like with like (re-anchoring at the last reading would be off by the approach distance).
    """

    def __init__(
        self,
        marker_spacing_m: float = MARKER_SPACING_M,
        position_tolerance_m: float | None = None,
        route: str | None = None,
        route_length_m: float | None = None,
        odometer_rel_tol: float = ODOMETER_REL_TOL,
        max_speed_mps: float = MAX_SPEED_MPS,
    ) -> None:
        spacing = finite_reading(marker_spacing_m)
        if spacing is None or spacing <= 0:
            raise ValueError(f"QrLocaliser marker_spacing_m must be a finite number > 0, got {marker_spacing_m!r}")
        default_tol = min(POSITION_TOLERANCE_M, TOLERANCE_PER_SPACING * spacing)
        tol = default_tol if position_tolerance_m is None else finite_reading(position_tolerance_m)
        if tol is None or not 0 < tol < spacing / 2:
            raise ValueError(f"QrLocaliser position_tolerance_m must be > 0 and < marker_spacing_m / 2 = {spacing / 2:g} "
                             f"(to tell neighbouring markers apart), got {position_tolerance_m!r}")
        speed = finite_reading(max_speed_mps)
        if speed is None or speed <= 0:
            raise ValueError(f"QrLocaliser max_speed_mps must be a finite number > 0, got {max_speed_mps!r}")
        rel = finite_reading(odometer_rel_tol)
        if rel is None or not 0 <= rel < 1:
            raise ValueError(f"QrLocaliser odometer_rel_tol must be in [0, 1), got {odometer_rel_tol!r}")
        if route is not None and (not isinstance(route, str) or not ROUTE_PATTERN.fullmatch(route)):
            raise ValueError(f"QrLocaliser route must be letters, digits, '_' or '-' (or None), got {route!r}")
        length = None if route_length_m is None else finite_reading(route_length_m)
        if route_length_m is not None and (length is None or length <= 0):
            raise ValueError(f"QrLocaliser route_length_m must be a finite number > 0 (or None), got {route_length_m!r}")
        self.marker_spacing_m = spacing
        self.position_tolerance_m = tol
        self.route = route
        self.route_length_m = length
        self.odometer_rel_tol = rel
        self.max_speed_mps = speed
        self.reset()

    def reset(self) -> None:
        """Forget every fix (a new run): staleness is ``inf`` again."""
        self._t_s: float | None = None  # latest valid time
        self._fix: _Fix | None = None  # last accepted marker: time of its latest reading, odometer at its first
        self._candidate: _Fix | None = None  # a rejected marker waiting for a second one to confirm a re-localisation
        self._route: str | None = self.route
        self._last = NEVER
        self._odo_m: float | None = None  # last odometer reading, dead-reckoned while readings are missing

    @property
    def state(self) -> LocalisationState:
        """The result of the latest update."""
        return self._last

    def update(
        self, t_s: float, payloads: Sequence[str], odometer_m: float | None, speed_mps: float | None = None
    ) -> LocalisationState:
        """Read this frame's payloads at time ``t_s`` with the odometer (m, None/NaN if unknown). Never raises.

        A missing odometer reading after a known one is dead-reckoned: the last reading plus the speed
        integrated since (``speed_mps``, m/s), so a copy of the last board cannot pass as "not moved".
        """
        t = finite_reading(t_s)
        if t is None or (self._t_s is not None and t < self._t_s):
            why = f"time {t_s!r} is not a number" if t is None else f"time {t:.3f} s runs backwards (last {self._t_s:.3f} s)"
            self._last = replace(self._last, reasons=(f"{why}: QR payloads ignored", *self._summary(self._last)))
            return self._last
        odo = self._odometer(t, finite_reading(odometer_m), finite_reading(speed_mps))
        self._t_s = t
        reasons: list[str] = []
        accepted = [m for m in _markers(payloads, reasons) if self._accept(m, t, odo, reasons)]
        if accepted:
            predicted = self._predicted(odo)
            best = min(accepted, key=lambda m: (abs(m.pos_m - predicted) if predicted is not None else m.pos_m, m.pos_m))
            self._fix = self._new_fix(best, t, odo)
            self._candidate = None
            if self._route is None:
                self._route = best.route  # lock onto the first route seen (pass route= to fix it up front)
            reasons.append(f"QR fix sector {best.sector} at {best.pos_m:.1f} m")
        self._last = self._state(t, odo, reasons)
        return self._last

    # -- steps of an update ------------------------------------------------------------------------
    def _odometer(self, t: float, odo: float | None, speed: float | None) -> float | None:
        """The odometer now: the reading, else the last reading dead-reckoned with the speed (None if never read)."""
        if odo is not None:
            self._odo_m = odo
        elif self._odo_m is not None and speed is not None and speed > 0 and self._t_s is not None:
            self._odo_m += speed * (t - self._t_s)
        return self._odo_m

    def _check(self, marker: TrackMarker, ref: _Fix | None, t: float, odo: float | None) -> str | None:
        since = None if ref is None or ref.odometer_m is None or odo is None else odo - ref.odometer_m
        elapsed = None if ref is None else t - ref.t_s
        return plausible_fix(marker, None if ref is None else ref.marker, since, elapsed, self._route, self.route_length_m,
                             self.position_tolerance_m, self.odometer_rel_tol, self.max_speed_mps, self.marker_spacing_m)

    def _accept(self, marker: TrackMarker, t: float, odo: float | None, reasons: list[str]) -> bool:
        why = self._check(marker, self._fix, t, odo)
        if why is None:
            return True
        relocated = self._relocalise(marker, t, odo)
        reasons.append(relocated or why)
        return relocated is not None

    def _relocalise(self, marker: TrackMarker, t: float, odo: float | None) -> str | None:
        """Two distinct markers that agree by odometer outvote the old fix; a lone one only becomes the candidate."""
        if odo is None or self._fix is None or (self._route is not None and marker.route != self._route):
            return None
        cand = self._candidate
        distinct = cand is None or abs(cand.marker.pos_m - marker.pos_m) > self.position_tolerance_m
        if cand is not None and distinct and self._check(marker, cand, t, odo) is None:
            return (f"QR re-localised: markers at {cand.marker.pos_m:.1f} m and {marker.pos_m:.1f} m agree by odometer, "
                    f"fix at {self._fix.marker.pos_m:.1f} m abandoned")
        if distinct:
            self._candidate = _Fix(marker, t, odo)  # the same board seen again keeps its first reading
        return None

    def _new_fix(self, marker: TrackMarker, t: float, odo: float | None) -> _Fix:
        old = self._fix
        if old is not None and marker == old.marker and old.odometer_m is not None:
            return _Fix(marker, t, old.odometer_m)  # same board again: fresh time, first reading's odometer anchor
        return _Fix(marker, t, odo)

    def _predicted(self, odo: float | None) -> float | None:
        fix = self._fix
        if fix is None or fix.odometer_m is None or odo is None:
            return None
        return fix.marker.pos_m + (odo - fix.odometer_m)

    def _state(self, t: float, odo: float | None, reasons: list[str]) -> LocalisationState:
        fix = self._fix
        if fix is None:
            return replace(NEVER, reasons=(*reasons, *NEVER.reasons))
        since = None if fix.odometer_m is None or odo is None else odo - fix.odometer_m
        missed = None if since is None else math.floor(abs(since) / self.marker_spacing_m)
        position = None if since is None else fix.marker.pos_m + since
        state = LocalisationState(staleness_s(t, fix.t_s), position, since, missed, fix.marker, (), fix.t_s)
        return replace(state, reasons=(*reasons, *self._summary(state)))

    def _summary(self, state: LocalisationState) -> tuple[str, ...]:
        if state.fix_t_s is None:
            return NEVER.reasons
        if state.staleness_s == 0.0:
            return ()
        missed = ("markers missed unknown (no odometer)" if state.missed_markers is None
                  else f"{state.missed_markers} marker{'' if state.missed_markers == 1 else 's'} missed")
        return (f"no QR fix for {state.staleness_s:.1f} s, {missed} (spacing {self.marker_spacing_m:.1f} m)",)


def _markers(payloads: object, reasons: list[str]) -> list[TrackMarker]:
    """The track markers among this frame's payloads (each text once); a reason for every rejected one."""
    if payloads is None:
        return []
    if isinstance(payloads, str):
        payloads = (payloads,)  # one payload given bare, not a sequence of characters
    try:
        items = list(payloads)  # type: ignore[call-overload]
    except TypeError:
        reasons.append(f"QR payloads of type {type(payloads).__name__} ignored: not a sequence")
        return []
    markers: list[TrackMarker] = []
    seen: set[str] = set()
    for payload in items:
        if isinstance(payload, str):
            if payload in seen:
                continue
            seen.add(payload)
        parsed = parse_marker(payload)
        if isinstance(parsed, TrackMarker):
            markers.append(parsed)
        elif isinstance(payload, str):
            reasons.append(f"QR payload {_quote(payload)} rejected: {parsed}")
        else:
            reasons.append(f"QR payload rejected: {parsed}")
    return markers
