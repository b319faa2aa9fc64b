"""One checker per numbered safety invariant of docs/architecture.md, and the examples that exercise it.

Each ``Invariant`` has ``cases(subject)``, a hypothesis strategy of ``Case`` values (histories sized by
the subject's rules and vehicle), and ``check(subject, case)``, which runs the case through fresh
supervisors and returns None, or a sentence saying which frame breaks the invariant and by how much.
``fearguard.testing.verify`` searches the cases with hypothesis and shrinks a failing one into the
smallest history that still breaks the invariant.
"""

from __future__ import annotations

import math
from collections.abc import Callable, Sequence
from dataclasses import dataclass, replace
from typing import Any

import numpy as np
from hypothesis import strategies as st

import fearguard as fg
from fearguard.cues import CUE_NAMES, CUE_SPECS, Worsens
from fearguard.fuzzy.promises import Promise, Response, promises, rule_for
from fearguard.perception import FROZEN_S
from fearguard.policy import creep_needs_m
from fearguard.readings import finite_reading
from fearguard.testing import strategies as fs
from fearguard.testing.history import Case, FrameSpec, SteerRaises, Step
from fearguard.testing.subject import NOT_CALLED, Driver, Run, Subject, run

TOL = 1e-9  # [m/s], [-] rounding allowed in comparisons of speeds and fears
FEAR_TOL = 1e-12  # [-] the vector path sums in another order than the scalar path
VISION_CUES = ("lane_confidence", "brightness", "occlusion")
STEADY_DT_S = (0.05, 0.1, 0.2)  # [s] frame periods of the steady drives
SWEEP_POINTS = 64  # [points] along a cue's worsening path, from its value to its worst
RAMP_EXTRA_S = 2.0  # [s] a steady drive lasts the limit's full ramp (max speed / comfort acceleration) and this much more
CheckFn = Callable[[Subject, Case], "str | None"]


@dataclass(frozen=True)
class Invariant:
    """A numbered invariant: its title, docs/architecture.md's words, the examples and the checker."""

    number: str
    key: str
    title: str
    design: str
    cases: Callable[[Subject], st.SearchStrategy[Case]]
    check: CheckFn
    prefix_closed: bool = False  # a violation at frame i is one of every longer drive too: a counterexample can be cut after it
    narrow: Callable[[Subject, Case], Case] | None = None  # after shrinking: the part of a case that shows the failure


# -- shared helpers -----------------------------------------------------------------------------
def _frames_for(subject: Subject) -> st.SearchStrategy[FrameSpec] | None:
    """A real steering function looks at pixels: give it frames (synthetic roads and rendered ones)."""
    return fs.frame_specs(garbage=False) if subject.steer is not None else None


def _drives(subject: Subject, *, cues: st.SearchStrategy[fg.Cues] | None = None, max_size: int = 30, faults: bool = True,
            frame_level: bool = True) -> st.SearchStrategy[Case]:
    """Cue-level drives (a frame for a real steering function), and short frame-level drives through perception."""
    cue_level = fs.histories(subject.rules, subject.vehicle, cues=cues, max_size=max_size, faults=faults, frames=_frames_for(subject))
    parts = [cue_level, cue_level, cue_level]
    if frame_level:
        parts.append(fs.histories(subject.rules, subject.vehicle, level="frame", max_size=6, faults=faults))
    return st.one_of(*parts).map(Case.drive)


def _cmd_text(cmd: fg.Command) -> str:
    return (f"{cmd.mode.name} {cmd.strategy.name}, limit {cmd.speed_limit_mps:.4g} m/s, steering {cmd.steering_deg:+.4g} deg, "
            f"fear {cmd.fear:.4g} ({cmd.fear_level.name})")


def _broken(r: Run) -> str | None:
    return f"FearGuard.step broke its contract: {r.raised}" if r.raised else None


def _t(step: Step) -> float | None:
    return finite_reading(step.t_s)


def _used_range_m(cmd: fg.Command) -> float:
    """The obstacle range the supervisor decided on; unknown counts as 0 (worst)."""
    d = cmd.cues.obstacle_range_m
    return d if isinstance(d, float) and d >= 0.0 else 0.0


def _stopped(cmd: fg.Command) -> bool:
    """EMERGENCY STOP with a zero limit: how a fault must be answered."""
    return cmd.mode is fg.Mode.EMERGENCY and cmd.strategy is fg.Strategy.STOP and cmd.speed_limit_mps == 0.0


def _is_fault(cmd: fg.Command) -> bool:
    """A fault command (time, steering function, malformed input) has no dominant cause."""
    return cmd.cause is None and cmd.mode is fg.Mode.EMERGENCY


def _steer_fault(answer: Any) -> str | None:
    if answer is NOT_CALLED:
        return None
    if isinstance(answer, SteerRaises):
        return f"the steering function raised {answer.exception}"
    if finite_reading(answer) is None:
        return f"the steering function returned {answer!r}"
    return None  # a finite angle beyond the range is no fault: the wheels stop at full lock (check_pass_through)


def _first_bad_frame(subject: Subject, case: Case, judge: Callable[[Step, fg.Command], str | None]) -> str | None:
    """Run every history of the case; the first frame whose command the judge objects to, as "frame i: why"."""
    for _, history in case.runs:
        r = run(subject, history)
        if r.raised:
            return _broken(r)
        for i, (step, cmd) in enumerate(zip(history, r.commands, strict=True)):
            why = judge(step, cmd)
            if why:
                return f"frame {i}: {why}"
    return None


# -- 1. limits in range ---------------------------------------------------------------------------
def check_limits_in_range(subject: Subject, case: Case) -> str | None:
    """0 ≤ speed limit ≤ max speed; fear in [0, 1]; steering finite within ±max steering; a reason every frame."""
    car = subject.vehicle

    def judge(step: Step, cmd: fg.Command) -> str | None:
        v, f, s = cmd.speed_limit_mps, cmd.fear, cmd.steering_deg
        if not (isinstance(v, float) and 0.0 <= v <= car.max_speed_mps):
            return f"speed limit {v!r} outside [0, {car.max_speed_mps:g}] m/s"
        if not (isinstance(f, float) and 0.0 <= f <= 1.0):
            return f"fear {f!r} outside [0, 1]"
        if not (isinstance(s, float) and math.isfinite(s) and abs(s) <= car.max_steering_deg):
            return f"steering {s!r} deg outside ±{car.max_steering_deg:g} deg"
        if not (isinstance(cmd.mode, fg.Mode) and isinstance(cmd.strategy, fg.Strategy) and isinstance(cmd.fear_level, fg.FearLevel)):
            return f"mode/strategy/level are not the enums: {cmd.mode!r}, {cmd.strategy!r}, {cmd.fear_level!r}"
        if not cmd.reasons or not all(isinstance(x, str) for x in cmd.reasons):
            return f"a command without its reasons: {cmd.reasons!r}"
        return None

    return _first_bad_frame(subject, case, judge)


# -- 2. safe distance -----------------------------------------------------------------------------
def stopping_distance_m(v: float, car: fg.VehicleLimits) -> float:
    """v·t_r + v²/(2a): reaction then braking at the car's stated deceleration."""
    return v * car.reaction_time_s + v * v / (2.0 * car.max_decel_mps2)


