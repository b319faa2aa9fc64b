"""Hypothesis strategies for everything a supervisor is fed, sized by a rule base and a vehicle.

Every strategy takes the ``RuleBase`` (universes, the brightness band, which values are calm) and the
``VehicleLimits`` (speeds, steering limit, range-sensor limits) it is meant for, so the values are dense
where that car's decisions change. Values come in three kinds, as docs/architecture.md's cue table has them:

- valid: inside the cue's physical range (``inf`` where it is a valid reading: nothing in range, never localised);
- unknown: NaN, outside the range (negative, above 1 or 255, ``-inf``);
- not a number at all: strings (also ``"0.9"``), bytes, bools, ``Decimal``, 0-d numpy arrays, None, lists.

Unknown and non-numbers must count as the worst value (invariant 4), so histories mix them in.
"""

from __future__ import annotations

import math
from functools import lru_cache
from typing import Any

import numpy as np
from hypothesis import strategies as st

import fearguard as fg
from fearguard.cues import CUE_NAMES, CUE_SPECS, calm_values
from fearguard.testing.frames import EFFECTS, GARBAGE, RENDER_POOL, RENDER_SCENARIOS
from fearguard.testing.history import FrameSpec, SteerRaises, Step

SearchStrategy = st.SearchStrategy
CALM_GRID = 201  # [points] per cue when looking for the values where fear is VERY_LOW


def _rules(rules: fg.RuleBase | None) -> fg.RuleBase:
    return rules if rules is not None else _default_rules()


@lru_cache(maxsize=1)
def _default_rules() -> fg.RuleBase:
    return fg.load_rules()


def _vehicle(vehicle: fg.VehicleLimits | None) -> fg.VehicleLimits:
    return vehicle if vehicle is not None else fg.VehicleLimits()


def cue_span(name: str, rules: fg.RuleBase | None = None, vehicle: fg.VehicleLimits | None = None) -> tuple[float, float]:
    """The finite interval worth sampling for a cue: its physical range, open ends cut past the rule universe."""
    spec = CUE_SPECS[CUE_NAMES.index(name)]
    if math.isfinite(spec.high):
        return spec.low, spec.high
    var = _rules(rules).variables.get(name)
    hi = float(var.universe[-1]) if var is not None else spec.span
    if name == "obstacle_range_m":
        hi = max(hi, _vehicle(vehicle).ultrasonic_max_range_m)
    return spec.low, 1.25 * hi


def non_numbers() -> SearchStrategy[Any]:
    """Values that are not a real number, though some convert to one: "0.9", b"1", True, Decimal, 0-d arrays, None."""
    return st.one_of(
        st.sampled_from(["0.9", "nan", "inf", "", "left", "1e3"]),
        st.text(max_size=6),
        st.sampled_from([b"1", b"\x00"]),
        st.booleans(),
        st.decimals(allow_nan=True, places=3, min_value=-10, max_value=300),
        st.floats(-10, 300).map(lambda v: np.array(v)),
        st.just(None),
        st.just([0.5]),
    )


def valid_values(name: str, rules: fg.RuleBase | None = None, vehicle: fg.VehicleLimits | None = None) -> SearchStrategy[float]:
    """Readings inside a cue's physical range, dense near its ends and the rules' term edges; inf where valid."""
    lo, hi = cue_span(name, rules, vehicle)
    edges = sorted({float(p) for shape in _rules(rules).variables[name].shapes.values() for p in shape[1] if lo <= p <= hi}) \
        if name in _rules(rules).variables else []
    parts: list[SearchStrategy[float]] = [st.floats(lo, hi)]
    if edges:
        parts.append(st.sampled_from(edges))
    if math.isinf(CUE_SPECS[CUE_NAMES.index(name)].high):
        parts.append(st.just(math.inf))
    return st.one_of(*parts)