def lead_speed_mps(step: Step, cmd: fg.Command) -> float:
    """Speed of the object ahead the supervisor assumed: ego speed − its closing speed (≥ 0); unknown: 0 (standing)."""
    closing, speed = cmd.closing_speed_mps, finite_reading(step.speed_mps)
    if speed is None or not isinstance(closing, float) or not math.isfinite(closing):
        return 0.0
    return max(0.0, speed - closing)


def check_safe_distance(subject: Subject, case: Case) -> str | None:
    """For the obstacle range d the supervisor used, at v = the speed limit (responsibility-sensitive safety):
    v·t_r + v²/(2a) ≤ max(0, d − margin + v_f²/(2b)), v_f the speed of the object ahead as the supervisor
    estimated it (its ``closing_speed_mps``; 0 = a standing obstacle), b its assumed hardest braking.

    With a range sensor, "nothing in range" (inf) means the nearest obstacle may stand just beyond the
    sensor's maximum range: the car must be able to stop within what it can see.
    """
    car = subject.vehicle
    b = car.lead_max_decel_mps2

    def judge(step: Step, cmd: fg.Command) -> str | None:
        d, seen, v_f = _used_range_m(cmd), "obstacle at", lead_speed_mps(step, cmd) if b else 0.0
        if math.isinf(d):
            if not car.has_ultrasonic:
                return None  # no range sensor: nothing is known in range (declared, not faked)
            d, seen, v_f = car.ultrasonic_max_range_m, "nothing in range: an obstacle may stand just beyond the sensor's maximum range", 0.0
        v = cmd.speed_limit_mps
        need = stopping_distance_m(v, car)
        room = max(0.0, d - car.stop_margin_m + (v_f * v_f / (2.0 * b) if b and v_f > 0.0 else 0.0))
        if need > room + TOL:
            ahead = f", the object ahead moving at {v_f:.4g} m/s and braking at most {b:g} m/s²" if v_f > 0.0 else ""
            return (f"speed limit {v:.4g} m/s needs {need:.4g} m to stop (reaction {car.reaction_time_s:g} s, "
                    f"braking {car.max_decel_mps2:g} m/s²) but there are {room:.4g} m ({seen} {d:.4g} m, margin "
                    f"{car.stop_margin_m:g} m{ahead}); {_cmd_text(cmd)}")
        return None

    return _first_bad_frame(subject, case, judge)


def _safe_distance_cases(subject: Subject) -> st.SearchStrategy[Case]:
    rb, car = subject.rules, subject.vehicle
    valid = fs.cues(rb, car, unknown=False)
    drives = _drives(subject, cues=st.one_of(fs.calm_cues(rb, car), valid, fs.cues(rb, car)))

    calm, ranges, speeds = fs.calm_cues(rb, car), fs.valid_values("obstacle_range_m", rb, car), fs.speeds(car, unknown=False)
    ramp_s = car.max_speed_mps / rb.policy.comfort_accel_mps2 + RAMP_EXTRA_S

    @st.composite
    def steady(draw: Any) -> Case:  # the same calm picture until the limit has ramped up fully: physics must bind
        d = draw(ranges)
        cues = replace(draw(calm), obstacle_range_m=d)
        dt = draw(st.sampled_from(STEADY_DT_S))
        n, v0 = math.ceil(ramp_s / dt), draw(speeds)  # the search trims it to the first frame that is too fast
        return Case.drive((Step(t_s=k * dt, speed_mps=v0, cues=cues) for k in range(n)),
                          note=f"a steady calm picture, obstacle at {d:.4g} m, every {dt:g} s")

    return st.one_of(drives, steady())


# -- 3. monotone ----------------------------------------------------------------------------------
def worse(cues: fg.Cues, name: str, amount: float, rules: fg.RuleBase, vehicle: fg.VehicleLimits | None = None) -> fg.Cues | None:
    """The same cues with one cue worse by ``amount`` (a share of its span); None when it has no worse value."""
    v = getattr(cues, name)
    spec = CUE_SPECS[CUE_NAMES.index(name)]
    lo, hi = fs.cue_span(name, rules, vehicle)
    span = hi - lo
    band_lo, band_hi = rules.brightness_band
    if spec.worsens is Worsens.WHEN_LOWER:
        new = (hi if math.isinf(v) else v) - amount * span if name != "obstacle_range_m" else (hi if math.isinf(v) else v) * (1.0 - amount)
    elif spec.worsens is Worsens.WHEN_HIGHER:
        new = v + amount * span
    elif v <= band_lo:
        new = v - amount * span
    elif v >= band_hi:
        new = v + amount * span
    else:
        return None
    new = min(max(new, lo), spec.high)
    return replace(cues, **{name: new})


def check_monotone(subject: Subject, case: Case) -> str | None:
    """A cue getting worse on the last frame never lowers fear nor raises the speed limit; nor does a faster
    closing speed (the obstacle's range rate, when the caller gives it)."""
    r_better, r_worse = run(subject, case.run("better")), run(subject, case.run("worse"))
    for r in (r_better, r_worse):
        if r.raised:
            return _broken(r)
    b, w = r_better.commands[-1], r_worse.commands[-1]
    if case.params.get("kind") == "closing":
        if w.speed_limit_mps > b.speed_limit_mps + FEAR_TOL:
            return (f"the obstacle closes faster on the last frame (range rate {case.params.get('from')} → {case.params.get('to')} m/s): "
                    f"the speed limit rises {b.speed_limit_mps:.6g} → {w.speed_limit_mps:.6g} m/s ({_cmd_text(b)} → {_cmd_text(w)})")
        return None
    what = f"{case.params.get('cue')} worsens {case.params.get('from')} → {case.params.get('to')} on the last frame"
    cb, cw = case.run("better")[-1].cues, case.run("worse")[-1].cues
    assert cb is not None and cw is not None
    rb = subject.rules
    fb, fw = rb.evaluate(cb).fear, rb.evaluate(cw).fear
    if fw < fb - FEAR_TOL:
        return f"{what}: the rules' fear falls {fb:.6g} → {fw:.6g}"
    swept = _fear_sweep(rb, cb, str(case.params.get("cue")), subject.vehicle)
    if swept:
        return swept
    batch = rb.evaluate_batch(np.array([cb.as_array(), cw.as_array()]))
    if batch[1] < batch[0] - FEAR_TOL:
        return f"{what}: evaluate_batch's fear falls {batch[0]:.6g} → {batch[1]:.6g}"
    if w.fear < b.fear - FEAR_TOL:
        return f"{what}: the supervisor's fear falls {b.fear:.6g} → {w.fear:.6g}"
    if w.speed_limit_mps > b.speed_limit_mps + FEAR_TOL:
        return f"{what}: the speed limit rises {b.speed_limit_mps:.6g} → {w.speed_limit_mps:.6g} m/s ({_cmd_text(b)} → {_cmd_text(w)})"
    return None


def worsening_path(cues: fg.Cues, name: str, rules: fg.RuleBase, vehicle: fg.VehicleLimits | None = None) -> list[float]:
    """Values of one cue from its value in ``cues`` to its worst, each worse than the one before (SWEEP_POINTS)."""
    v = getattr(cues, name)
    spec = CUE_SPECS[CUE_NAMES.index(name)]
    lo, hi = fs.cue_span(name, rules, vehicle)
    start = hi if math.isinf(v) else v
    if spec.worsens is Worsens.WHEN_LOWER:
        ends = [(start, lo)]
    elif spec.worsens is Worsens.WHEN_HIGHER:
        ends = [(start, hi)]
    else:  # brightness: away from the band, on the side it is on (from the band's edges when inside it)
        band_lo, band_hi = rules.brightness_band
        ends = [(min(v, band_lo), 0.0)] if v <= band_lo else [(max(v, band_hi), 255.0)] if v >= band_hi else []
    path = [float(x) for a, b in ends for x in np.linspace(a, b, SWEEP_POINTS)]
    if math.isinf(spec.high) and spec.worsens is Worsens.WHEN_LOWER and math.isinf(v):
        path.insert(0, math.inf)  # nothing in range, then an obstacle coming closer
    elif math.isinf(spec.high) and spec.worsens is Worsens.WHEN_HIGHER:
        path.append(math.inf)  # never localised is the stalest
    return path


def _sweep_drop(rules: fg.RuleBase, cues: fg.Cues, name: str, vehicle: fg.VehicleLimits) -> tuple[fg.Cues, fg.Cues, float, float] | None:
    """Fear along the whole worsening path of one cue, the other cues fixed: the first step where it falls
    (the better and the worse cues, their fears), or None."""
    path = worsening_path(cues, name, rules, vehicle)
    if len(path) < 2:
        return None
    rows = np.array([replace(cues, **{name: x}).as_array() for x in path])
    fear = rules.evaluate_batch(rows)
    drops = np.flatnonzero(fear[1:] < fear[:-1] - FEAR_TOL)
    if not drops.size:
        return None
    k = int(drops[0])
    return replace(cues, **{name: path[k]}), replace(cues, **{name: path[k + 1]}), float(fear[k]), float(fear[k + 1])


def _fear_sweep(rules: fg.RuleBase, cues: fg.Cues, name: str, vehicle: fg.VehicleLimits) -> str | None:
    """Fear along the worsening path of one cue from these cues, and from the calm picture (a drop a busy picture
    masks shows there): it must never fall."""
    for base in (cues, fs.best_cues(rules)):
        drop = _sweep_drop(rules, base, name, vehicle)
        if drop is not None:
            b, w, fb, fw = drop
            return (f"the rules' fear falls {fb:.6g} → {fw:.6g} when {name} worsens {getattr(b, name):.6g} → "
                    f"{getattr(w, name):.6g} (the other cues as in {b})")
    return None


def _monotone_at_drop(subject: Subject, case: Case) -> Case:
    """A rules-level drop found by the sweep, put on the last frames of the case: the history shows the failing values."""
    name = str(case.params.get("cue"))
    if case.params.get("kind") == "closing" or name not in CUE_NAMES:
        return case
    better = case.run("better")
    for base in (better[-1].cues, fs.best_cues(subject.rules)):
        drop = _sweep_drop(subject.rules, base, name, subject.vehicle) if base is not None else None
        if drop is not None:
            b, w, _, _ = drop
            params = {**case.params, "from": _num(getattr(b, name)), "to": _num(getattr(w, name))}
            runs = tuple((k, (*h[:-1], replace(h[-1], cues=b if k == "better" else w))) for k, h in case.runs)
            return Case(runs, f"{name} worse on the last frame: {params['from']} → {params['to']}", params)
    return case


def _monotone_cases(subject: Subject) -> st.SearchStrategy[Case]:
    rb, car = subject.rules, subject.vehicle
    # a calm base lets one group's fear show (fear is the max over groups: a busy picture masks a group)
    hazard_or_valid = st.one_of(fs.calm_cues(rb, car), fs.hazard_cues(rb), fs.cues(rb, car, unknown=False))

    prefixes = fs.histories(rb, car, cues=st.one_of(hazard_or_valid, fs.cues(rb, car)), max_size=15, frames=_frames_for(subject))
    names, amounts, edges = st.sampled_from(CUE_NAMES), st.floats(0.0, 1.0), st.sampled_from(rb.brightness_band)
    gaps, speeds, leads = st.sampled_from([0.05, 0.1, 0.5]), fs.speeds(car, unknown=False), fs.leads(boxes=False)
    steer = fs.steering_outputs(car, faults=False)

    @st.composite
    def pair(draw: Any) -> Case:
        prefix, last, name, amount = draw(prefixes), draw(hazard_or_valid), draw(names), draw(amounts)
        w = worse(last, name, amount, rb, car)
        if w is None:  # brightness inside the normal band: move it to an edge of the band first
            last = replace(last, brightness=draw(edges))
            w = worse(last, name, amount, rb, car)
            assert w is not None
        t_last = max([_t(s) or 0.0 for s in prefix]) + draw(gaps)
        tail = Step(t_s=t_last, speed_mps=draw(speeds), lead=draw(leads), steer_output=draw(steer), frame=prefix[-1].frame)
        params = {"cue": name, "from": _num(getattr(last, name)), "to": _num(getattr(w, name))}
        return Case((("better", (*prefix, replace(tail, cues=last))), ("worse", (*prefix, replace(tail, cues=w)))),
                    note=f"{name} worse on the last frame", params=params)

    rates, faster = st.floats(-2.0 * car.max_speed_mps, car.max_speed_mps), st.floats(0.0, 2.0 * car.max_speed_mps)
    ranges = fs.valid_values("obstacle_range_m", rb, car)

    @st.composite
    def closing(draw: Any) -> Case:  # the same drive; on the last frame the obstacle approaches faster
        prefix, last, rate, more = draw(prefixes), draw(hazard_or_valid), draw(rates), draw(faster)
        last = replace(last, obstacle_range_m=draw(ranges))
        t_last = max([_t(s) or 0.0 for s in prefix]) + draw(gaps)
        tail = Step(t_s=t_last, speed_mps=draw(speeds), cues=last, lead=draw(leads), steer_output=draw(steer), frame=prefix[-1].frame)
        params = {"kind": "closing", "from": rate, "to": rate - more}
        runs = (("better", (*prefix, replace(tail, range_rate_mps=rate))), ("worse", (*prefix, replace(tail, range_rate_mps=rate - more))))
        return Case(runs, note="the obstacle closes faster on the last frame", params=params)

    return st.one_of(pair(), pair(), closing())


def _num(v: float) -> float | str:
    return v if math.isfinite(v) else ("inf" if v > 0 else "-inf")