def unknown_values(name: str) -> SearchStrategy[Any]:
    """Readings that are unknown: NaN, outside the physical range, -inf, or not a number."""
    spec = CUE_SPECS[CUE_NAMES.index(name)]
    outside = [st.floats(max_value=spec.low, exclude_max=True, allow_infinity=True, allow_nan=False)]
    if math.isfinite(spec.high):
        outside.append(st.floats(min_value=spec.high, exclude_min=True, allow_infinity=True, allow_nan=False))
    return st.one_of(st.just(math.nan), *outside, non_numbers())


def cue_values(name: str, rules: fg.RuleBase | None = None, vehicle: fg.VehicleLimits | None = None, *,
               unknown: bool = True) -> SearchStrategy[Any]:
    """One cue's value: mostly valid, with unknown ones mixed in unless ``unknown=False``."""
    valid = valid_values(name, rules, vehicle)
    return st.one_of(valid, valid, valid, unknown_values(name)) if unknown else valid


def cues(rules: fg.RuleBase | None = None, vehicle: fg.VehicleLimits | None = None, *, unknown: bool = True) -> SearchStrategy[fg.Cues]:
    """Cue vectors for this rule base and vehicle (unknown values mixed in unless ``unknown=False``)."""
    return st.builds(fg.Cues, **{n: cue_values(n, rules, vehicle, unknown=unknown) for n in CUE_NAMES})


cue_vectors = cues  # the same strategy, for code where ``cues`` names a parameter


@lru_cache(maxsize=16)
def calm_ranges(rules: fg.RuleBase) -> dict[str, tuple[float, float]]:
    """For each cue, the interval around its best value where fear stays VERY_LOW with the other cues best.

    Found on a grid of each rule universe, so it holds for any rule base: the values a pass-through
    test must reach. Open-ended cues keep ``inf`` (nothing in range, never localised) out of it.
    """
    best = best_cues(rules)
    out: dict[str, tuple[float, float]] = {}
    for name in CUE_NAMES:
        lo, hi = cue_span(name, rules)
        grid = np.linspace(lo, hi, CALM_GRID)
        base = {n: getattr(best, n) for n in CUE_NAMES}
        calm = [rules.evaluate(fg.Cues(**{**base, name: float(v)})).level is fg.FearLevel.VERY_LOW for v in grid]
        centre = float(getattr(best, name))
        i = int(np.argmin(np.abs(grid - min(centre, hi))))
        if not calm[i]:
            out[name] = (centre, centre) if math.isfinite(centre) else (hi, hi)
            continue
        a = b = i
        while a > 0 and calm[a - 1]:
            a -= 1
        while b < len(grid) - 1 and calm[b + 1]:
            b += 1
        out[name] = (float(grid[a]), float(grid[b]))
    return out


@lru_cache(maxsize=16)
def best_cues(rules: fg.RuleBase) -> fg.Cues:
    """The calmest picture: each cue at its best (brightness mid band; open ends at inf / 0)."""
    return fg.Cues(*calm_values(rules.brightness_band))


def calm_cues(rules: fg.RuleBase | None = None, vehicle: fg.VehicleLimits | None = None) -> SearchStrategy[fg.Cues]:
    """Cues where fear is very low for this rule base: pass-through must be exercised, not only possible."""
    rb = _rules(rules)
    ranges = calm_ranges(rb)
    best = best_cues(rb)

    def near(name: str) -> SearchStrategy[float]:
        a, b = ranges[name]
        centre = float(getattr(best, name))
        c = centre if math.isfinite(centre) else b
        lo, hi = c - 0.5 * (c - a), c + 0.5 * (b - c)  # the half of the calm interval nearer the best value
        return st.one_of(st.just(centre), st.floats(lo, hi) if hi > lo else st.just(c))

    return st.builds(fg.Cues, **{n: near(n) for n in CUE_NAMES})


def worst_values(name: str) -> tuple[float, ...]:
    """The value(s) an unknown cue counts as: brightness has two extremes, the worse of them wins."""
    spec = CUE_SPECS[CUE_NAMES.index(name)]
    return (0.0, 255.0) if spec.worst is None else (spec.worst,)