# -- 4. unknown = worst ---------------------------------------------------------------------------
def check_unknown_is_worst(subject: Subject, case: Case) -> str | None:
    """Losing the camera (the picture's cues unknown), everything else calm, ends in EMERGENCY after
    enter_frames; an unknown cue gives exactly the fear (and the command) of its worst value; no rule
    firing gives fear 1."""
    rb = subject.rules
    r = run(subject, case.run("camera_lost"))
    if r.raised:
        return _broken(r)
    n = rb.policy.enter_frames
    if not any(c.mode is fg.Mode.EMERGENCY for c in r.commands[:n]):
        peak = max(c.fear for c in r.commands)
        return (f"the camera is lost ({', '.join(VISION_CUES)} unknown = worst), everything else calm, for {len(r.commands)} "
                f"frames: no EMERGENCY within enter_frames = {n} (fear at most {peak:.4g}, the emergency threshold is "
                f"{rb.policy.emergency_enter_fear:g}); last: {_cmd_text(r.commands[-1])}")
    name = str(case.params["cue"])
    unknown_run = case.run("unknown")
    bad_cues = unknown_run[-1].cues
    assert bad_cues is not None
    worst_runs = [h for k, h in case.runs if k.startswith("worst")]
    expected = max(rb.evaluate(h[-1].cues).fear for h in worst_runs)  # type: ignore[arg-type]
    got = rb.evaluate(bad_cues)
    if got.fear != expected:
        return f"{name} = {getattr(bad_cues, name)!r} is unknown: fear {got.fear!r}, but its worst value gives {expected!r}"
    rows = np.array([bad_cues.as_array(), *(h[-1].cues.as_array() for h in worst_runs)])  # type: ignore[union-attr]
    batch = rb.evaluate_batch(rows)
    if abs(batch[0] - batch[1:].max()) > FEAR_TOL:
        return f"{name} = {getattr(bad_cues, name)!r} is unknown: evaluate_batch gives {batch[0]!r}, its worst value {batch[1:].max()!r}"
    for group in rb.groups:
        silent = all(got.activations.get(rule.text, 0.0) <= 0.0 for rule in group.rules)
        if silent and (got.group_fears[group.name] != 1.0 or got.fear != 1.0):
            return (f"no rule of group {group.name!r} fires at {bad_cues}: its fear is {got.group_fears[group.name]!r} "
                    f"and fear {got.fear!r}, not 1")
    r_bad = run(subject, unknown_run)
    r_worst = [run(subject, h) for h in worst_runs]
    for r in (r_bad, *r_worst):
        if r.raised:
            return _broken(r)
    b = r_bad.commands[-1]
    worst_fear = max(r.commands[-1].fear for r in r_worst)  # the supervisor's (an absent sensor's cue is neutral in both)
    matches = [r.commands[-1] for r in r_worst if r.commands[-1].fear == worst_fear]
    if not any(b.fear == m.fear and b.speed_limit_mps == m.speed_limit_mps and b.mode is m.mode for m in matches):
        return f"{name} = {getattr(bad_cues, name)!r} on the last frame: {_cmd_text(b)}; with its worst value: {_cmd_text(matches[0])}"
    return None


def _unknown_cases(subject: Subject) -> st.SearchStrategy[Case]:
    rb, car = subject.rules, subject.vehicle

    prefixes = fs.histories(rb, car, max_size=10, frames=_frames_for(subject))
    bases = st.one_of(fs.calm_cues(rb, car), fs.cues(rb, car, unknown=False), fs.hazard_cues(rb))
    names, unknown = st.sampled_from(CUE_NAMES), {n: fs.unknown_values(n) for n in CUE_NAMES}
    speeds, steer, dts = fs.speeds(car, unknown=False), fs.steering_outputs(car, faults=False), st.floats(0.02, 0.5)

    @st.composite
    def pair(draw: Any) -> Case:
        prefix, base, name = draw(prefixes), draw(bases), draw(names)
        bad = draw(unknown[name])
        t_last = max([_t(s) or 0.0 for s in prefix]) + 0.1
        tail = Step(t_s=t_last, speed_mps=draw(speeds), steer_output=draw(steer), frame=prefix[-1].frame)
        runs = [("unknown", (*prefix, replace(tail, cues=replace(base, **{name: bad}))))]
        runs += [(f"worst{k}", (*prefix, replace(tail, cues=replace(base, **{name: w})))) for k, w in enumerate(fs.worst_values(name))]
        # and a camera lost for good, everything else calm: an unknown picture must end in EMERGENCY
        lost = replace(fs.best_cues(rb), **{n: draw(unknown[n]) for n in VISION_CUES})
        dt = draw(dts)
        runs.append(("camera_lost", tuple(Step(t_s=k * dt, speed_mps=draw(speeds), cues=lost) for k in range(rb.policy.enter_frames + 2))))
        return Case(tuple(runs), note=f"{name} unknown on the last frame; the camera lost", params={"cue": name})

    return pair()


# -- 5. no chattering -----------------------------------------------------------------------------
def check_no_chattering(subject: Subject, case: Case) -> str | None:
    """Entering EMERGENCY needs enter_frames consecutive frames over the threshold (faults and imminent
    collisions enter at once); leaving needs fear below the exit threshold for hold_s, over at least two
    frames (one calm frame is not evidence)."""
    cfg = subject.rules.policy
    history = case.run("drive")
    r = run(subject, history)
    if r.raised:
        return _broken(r)
    cmds = r.commands
    times = [_t(s) for s in history]
    entered_at: float | None = None
    for i, cmd in enumerate(cmds):
        was = cmds[i - 1].mode if i else fg.Mode.NORMAL
        if cmd.mode is fg.Mode.EMERGENCY and was is not fg.Mode.EMERGENCY:
            entered_at = times[i]
            if _is_fault(cmd):
                continue
            window = [c.fear for c in cmds[max(0, i + 1 - cfg.enter_frames) : i + 1]]
            if i + 1 < cfg.enter_frames or not all(f >= cfg.emergency_enter_fear for f in window):
                return (f"frame {i}: entered EMERGENCY after the fears {[round(f, 4) for f in window]}, but entering needs "
                        f"{cfg.enter_frames} consecutive frames with fear ≥ {cfg.emergency_enter_fear:g}")
        if was is fg.Mode.EMERGENCY and cmd.mode is not fg.Mode.EMERGENCY:
            k = i
            while k > 0 and _calm_in_emergency(cmds[k - 1], cfg):
                k -= 1
            calm_for = (times[i] or 0.0) - (times[k] or 0.0)
            if cmd.fear >= cfg.emergency_exit_fear or k == i or calm_for < cfg.hold_s:
                return (f"frame {i}: left EMERGENCY (entered at t = {entered_at} s) after {i - k + 1} frame(s) and {calm_for:.4g} s "
                        f"with fear below {cfg.emergency_exit_fear:g}; leaving needs {cfg.hold_s:g} s over at least two frames "
                        f"(hold_s = {cfg.hold_s:g}: {'a latch of 0 s lets the mode chatter' if cfg.hold_s <= 0 else 'brake latch'})")
    return None


def _calm_in_emergency(cmd: fg.Command, cfg: fg.PolicyConfig) -> bool:
    """A frame of EMERGENCY (not a fault) with fear below the exit threshold: it counts toward leaving."""
    return cmd.fear < cfg.emergency_exit_fear and not _is_fault(cmd) and cmd.mode is fg.Mode.EMERGENCY


def _chattering_cases(subject: Subject) -> st.SearchStrategy[Case]:
    rb, car = subject.rules, subject.vehicle
    clear = {"obstacle_range_m": math.inf}  # no collision cause: every entry must be earned by enter_frames
    ladder = st.one_of(fs.hazard_cues(rb), fs.calm_cues(rb, car), fs.cues(rb, car, unknown=False)).map(lambda c: replace(c, **clear))
    steps = st.lists(st.tuples(st.floats(0.02, 0.6), ladder), min_size=1, max_size=60)

    def build(items: Sequence[tuple[float, fg.Cues]]) -> Case:
        t, out = 0.0, []
        for dt, c in items:
            t += dt
            out.append(Step(t_s=t, speed_mps=0.0, cues=c, steer_output=0.0))
        return Case.drive(out)

    lost = replace(fs.best_cues(rb), lane_confidence=0.0, occlusion=1.0)  # every bundled file's EMERGENCY

    @st.composite
    def enter_then_calm(draw: Any) -> Case:  # an EMERGENCY, then calm pictures: the latch must hold for hold_s
        dt, hot, calm = draw(st.sampled_from(STEADY_DT_S)), draw(st.integers(rb.policy.enter_frames, 8)), draw(st.integers(2, 40))
        items = [(dt, lost)] * hot + [(dt, draw(fs.calm_cues(rb, car)))] * calm
        return replace(build(items), note=f"{hot} frames of a lost road, then {calm} calm ones, every {dt:g} s")

    return st.one_of(enter_then_calm(), steps.map(build), steps.map(build))


# -- 6. rate limits -------------------------------------------------------------------------------
def check_rate_limits(subject: Subject, case: Case) -> str | None:
    """The speed limit falls at once (never above what fear and the envelope allow) and rises no faster
    than the comfort acceleration."""
    cfg = subject.rules.policy
    for _, history in case.runs:
        r = run(subject, history)
        if r.raised:
            return _broken(r)
        ref: tuple[float, float] | None = None  # (time, limit) of the supervisor's last frame with a clock
        for i, (step, cmd) in enumerate(zip(history, r.commands, strict=True)):
            t = _t(step)
            prev_limit = r.commands[i - 1].speed_limit_mps if i else None
            if t is not None and ref is not None and prev_limit is not None and t > ref[0]:
                allowed = prev_limit + cfg.comfort_accel_mps2 * (t - ref[0])
                if cmd.speed_limit_mps > allowed + TOL:
                    return (f"frame {i}: the speed limit rises {prev_limit:.4g} → {cmd.speed_limit_mps:.4g} m/s in {t - ref[0]:.4g} s, "
                            f"faster than the comfort acceleration {cfg.comfort_accel_mps2:g} m/s²")
            cap = min(cmd.fear_limit_mps, cmd.envelope_mps)
            if not math.isnan(cap) and cmd.speed_limit_mps > cap + FEAR_TOL:
                return f"frame {i}: the speed limit {cmd.speed_limit_mps:.4g} m/s is above what fear and the envelope allow ({cap:.4g} m/s)"
            if t is not None:
                ref = (t, cmd.speed_limit_mps)
    return None


# -- 7. pass-through ------------------------------------------------------------------------------
RATE_WORDS = ("rate", "limit")  # a reason naming the physical limit that changed the steering


def check_pass_through(subject: Subject, case: Case) -> str | None:
    """At very low fear in NORMAL the wrapped steering angle is returned unchanged (PASS_THROUGH), unless a
    physical limit binds: an angle beyond the steering range is held at full lock, and the steering-rate limit
    moves the angle exactly max_steering_rate_dps × dt toward that — the smallest change that respects both — with a
    reason. A steady drive through the calmest picture does reach very low fear in NORMAL (else the check would be
    vacuous)."""
    history = case.run("drive")
    r = run(subject, history)
    if r.raised:
        return _broken(r)
    rate = subject.vehicle.max_steering_rate_dps
    last_t: float | None = None
    for i, (step, cmd, raw) in enumerate(zip(history, r.commands, r.steering_in, strict=True)):
        t = _t(step)
        if cmd.mode is fg.Mode.NORMAL and cmd.fear_level is fg.FearLevel.VERY_LOW:
            wanted = finite_reading(raw)
            if cmd.strategy is not fg.Strategy.PASS_THROUGH or wanted is None:
                return f"frame {i}: NORMAL at VERY_LOW fear, the steering function said {raw!r} deg but the command is {_cmd_text(cmd)}"
            lock = subject.vehicle.max_steering_deg
            if abs(wanted) > lock and not any("full lock" in reason for reason in cmd.reasons):
                return f"frame {i}: the steering function said {wanted!r} deg, beyond ±{lock:g} deg, and no reason says so"
            wanted = min(max(wanted, -lock), lock)
            if cmd.steering_deg != wanted:
                prev = r.commands[i - 1].steering_deg if i else None
                why = _rate_limited(wanted, cmd, prev, None if t is None or last_t is None else t - last_t, rate)
                if why:
                    return f"frame {i}: NORMAL at VERY_LOW fear, the steering function said {wanted!r} deg: {why}; {_cmd_text(cmd)}"
        last_t = t if t is not None else last_t
    if case.params.get("kind") == "steady_calm" and not any(
            c.mode is fg.Mode.NORMAL and c.fear_level is fg.FearLevel.VERY_LOW for c in r.commands):
        return (f"the calmest picture ({fs.best_cues(subject.rules)}) for {len(r.commands)} frames never gives NORMAL at VERY_LOW fear: "
                f"the steering is never passed through; last: {_cmd_text(r.commands[-1])}")
    return None


def _rate_limited(wanted: float, cmd: fg.Command, prev: float | None, dt: float | None, rate: float | None) -> str | None:
    """Why a changed steering angle is not the smallest change the rate limit allows (None: it is)."""
    if rate is None or prev is None or dt is None:
        return "the angle was changed although no steering-rate limit can bind"
    step = rate * max(dt, 0.0)
    smallest = min(max(wanted, prev - step), prev + step)
    if abs(cmd.steering_deg - smallest) > TOL:
        return (f"the rate limit ({rate:g} deg/s × {dt:.4g} s from {prev:+.4g} deg) allows {smallest:+.6g} deg, "
                f"the command is {cmd.steering_deg:+.6g} deg")
    if not any(w in reason.lower() for reason in cmd.reasons for w in RATE_WORDS):
        return "the rate limit changed the angle but no reason says so"
    return None


def _pass_through_cases(subject: Subject) -> st.SearchStrategy[Case]:
    rb, car = subject.rules, subject.vehicle
    calm_or_valid = st.one_of(fs.calm_cues(rb, car), fs.calm_cues(rb, car), fs.cues(rb, car, unknown=False))
    drives = fs.histories(rb, car, cues=calm_or_valid, faults=False, frames=_frames_for(subject), max_size=30).map(Case.drive)

    angles, frames = fs.steering_outputs(car, faults=False), _frames_for(subject) or st.none()

    @st.composite
    def steady(draw: Any) -> Case:
        angle = draw(angles)
        steps = [Step(t_s=0.1 * k, speed_mps=0.0, cues=fs.best_cues(rb), steer_output=angle, frame=draw(frames)) for k in range(5)]
        return Case.drive(steps, note="the calmest picture, steadily", kind="steady_calm")

    return st.one_of(drives, drives, steady())


# -- 8. deterministic -----------------------------------------------------------------------------
def _signature(r: Run) -> list[tuple[Any, ...]]:
    return [(c.steering_deg, c.speed_limit_mps, c.mode, c.strategy, c.fear, c.fear_level, c.reasons) for c in r.commands]


def check_deterministic(subject: Subject, case: Case) -> str | None:
    """The same inputs give the same outputs: two fresh supervisors, and one after ``reset()``, agree frame by frame."""
    history = case.run("drive")
    driver = Driver(subject)
    first = driver.drive(history)
    if first.raised:
        return _broken(first)
    again = run(subject, history)
    driver.reset()
    after_reset = driver.drive(history)
    for label, other in (("a second fresh supervisor", again), ("the same supervisor after reset()", after_reset)):
        for i, (a, b) in enumerate(zip(_signature(first), _signature(other), strict=True)):
            if a != b:
                return f"frame {i}: {label} answers differently: {a} vs {b}"
    return None