def hazard_cues(rules: fg.RuleBase | None = None) -> SearchStrategy[fg.Cues]:
    """A calm picture with one or two cues at their worst: the situations that must end in EMERGENCY."""
    best = best_cues(_rules(rules))
    base = {n: getattr(best, n) for n in CUE_NAMES}
    singles = [fg.Cues(**{**base, n: w}) for n in CUE_NAMES for w in worst_values(n)]
    pairs = [fg.Cues(**{**base, a: worst_values(a)[0], b: worst_values(b)[-1]})
             for i, a in enumerate(CUE_NAMES) for b in CUE_NAMES[i + 1 :]]
    return st.sampled_from(singles + pairs + [best])


def speeds(vehicle: fg.VehicleLimits | None = None, *, unknown: bool = True) -> SearchStrategy[Any]:
    """Measured ego speeds: 0 to above the car's maximum; NaN, negative and non-numbers when ``unknown``."""
    top = _vehicle(vehicle).max_speed_mps
    valid = st.one_of(st.floats(0.0, 1.2 * top), st.sampled_from([0.0, top]))
    return st.one_of(valid, valid, valid, st.just(math.nan), st.floats(-5.0, -1e-6), non_numbers()) if unknown else valid


def steering_outputs(vehicle: fg.VehicleLimits | None = None, *, faults: bool = True) -> SearchStrategy[Any]:
    """What a wrapped steering function answers: angles within the limit, now and then beyond it (held at full lock,
    no fault), and (``faults``) NaN, junk, raising."""
    limit = _vehicle(vehicle).max_steering_deg
    fine = st.floats(-limit, limit)
    beyond = st.builds(math.copysign, st.floats(limit, 3 * limit, exclude_min=True), st.sampled_from([1.0, -1.0]))
    angles = st.one_of(fine, fine, fine, fine, beyond)
    if not faults:
        return angles
    junk = st.sampled_from(["left", None, SteerRaises(), SteerRaises("ValueError")])
    bad = st.one_of(st.floats(allow_nan=True, allow_infinity=True), junk, non_numbers())
    return st.one_of(angles, angles, angles, bad)


def leads(*, boxes: bool = True) -> SearchStrategy[Any]:
    """The vehicle ahead: none, a ``Lead`` (bearing, maybe a range; or junk in them), or a detector's ``LeadBox``."""
    bearing = st.one_of(st.floats(-30.0, 30.0), st.floats(allow_nan=True, allow_infinity=True), non_numbers())
    rng = st.one_of(st.none(), st.floats(0.0, 60.0), st.floats(allow_nan=True, allow_infinity=True), non_numbers())
    parts: list[SearchStrategy[Any]] = [st.none(), st.none(), st.builds(fg.Lead, bearing, rng)]
    if boxes:
        parts.append(lead_boxes())
    return st.one_of(*parts)


def lead_boxes() -> SearchStrategy[fg.LeadBox]:
    """Boxes from an external detector (pixels): plausible ones, empty, negative, NaN."""
    px = st.one_of(st.floats(-20.0, 400.0), st.just(math.nan))
    return st.builds(fg.LeadBox, px, px, st.one_of(st.floats(0.0, 200.0), st.just(-5.0)), st.one_of(st.floats(0.0, 200.0), st.just(0.0)))


def ultrasonic_readings(vehicle: fg.VehicleLimits | None = None) -> SearchStrategy[Any]:
    """Range-sensor readings (m): inside the sensor's limits, inf (no echo), dropouts (None), NaN, spikes, junk."""
    car = _vehicle(vehicle)
    inside = st.floats(car.ultrasonic_min_range_m, car.ultrasonic_max_range_m)
    return st.one_of(inside, inside, inside, st.just(math.inf), st.none(), st.just(math.nan), st.floats(-1.0, 0.0),
                     st.floats(car.ultrasonic_max_range_m, 10 * car.ultrasonic_max_range_m), st.just(0.01), non_numbers())