# -- 9. liveness of the recovery ------------------------------------------------------------------
RECOVERY_WAIT_S = 30.0  # [s] standing still in a road-picture emergency: the creep must have come by then


def check_recovery_is_live(subject: Subject, case: Case) -> str | None:
    """A road-picture emergency (no fault, nothing in the way) at standstill with the path known clear — a range reading
    beyond a creep's stopping distance, or nothing within a range sensor's reach — is followed by a bounded creep (speed
    limit > 0) within RECOVERY_WAIT_S, even with nothing of the lane in sight; with nothing known about the path, an
    obstacle near or after a fault it stays stopped, and a road-picture stop says why."""
    history = case.run("drive")
    r = run(subject, history)
    if r.raised:
        return _broken(r)
    kind = case.params.get("kind")
    if kind == "fault" and not any(isinstance(a, SteerRaises) for a in r.steering_in):
        kind = "road_lost"  # the subject's own steering function answered: the scripted fault did not happen
    creeps = [i for i, c in enumerate(r.commands) if c.mode is fg.Mode.EMERGENCY and c.speed_limit_mps > 0.0]
    if kind == "road_lost" and not creeps:
        return (f"the road picture is lost, the path known clear, car standing: still {_cmd_text(r.commands[-1])} after "
                f"{history[-1].t_s:.4g} s")
    if kind in ("obstacle", "fault", "unknown_path") and creeps:
        return f"frame {creeps[0]}: a creep ({_cmd_text(r.commands[creeps[0]])}) although {case.note}"
    last = r.commands[-1]
    if kind == "unknown_path" and not any("staying stopped" in x for x in last.reasons):
        return f"the path ahead is unknown and the car stays stopped, but no reason says why: {last.reasons}"
    cfg = subject.rules.policy
    episodes = _runs_of(creeps)
    most, longest_s = cfg.recovery_max_creeps, cfg.recovery_creep_s
    if len(episodes) > most:
        return f"{len(episodes)} creeps in one EMERGENCY, more than recovery_max_creeps = {most}"
    dt = float(case.params.get("dt", 0.0))
    for a, b in episodes:
        lasted = float(history[b].t_s) - float(history[a].t_s)
        if lasted > longest_s + dt + TOL:
            return f"frames {a}-{b}: a creep of {lasted:.4g} s, longer than recovery_creep_s = {longest_s:g} s"
    return None


def _runs_of(indices: Sequence[int]) -> list[tuple[int, int]]:
    """Consecutive runs in a sorted list of frame indices, as (first, last)."""
    runs: list[tuple[int, int]] = []
    for i in indices:
        if runs and i == runs[-1][1] + 1:
            runs[-1] = (runs[-1][0], i)
        else:
            runs.append((i, i))
    return runs


def _recovery_cases(subject: Subject) -> st.SearchStrategy[Case]:
    rb, car = subject.rules, subject.vehicle
    need = creep_needs_m(rb.policy, car)
    calm_from = max(need, fs.calm_ranges(rb)["obstacle_range_m"][0])  # clear for a creep, and far enough to be no hazard
    scripted = ["fault"] if subject.steer is None else []  # a fault can be scripted only for the scripted steering
    kinds = st.sampled_from(["road_lost", "road_lost", "obstacle", *(["unknown_path"] if not car.has_ultrasonic else []), *scripted])
    # a given range counts up to the sensor's maximum: beyond it, it reads as the maximum (issue 31)
    far = [st.floats(calm_from, car.ultrasonic_max_range_m)] if calm_from <= car.ultrasonic_max_range_m else []
    clear_ranges = st.one_of(*far, st.just(math.inf)) if car.has_ultrasonic else far[0] if far else st.just(math.inf)
    if not far and not car.has_ultrasonic:  # these rules call every range this car can report a hazard: no path known clear
        kinds = st.sampled_from(["obstacle", "unknown_path", *scripted])
    near = st.floats(0.0, need, exclude_max=True)

    @st.composite
    def standstill(draw: Any) -> Case:
        kind = draw(kinds)
        # nothing of the lane in sight, markings hidden: the road picture alone is lost (issue 35: where the markings end)
        lost = replace(fs.best_cues(rb), lane_confidence=draw(st.sampled_from([0.0, rb.policy.recovery_min_confidence])), occlusion=1.0)
        rng = draw(clear_ranges) if kind in ("road_lost", "fault") else draw(near) if kind == "obstacle" else math.inf
        lost = replace(lost, obstacle_range_m=rng)
        dt = draw(st.sampled_from(STEADY_DT_S))
        n = int(RECOVERY_WAIT_S / dt)
        steps = [Step(t_s=k * dt, speed_mps=0.0, cues=lost, steer_output=SteerRaises() if kind == "fault" and k == 0 else 0.0)
                 for k in range(n)]
        note = {"road_lost": "the road picture is lost", "obstacle": "an obstacle is closer than a creep could stop for",
                "fault": "the steering function faulted", "unknown_path": "nothing is known about the path ahead"}[kind]
        return Case.drive(steps, note=note, kind=kind, dt=dt)

    return standstill()


# -- 10. the watchdog -----------------------------------------------------------------------------
def check_watchdog(subject: Subject, case: Case) -> str | None:
    """Stale or broken input is a fault for that frame: EMERGENCY/STOP with a zero limit when time does not
    increase (or is not a number) or the steering function fails (raises, NaN, not a number)."""
    for _, history in case.runs:
        r = run(subject, history)
        if r.raised:
            return _broken(r)
        last_t: float | None = None
        for i, (step, cmd, raw) in enumerate(zip(history, r.commands, r.steering_in, strict=True)):
            t = _t(step)
            why = None
            if t is None:
                why = f"time t_s = {step.t_s!r} is not a finite number"
            elif last_t is not None and t <= last_t:
                why = f"time did not increase ({last_t:.4g} s → {t:.4g} s)"
            else:
                why = _steer_fault(raw)
            if why and not _stopped(cmd):
                return f"frame {i}: {why}, but the command is {_cmd_text(cmd)}"
            if t is not None:
                last_t = t
    return None


def _watchdog_cases(subject: Subject) -> st.SearchStrategy[Case]:
    return _drives(subject, max_size=25)




def check_stall(subject: Subject, case: Case) -> str | None:
    """A frame later than the watchdog allows — max(watchdog_frames × the frame period, watchdog_age_s) — is a
    fault for that frame: EMERGENCY/STOP with a zero limit. Checked where it must hold whatever period the
    supervisor measured: a gap longer than watchdog_age_s and watchdog_frames × every earlier gap."""
    cfg = subject.rules.policy
    frames_n, age_s = cfg.watchdog_frames, cfg.watchdog_age_s
    for _, history in case.runs:
        r = run(subject, history)
        if r.raised:
            return _broken(r)
        last_t: float | None = None
        gaps: list[float] = []
        for i, (step, cmd) in enumerate(zip(history, r.commands, strict=True)):
            t = _t(step)
            if t is None:
                continue
            if last_t is not None and t > last_t:
                gap = t - last_t
                allowed = max(age_s, frames_n * max(gaps)) if gaps else age_s
                if gap > allowed + TOL and not _stopped(cmd):
                    return (f"frame {i}: the input stalled {gap:.4g} s (the watchdog allows {allowed:.4g} s), "
                            f"but the command is {_cmd_text(cmd)}")
                gaps.append(gap)
            last_t = t
    return None


def _stall_cases(subject: Subject) -> st.SearchStrategy[Case]:
    rb, car = subject.rules, subject.vehicle
    calm = fs.calm_cues(rb, car)
    periods, stalls, counts = st.sampled_from([0.02, 0.05, 0.1, 0.2]), st.floats(1.0, 6.0), st.integers(2, 25)

    @st.composite
    def steady_then_stall(draw: Any) -> Case:  # a steady drive, one late frame, then the steady drive again
        dt, n, gap = draw(periods), draw(counts), draw(stalls)
        times = [k * dt for k in range(n)] + [(n - 1) * dt + gap + k * dt for k in range(3)]
        return Case.drive((Step(t_s=t, speed_mps=car.max_speed_mps / 2, cues=draw(calm)) for t in times),
                          note=f"{n} frames every {dt:g} s, then one {gap:.3g} s late")

    return st.one_of(steady_then_stall(), steady_then_stall(), _drives(subject, max_size=25, frame_level=False))


def _vision(cmd: fg.Command) -> tuple[float, ...]:
    """The picture's cues of a command, NaN made comparable."""
    return tuple(-1.0 if not isinstance(v, float) or math.isnan(v) else v for v in (getattr(cmd.cues, n) for n in VISION_CUES))


def check_refilled_buffer(subject: Subject, case: Case) -> str | None:
    """One buffer refilled with new pixels every frame (as camera drivers do) is analysed afresh: the
    commands are those of the same pixels in new arrays (an identity cache would repeat the first frame)."""
    history = case.run("drive")
    fresh = tuple(replace(s, frame=replace(s.frame, reuse_buffer=False)) if s.frame is not None else s for s in history)
    a, b = run(subject, history), run(subject, fresh)
    for r in (a, b):
        if r.raised:
            return _broken(r)
    for i, (x, y) in enumerate(zip(a.commands, b.commands, strict=True)):
        if _vision(x) != _vision(y) or x.speed_limit_mps != y.speed_limit_mps or x.mode is not y.mode:
            return (f"frame {i}: the pixels arrive in the previous frame's buffer and the answer differs from the same pixels in a "
                    f"new array: cues {_vision(x)} vs {_vision(y)}; {_cmd_text(x)} vs {_cmd_text(y)}")
    return None


def _refill_cases(subject: Subject) -> st.SearchStrategy[Case]:
    kinds = st.sampled_from(["render", "synthetic"])
    renders = st.builds(FrameSpec, kind=st.just("render"), source=st.sampled_from(fs.RENDER_SCENARIOS),
                        index=st.integers(0, fs.RENDER_POOL - 1), effect=st.sampled_from(fs.EFFECTS))
    synthetic = st.builds(FrameSpec, kind=st.just("synthetic"), index=st.integers(0, 20), effect=st.sampled_from(fs.EFFECTS),
                          offset_px=st.floats(-40.0, 40.0))
    counts, speeds = st.integers(2, 8), fs.speeds(subject.vehicle, unknown=False)

    @st.composite
    def refilled(draw: Any) -> Case:
        specs = renders if draw(kinds) == "render" else synthetic
        n = draw(counts)
        frames = [draw(specs) for _ in range(n)]
        steps = [Step(t_s=0.05 * k, speed_mps=draw(speeds), frame=replace(f, reuse_buffer=k > 0)) for k, f in enumerate(frames)]
        return Case.drive(steps, note="one buffer refilled with each new frame")

    return refilled()




def check_repeated_frames(subject: Subject, case: Case) -> str | None:
    """The same frame content again within a short window (a loop faster than its camera) is "no new frame":
    no "frozen" reason and the same picture cues as when it was new; content identical for longer than the
    frozen threshold (perception.FROZEN_S) is a frozen camera: its picture cues are unknown."""
    frozen_s = FROZEN_S
    history = case.run("drive")
    r = run(subject, history)
    if r.raised:
        return _broken(r)
    first: dict[Any, tuple[int, float]] = {}
    for i, (step, cmd) in enumerate(zip(history, r.commands, strict=True)):
        key = step.frame
        if i == 0 or key != history[i - 1].frame:
            first = {key: (i, float(step.t_s))}
            continue
        k, since = first[key]
        same_s = float(step.t_s) - since
        frozen = any("frozen" in reason for reason in cmd.reasons)
        if same_s <= 0.5 * frozen_s and (frozen or _vision(cmd) != _vision(r.commands[k])):
            return (f"frame {i}: the frame of frame {k} again after {same_s:.3g} s (a loop faster than its camera; frozen means "
                    f"over {frozen_s:g} s): {'a frozen camera' if frozen else 'other picture cues'} — cues {_vision(cmd)} vs "
                    f"{_vision(r.commands[k])}")
        if same_s > 1.5 * frozen_s and _vision(cmd) != (-1.0, -1.0, -1.0):
            return (f"frame {i}: the same pixels for {same_s:.3g} s (over {frozen_s:g} s: a frozen camera) but the picture cues "
                    f"are known: {_vision(cmd)}")
    return None


def _repeat_cases(subject: Subject) -> st.SearchStrategy[Case]:
    frames = fs.frame_specs(garbage=False)
    repeats, periods, speeds = st.integers(1, 4), st.sampled_from([0.02, 0.05]), fs.speeds(subject.vehicle, unknown=False)
    stuck = st.integers(0, 1)

    @st.composite
    def camera_slower_than_loop(draw: Any) -> Case:  # e.g. a 5 fps camera read by a 20 Hz loop; once maybe a frozen camera
        dt, n_frames = draw(periods), draw(st.integers(1, 4))
        steps: list[Step] = []
        for j in range(n_frames):
            spec = replace(draw(frames), reuse_buffer=False)
            copies = draw(repeats) if not (j == n_frames - 1 and draw(stuck)) else math.ceil(2.0 / dt)  # frozen for 2 s
            for _ in range(copies):
                steps.append(Step(t_s=len(steps) * dt, speed_mps=draw(speeds), frame=spec))
        return Case.drive(steps, note=f"a camera slower than the loop (every {dt:g} s)")

    return camera_slower_than_loop()


# -- 11. reachable: each hazard alone reaches its response ----------------------------------------
REACH_EXTRA_FRAMES = 2  # [frames] the hazard lasts enter_frames and this many more before the answer is judged
CALM_LEAD_IN = 3  # [frames] calm frames before the hazard arrives


def _promise_of(subject: Subject, spec: Any) -> Promise:
    """The promise a run drives (a case's params), rebuilt from the rule file so a saved case replays against the file."""
    cue, value, response = str(spec["cue"]), float(spec["value"]), Response[str(spec["response"])]
    found = [p for p in promises(subject.rules, (cue,)) if p.value == value and p.response is response]
    return found[0] if found else Promise(cue, value, str(spec.get("where", "given")), None, response)


def _answers(response: Response, cmd: fg.Command, lead: bool) -> bool:
    """Does the command answer as the promise says?"""
    if response is Response.CAUTION:
        return cmd.mode is not fg.Mode.NORMAL
    if cmd.mode is not fg.Mode.EMERGENCY:
        return False
    if response is Response.ROAD_EMERGENCY:
        return cmd.strategy in ((fg.Strategy.STOP, fg.Strategy.FOLLOW_LEAD) if lead else (fg.Strategy.STOP,))
    if response is Response.COLLISION_STOP:
        return cmd.strategy is fg.Strategy.STOP and cmd.speed_limit_mps == 0.0
    return cmd.strategy is fg.Strategy.CRAWL