def echo_times() -> SearchStrategy[Any]:
    """Raw HC-SR04 echo times (s): plausible (d = 17150 × t cm), zero, negative, NaN, None."""
    return st.one_of(st.none(), st.floats(0.0001, 0.03), st.sampled_from([0.0, -0.001, math.nan, 1.0]))


def qr_payloads(route: str = "campus", spacing_m: float = 5.0) -> SearchStrategy[Any]:
    """QR payloads: genuine FG1 markers, the same old board again (stale), and forged or broken ones."""
    from fearguard.sensors.localisation import format_marker

    genuine = st.integers(0, 40).map(lambda i: format_marker(route, i, i * spacing_m))
    stale = st.just(format_marker(route, 0, 0.0))
    forged = st.one_of(
        st.integers(0, 40).map(lambda i: format_marker("elsewhere", i, i * spacing_m)),  # another route
        st.integers(0, 40).map(lambda i: format_marker(route, i, 1000.0 + i)),  # a jump no odometer explains
        st.sampled_from([f"FG2;route={route};sector=1;pos_m=5.0", f"FG1;route={route};sector=-1;pos_m=5", "FG1;route=;sector=1",
                         f"FG1;route={route};sector=1;pos_m=nan", "https://example.com", "", "FG1;" * 200]),
        st.text(max_size=30),
        non_numbers(),
    )
    return st.one_of(st.none(), st.none(), genuine, stale, forged)


def frame_specs(*, garbage: bool = True, render: bool = True) -> SearchStrategy[FrameSpec]:
    """Frames: rendered by the simulator, small synthetic roads, degraded pictures; broken ones when ``garbage``."""
    effect = st.sampled_from(EFFECTS)
    reuse = st.booleans()
    parts: list[SearchStrategy[FrameSpec]] = [
        st.builds(FrameSpec, kind=st.just("synthetic"), index=st.integers(0, 20), effect=effect, offset_px=st.floats(-40.0, 40.0),
                  reuse_buffer=reuse),
    ]
    if render:
        parts.append(st.builds(FrameSpec, kind=st.just("render"), source=st.sampled_from(RENDER_SCENARIOS),
                               index=st.integers(0, RENDER_POOL - 1), effect=effect, reuse_buffer=reuse))
    if garbage:
        parts.append(st.builds(FrameSpec, kind=st.just("garbage"), source=st.sampled_from(GARBAGE)))
    return st.one_of(*parts)


def time_steps(*, faults: bool = True) -> SearchStrategy[float]:
    """Time between frames (s): 100 Hz to 2 Hz; with ``faults`` also a stall (2-5 s), no step, a step back, NaN."""
    fine = st.floats(0.01, 0.5)
    if not faults:
        return fine
    return st.one_of(fine, fine, fine, fine, fine, fine, st.floats(2.0, 5.0), st.sampled_from([0.0, -1.0, math.nan]))