def check_reachable(subject: Subject, case: Case) -> str | None:
    """Each cue the car has, alone at its worst (the others calm), held for enter_frames and the flicker grace
    (``road_enter_s``), reaches the response the design promises:
    a lost or hidden road EMERGENCY (STOP, or FOLLOW_LEAD with a lead), an obstacle in the rules' imminent or near
    range EMERGENCY STOP, darkness or glare at least CAUTION, stale localisation EMERGENCY CRAWL; half-way into
    each worst term at least CAUTION (fuzzy/promises.py). One run per promise; the first that is not kept fails."""
    specs = case.params["promises"]
    for (_, history), spec in zip(case.runs, specs, strict=True):
        promise = _promise_of(subject, spec)
        r = run(subject, history)
        if r.raised:
            return _broken(r)
        cmd, lead = r.commands[-1], history[-1].lead is not None
        if _answers(promise.response, cmd, lead):
            continue
        result = subject.rules.evaluate(promise.cues(subject.rules))
        rule = rule_for(subject.rules, promise)
        fired = f" (fired {result.activations[rule]:.2f})" if rule in result.activations else ""
        should = f"; the rule that should have fired: {rule!r}{fired}" if rule else "; no rule of the file reads this term"
        return (f"{promise.text()} for {len(history) - CALM_LEAD_IN} frames: fear {cmd.fear:.3f} ({cmd.fear_level.name}), "
                f"{cmd.mode.name} {cmd.strategy.name} at {cmd.speed_limit_mps:.3g} m/s; promised {promise.response.value}"
                f"{' (a lead ahead)' if lead else ''}{should}")
    return None


def _first_broken_promise(subject: Subject, case: Case) -> Case:
    """Only the run of the first promise not kept: the counterexample shows one history, the one that matters."""
    for run_, spec in zip(case.runs, case.params["promises"], strict=True):
        one = Case((run_,), case.note, {"promises": [spec]})
        if check_reachable(subject, one) is not None:
            return Case((run_,), f"{_promise_of(subject, spec).text()}: promised {spec['response']}", {"promises": [spec]})
    return case


def _reachable_cases(subject: Subject) -> st.SearchStrategy[Case]:
    rb, car = subject.rules, subject.vehicle
    cues = tuple(n for n in CUE_NAMES if n != "qr_staleness_s" or car.has_qr_localisation)  # QR: only a car that has it
    chosen = promises(rb, cues)
    dts, speeds = st.sampled_from(STEADY_DT_S), fs.speeds(car, unknown=False)
    leads = st.one_of(st.none(), st.builds(fg.Lead, st.floats(-15.0, 15.0), st.one_of(st.none(), st.floats(5.0, 60.0))))
    best = fs.best_cues(rb)

    @st.composite
    def drives(draw: Any) -> Case:  # every promise, each in its own run, at one frame rate, speed and lead
        dt, v, lead = draw(dts), draw(speeds), draw(leads)
        n = CALM_LEAD_IN + rb.policy.enter_frames + REACH_EXTRA_FRAMES + math.ceil(rb.policy.road_enter_s / dt)  # a flicker's grace
        runs = []
        for p in chosen:
            hazard = p.cues(rb)
            calm = replace(hazard, **{p.cue: getattr(best, p.cue)})
            ahead = lead if p.response is Response.ROAD_EMERGENCY else None
            speed = 0.0 if p.cue == "obstacle_range_m" else v  # a standing obstacle at a range that does not change: a car at rest
            runs.append((f"{p.cue}={p.value:g}", tuple(
                Step(t_s=k * dt, speed_mps=speed, cues=calm if k < CALM_LEAD_IN else hazard,
                     lead=None if k < CALM_LEAD_IN else ahead, steer_output=0.0) for k in range(n))))
        specs = [{"cue": p.cue, "value": p.value, "where": p.where, "response": p.response.name} for p in chosen]
        return Case(tuple(runs), note=f"each of {len(chosen)} hazards alone, every {dt:g} s at {v:.3g} m/s",
                    params={"promises": specs})

    return drives()


INVARIANTS: tuple[Invariant, ...] = (
    Invariant("1", "limits_in_range", "limits in range",
              "0 ≤ speed_limit_mps ≤ max_speed_mps; fear in [0, 1]; steering within ±max_steering_deg",
              lambda s: _drives(s), check_limits_in_range, prefix_closed=True),
    Invariant("2", "safe_distance", "safe distance", "v·t_r + v²/(2·a) ≤ max(0, d − margin) for v = the speed limit",
              _safe_distance_cases, check_safe_distance, prefix_closed=True),
    Invariant("3", "monotone", "monotone in each cue and closing speed",
              "a cue getting worse never lowers fear nor raises the speed limit; a faster closing speed never raises it",
              _monotone_cases, check_monotone, narrow=_monotone_at_drop),
    Invariant("4", "unknown_is_worst", "unknown = worst",
              "a NaN cue gives exactly the fear of that cue's worst value; no rule firing = fear 1",
              _unknown_cases, check_unknown_is_worst),
    Invariant("5", "no_chattering", "no chattering", "EMERGENCY needs enter_frames frames to enter and hold_s to leave",
              _chattering_cases, check_no_chattering, prefix_closed=True),
    Invariant("6", "rate_limits", "rate limits", "the speed limit falls at once, rises no faster than a comfort acceleration",
              lambda s: _drives(s), check_rate_limits, prefix_closed=True),
    Invariant("7", "pass_through", "pass-through", "at very low fear in NORMAL the wrapped steering angle is returned unchanged",
              _pass_through_cases, check_pass_through),
    Invariant("8", "deterministic", "deterministic", "same inputs, same outputs", lambda s: _drives(s), check_deterministic,
              prefix_closed=True),
    Invariant("9", "recovery_is_live", "liveness of the recovery",
              "a road-picture emergency (range clear, no fault) is followed by a bounded creep, not a stop for good",
              _recovery_cases, check_recovery_is_live),
    Invariant("10", "watchdog", "stale input is a fault", "time not increasing, a failed steering function: EMERGENCY/STOP at once",
              _watchdog_cases, check_watchdog, prefix_closed=True),
    Invariant("10", "stall", "a stall is a fault", "a frame later than the watchdog allows gives EMERGENCY/STOP",
              _stall_cases, check_stall, prefix_closed=True),
    Invariant("10", "refilled_buffer", "a refilled buffer is a new frame", "one buffer refilled with new pixels is analysed afresh",
              _refill_cases, check_refilled_buffer, prefix_closed=True),
    Invariant("10", "repeated_frames", "a repeated frame is no new frame",
              "a repeated frame within a short window is 'no new frame', not a frozen camera", _repeat_cases, check_repeated_frames,
              prefix_closed=True),
    Invariant("11", "reachable", "each hazard alone reaches its response",
              "a cue alone at its worst (the others calm) reaches the mode and strategy the design promises", _reachable_cases,
              check_reachable, narrow=_first_broken_promise),
)


def invariant(key: str) -> Invariant:
    """An invariant by key ("safe_distance") or number ("2")."""
    for inv in INVARIANTS:
        if key in (inv.key, inv.number):
            return inv
    raise KeyError(f"no invariant {key!r}; known: {', '.join(i.key for i in INVARIANTS)}")