def histories(rules: fg.RuleBase | None = None, vehicle: fg.VehicleLimits | None = None, *,
              cues: SearchStrategy[fg.Cues] | None = None, level: str = "cue", min_size: int = 1, max_size: int = 30,
              faults: bool = True, steer: SearchStrategy[Any] | None = None, frames: SearchStrategy[FrameSpec] | None = None,
              lead: SearchStrategy[Any] | None = None) -> SearchStrategy[tuple[Step, ...]]:
    """A drive: time going forward (with faults: stalls, repeats, steps back, NaN), speeds, and per frame

    - ``level="cue"``: given cues (perception skipped), a frame only when ``frames`` is given (for a real
      steering function to look at);
    - ``level="frame"``: a frame (rendered, synthetic, degraded, broken, repeated, refilled buffer) and the
      sensor readings (ultrasonic with dropouts, odometer, QR payloads), measured by perception.
    Every step also has a lead (or none) and the scripted steering output.
    """
    if level not in ("cue", "frame"):
        raise ValueError(f"level must be 'cue' or 'frame', got {level!r}")
    rb, car = _rules(rules), _vehicle(vehicle)
    parts = {
        "n": st.integers(min_size, max_size),
        "t0": st.sampled_from([0.0, 100.0]),
        "dt": time_steps(faults=faults),
        "repeat": st.integers(0, 4),
        "speed": speeds(car, unknown=faults),
        "cues": cues if cues is not None else cue_vectors(rb, car, unknown=faults),
        "steer": steer if steer is not None else steering_outputs(car, faults=faults),
        "lead": lead if lead is not None else (leads() if faults else st.one_of(st.none(), st.builds(fg.Lead, st.floats(-20, 20)))),
        "frames": frames if frames is not None or level == "cue" else frame_specs(garbage=faults),
        "ultrasonic": ultrasonic_readings(car),
        "echo": st.one_of(st.none(), st.none(), echo_times()),
        "odometer_fault": st.sampled_from([False, False, None, math.nan]),
        "qr": qr_payloads(),
    }
    return _histories(parts, level == "frame")


@st.composite
def _histories(draw: Any, parts: dict[str, SearchStrategy[Any]], frame_level: bool) -> tuple[Step, ...]:
    n = draw(parts["n"])
    t, odo = draw(parts["t0"]), 0.0
    steps: list[Step] = []
    for k in range(n):
        dt = draw(parts["dt"]) if k else 0.0
        step_t = math.nan if math.isnan(dt) else t + dt  # a NaN clock on one frame; the next frames go on from t
        t = t if math.isnan(dt) else step_t
        frame = None
        if parts["frames"] is not None:
            repeat = bool(steps) and steps[-1].frame is not None and draw(parts["repeat"]) == 0
            frame = steps[-1].frame if repeat else draw(parts["frames"])
        speed = draw(parts["speed"])
        odo += 0.1 * (speed if isinstance(speed, float) and math.isfinite(speed) and speed > 0 else 0.0)
        if frame_level:
            bad_odo = draw(parts["odometer_fault"])
            steps.append(Step(
                t_s=step_t, speed_mps=speed, frame=frame, ultrasonic_range_m=draw(parts["ultrasonic"]),
                ultrasonic_echo_s=draw(parts["echo"]),
                odometer_m=odo if bad_odo is False else bad_odo, qr_payload=draw(parts["qr"]), lead=draw(parts["lead"]),
                steer_output=draw(parts["steer"]),
            ))
        else:
            steps.append(Step(t_s=step_t, speed_mps=speed, cues=draw(parts["cues"]), frame=frame, lead=draw(parts["lead"]),
                              steer_output=draw(parts["steer"])))
    return tuple(steps)


def observations(rules: fg.RuleBase | None = None, vehicle: fg.VehicleLimits | None = None, *,
                 level: str = "cue") -> SearchStrategy[fg.Observation]:
    """Single Observations (pixels rebuilt): for fuzzing a component that takes one at a time."""
    from fearguard.testing.frames import frame_pixels
    from fearguard.testing.subject import observation

    return histories(rules, vehicle, level=level, max_size=1, frames=frame_specs() if level == "frame" else None).map(
        lambda h: observation(h[0], frame_pixels(h[0].frame)))


def vehicles() -> SearchStrategy[fg.VehicleLimits]:
    """Plausible cars from a 1:20 robot to a road car (speed, braking, reaction, margin, steering, sensors)."""
    return st.builds(
        fg.VehicleLimits, max_speed_mps=st.floats(0.3, 40.0), max_decel_mps2=st.floats(0.3, 9.0), reaction_time_s=st.floats(0.0, 1.5),
        stop_margin_m=st.floats(0.0, 1.0), max_steering_deg=st.floats(5.0, 45.0), has_ultrasonic=st.booleans(),
        has_qr_localisation=st.booleans(),
    )

