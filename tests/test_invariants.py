"""Property tests (hypothesis) for every safety invariant of DESIGN.md, numbered as there."""

from __future__ import annotations

import math
import tempfile
from pathlib import Path

import numpy as np
from hypothesis import assume, given
from hypothesis import strategies as st

import fearguard as fg
from fearguard.cues import CUE_NAMES

RULES = fg.load_rules()
# a variant where glare is worse than darkness, so "unknown brightness" must pick the right extreme
_ASYM = Path(tempfile.mkdtemp()) / "asymmetric.toml"
_ASYM.write_text((Path(__file__).resolve().parents[1] / "rules" / "default.toml").read_text().replace(
    '"IF brightness IS dark OR brightness IS glare THEN fear IS very_high"',
    '"IF brightness IS dark THEN fear IS medium", "IF brightness IS glare THEN fear IS very_high"'))
ASYMMETRIC = fg.load_rules(_ASYM)
VEHICLE = fg.VehicleLimits()
CFG = RULES.policy
BAND_LO, BAND_HI = RULES.brightness_band

# any float a broken sensor could send, and the meaningful ranges, densely at the boundaries
anything = st.floats(allow_nan=True, allow_infinity=True, width=64)
valid = {
    "lane_confidence": st.floats(0.0, 1.0),
    "brightness": st.floats(0.0, 255.0),
    "occlusion": st.floats(0.0, 1.0),
    "obstacle_range_m": st.one_of(st.floats(0.0, 6.0), st.just(math.inf)),
    "qr_staleness_s": st.one_of(st.floats(0.0, 40.0), st.just(math.inf)),
}
valid_cues = st.builds(fg.Cues, **valid)
calm = {  # values where fear is very low: pass-through must be exercised, not just possible
    "lane_confidence": st.floats(0.75, 1.0),
    "brightness": st.floats(80.0, 180.0),
    "occlusion": st.floats(0.0, 0.1),
    "obstacle_range_m": st.one_of(st.floats(2.2, 6.0), st.just(math.inf)),
    "qr_staleness_s": st.floats(0.0, 3.0),
}
calm_or_valid = st.one_of(st.builds(fg.Cues, **calm), valid_cues)
# hazards that put the supervisor into EMERGENCY with one or several causes at once
HAZARDS = [
    fg.Cues(0.1, 120.0, 0.9, math.inf, 0.5),  # road lost
    fg.Cues(0.9, 250.0, 0.0, math.inf, 0.5),  # glare
    fg.Cues(0.9, 120.0, 0.0, 0.6, 0.5),  # obstacle near
    fg.Cues(0.9, 120.0, 0.0, math.inf, 25.0),  # localisation stale
    fg.Cues(0.1, 120.0, 0.9, math.inf, 25.0),  # road lost and stale
    fg.Cues(0.9, 120.0, 0.0, math.inf, 0.5),  # calm
]
hazard_or_valid = st.one_of(st.sampled_from(HAZARDS), valid_cues)
vehicles = st.builds(fg.VehicleLimits, max_speed_mps=st.floats(0.5, 40.0), max_decel_mps2=st.floats(0.3, 9.0),
                     reaction_time_s=st.floats(0.0, 1.5), stop_margin_m=st.floats(0.0, 1.0))
any_cues = st.builds(fg.Cues, **{n: st.one_of(valid[n], anything) for n in CUE_NAMES})
steer_out = st.one_of(st.floats(-40, 40), anything, st.just("left"), st.none())
lead = st.one_of(st.none(), st.builds(fg.Lead, st.one_of(st.floats(-30, 30), anything), st.one_of(st.none(), st.floats(0, 10), anything)))


@st.composite
def drives(draw, cues=any_cues, n_max=40):
    """A sequence of frames: time steps (sometimes broken), speeds, cues, steering outputs, leads."""
    n = draw(st.integers(1, n_max))
    t, frames = 0.0, []
    for _ in range(n):
        t += draw(st.one_of(st.floats(0.01, 0.5), st.just(-1.0), st.just(0.0))) if frames else 0.0
        frames.append((t, draw(st.one_of(st.floats(0, 3), anything)), draw(cues), draw(steer_out), draw(lead)))
    return frames


def run(frames, vehicle=VEHICLE):
    outputs = iter([f[3] for f in frames])
    guard = fg.FearGuard(lambda frame: next(outputs), rules=RULES, vehicle=vehicle)
    return [guard.step(fg.Observation(t_s=t, speed_mps=v, cues=c, lead=ld)) for t, v, c, _, ld in frames]


# 1. bounds -------------------------------------------------------------------------------------
@given(drives())
def test_1_limits_fear_and_steering_stay_in_bounds(frames) -> None:
    for cmd in run(frames):
        assert 0.0 <= cmd.speed_limit_mps <= VEHICLE.max_speed_mps
        assert 0.0 <= cmd.fear <= 1.0
        assert abs(cmd.steering_deg) <= VEHICLE.max_steering_deg and math.isfinite(cmd.steering_deg)
        assert isinstance(cmd.mode, fg.Mode) and isinstance(cmd.strategy, fg.Strategy) and cmd.reasons


# 2. stopping envelope --------------------------------------------------------------------------
@given(drives(cues=calm_or_valid), vehicles)
def test_2_speed_limit_can_stop_before_the_obstacle(frames, car) -> None:
    for (_, _, cues, _, _), cmd in zip(frames, run(frames, car), strict=True):
        d = cues.obstacle_range_m
        v = cmd.speed_limit_mps
        room = max(0.0, d - car.stop_margin_m)
        assert v * car.reaction_time_s + v * v / (2 * car.max_decel_mps2) <= room


@given(st.builds(fg.Cues, **calm), vehicles)
def test_2_steady_approach_where_physics_binds(cues, car) -> None:
    frames = [(0.1 * k, 0.0, cues, 0.0, None) for k in range(300)]  # 30 s: the limit has ramped up fully
    d = cues.obstacle_range_m
    room = max(0.0, d - car.stop_margin_m)
    for cmd in run(frames, car):
        v = cmd.speed_limit_mps
        assert v * car.reaction_time_s + v * v / (2 * car.max_decel_mps2) <= room


# 3. monotone -----------------------------------------------------------------------------------
def worse(cues: fg.Cues, name: str, amount: float) -> fg.Cues | None:
    """The same cues with one cue worse by `amount` (a fraction of its span); None if no worse value."""
    v = getattr(cues, name)
    if name == "lane_confidence":
        new = v - amount
    elif name == "occlusion":
        new = v + amount
    elif name == "obstacle_range_m":
        new = (6.0 if math.isinf(v) else v) * (1.0 - amount)
    elif name == "qr_staleness_s":
        new = v + 40.0 * amount
    elif v <= BAND_LO:  # brightness: away from the normal band
        new = v - 255.0 * amount
    elif v >= BAND_HI:
        new = v + 255.0 * amount
    else:
        return None
    if name in ("lane_confidence", "occlusion"):
        new = min(max(new, 0.0), 1.0)
    elif name == "brightness":
        new = min(max(new, 0.0), 255.0)
    return fg.Cues(**{**{n: getattr(cues, n) for n in CUE_NAMES}, name: new})


@given(valid_cues, st.sampled_from(CUE_NAMES), st.floats(0.0, 1.0))
def test_3_fear_never_falls_when_a_cue_worsens(cues, name, amount) -> None:
    w = worse(cues, name, amount)
    assume(w is not None)
    assert RULES.evaluate(w).fear >= RULES.evaluate(cues).fear - 1e-12
    both = RULES.evaluate_batch(np.array([cues.as_array(), w.as_array()]))
    assert both[1] >= both[0] - 1e-12


@given(drives(cues=hazard_or_valid, n_max=15), hazard_or_valid, st.sampled_from(CUE_NAMES), st.floats(0.0, 1.0), lead)
def test_3_speed_limit_never_rises_when_a_cue_worsens(history, cues, name, amount, ld) -> None:
    w = worse(cues, name, amount)
    assume(w is not None)
    t_next = history[-1][0] + 0.1
    limits = []
    for last in (cues, w):
        frames = [*history, (t_next, 1.0, last, 0.0, ld)]
        limits.append(run(frames)[-1].speed_limit_mps)
    assert limits[1] <= limits[0] + 1e-12


# 4. unknown = worst; nothing fired = 1 ---------------------------------------------------------
@given(valid_cues, st.sampled_from(CUE_NAMES), st.sampled_from([math.nan, -1.0, -math.inf, 1e9, "bad"]), st.booleans())
def test_4_unknown_cue_gives_exactly_the_worst_fear(cues, name, bad, asymmetric) -> None:
    rules = ASYMMETRIC if asymmetric else RULES
    spec_worst = {"lane_confidence": [0.0], "brightness": [0.0, 255.0], "occlusion": [1.0],
                  "obstacle_range_m": [0.0], "qr_staleness_s": [math.inf]}[name]
    if name in ("obstacle_range_m", "qr_staleness_s") and bad == 1e9:
        bad = math.nan  # 1e9 m or s is a valid (far, stale) reading for the open-ended cues
    base = {n: getattr(cues, n) for n in CUE_NAMES}
    unknown = rules.evaluate(fg.Cues(**{**base, name: bad})).fear
    expected = max(rules.evaluate(fg.Cues(**{**base, name: w})).fear for w in spec_worst)
    assert unknown == expected
    row = np.array([fg.Cues(**{**base, name: bad}).as_array()])
    worst_rows = np.array([fg.Cues(**{**base, name: w}).as_array() for w in spec_worst])
    # the vector path sums in BLAS order, which may differ from the scalar path's in the last bit
    assert abs(rules.evaluate_batch(row)[0] - rules.evaluate_batch(worst_rows).max()) <= 1e-12




def test_4_no_rule_firing_gives_fear_1_plain(write_rules) -> None:
    rb = fg.load_rules(write_rules(('  "IF qr_staleness_s IS stale THEN fear IS high",\n', "")))
    res = rb.evaluate(fg.Cues(0.9, 120.0, 0.0, 3.0, 20.0))  # only 'stale' is non-zero here: no rule fires
    assert res.fear == 1.0 and res.group_fears["localisation"] == 1.0 and res.level is fg.FearLevel.VERY_HIGH
    assert rb.reference_fear(fg.Cues(0.9, 120.0, 0.0, 3.0, 20.0)) == 1.0


# 5. no chattering ------------------------------------------------------------------------------
fear_cues = st.sampled_from([fg.Cues(0.9, 120.0, 0.0, math.inf, 0.5),   # very low
                             fg.Cues(0.45, 120.0, 0.2, math.inf, 0.5),  # medium-ish
                             fg.Cues(0.1, 120.0, 0.9, math.inf, 0.5)])  # very high, not a collision


@given(st.lists(st.tuples(st.floats(0.02, 0.6), fear_cues), min_size=1, max_size=60))
def test_5_emergency_needs_enter_frames_and_holds_hold_s(steps) -> None:
    frames, t = [], 0.0
    for dt, cues in steps:
        t += dt
        frames.append((t, 0.0, cues, 0.0, None))
    cmds = run(frames)
    fears = [c.fear for c in cmds]
    entered_at = None
    for i, cmd in enumerate(cmds):
        was = cmds[i - 1].mode if i else fg.Mode.NORMAL
        if cmd.mode is fg.Mode.EMERGENCY and was is not fg.Mode.EMERGENCY:
            assert i + 1 >= CFG.enter_frames
            assert all(f >= CFG.emergency_enter_fear for f in fears[i + 1 - CFG.enter_frames : i + 1])
            entered_at = frames[i][0]
        if was is fg.Mode.EMERGENCY and cmd.mode is not fg.Mode.EMERGENCY:
            assert frames[i][0] - entered_at >= CFG.hold_s
            k = i  # start of the run of frames below the exit threshold that ends here
            while k > 0 and fears[k - 1] < CFG.emergency_exit_fear:
                k -= 1
            assert fears[i] < CFG.emergency_exit_fear and frames[i][0] - frames[k][0] >= CFG.hold_s


@given(st.floats(0.05, 0.6), st.floats(0.5, 2.0))
def test_5_imminent_collision_enters_at_once(range_m, speed) -> None:
    cmd = run([(0.0, speed, fg.Cues(0.9, 120.0, 0.0, range_m, 0.5), 0.0, None)])[0]
    if fg.policy.imminent_collision(range_m, speed, VEHICLE):
        assert cmd.mode is fg.Mode.EMERGENCY and cmd.strategy is fg.Strategy.STOP


# 6. falls at once, rises at comfort acceleration ------------------------------------------------
@given(drives(cues=valid_cues))
def test_6_speed_limit_rate(frames) -> None:
    cmds = run(frames)
    for i in range(1, len(cmds)):
        dt = frames[i][0] - frames[i - 1][0]
        rise = cmds[i].speed_limit_mps - cmds[i - 1].speed_limit_mps
        if dt > 0:
            assert rise <= CFG.comfort_accel_mps2 * dt + 1e-9
        if cmds[i].mode is not fg.Mode.EMERGENCY:  # falls at once: never above what fear and envelope allow
            assert cmds[i].speed_limit_mps <= min(cmds[i].fear_limit_mps, cmds[i].envelope_mps) + 1e-12


# 7. pass-through -------------------------------------------------------------------------------
@given(drives(cues=calm_or_valid), st.floats(-30.0, 30.0))
def test_7_steering_passes_unchanged_at_very_low_fear_in_normal(frames, angle) -> None:
    frames = [(t, v, c, angle, ld) for t, v, c, _, ld in frames]
    for cmd in run(frames):
        if cmd.mode is fg.Mode.NORMAL and cmd.fear_level is fg.FearLevel.VERY_LOW:
            assert cmd.steering_deg == angle and cmd.strategy is fg.Strategy.PASS_THROUGH


def test_7_calm_frames_do_reach_normal_very_low() -> None:
    cmds = run([(0.1 * k, 1.0, fg.Cues(0.9, 120.0, 0.0, math.inf, 0.5), 7.25, None) for k in range(5)])
    assert all(c.mode is fg.Mode.NORMAL and c.fear_level is fg.FearLevel.VERY_LOW and c.steering_deg == 7.25 for c in cmds)


# 8. deterministic ------------------------------------------------------------------------------
@given(drives())
def test_8_same_inputs_same_outputs(frames) -> None:
    a, b = run(frames), run(frames)
    assert [(c.steering_deg, c.speed_limit_mps, c.mode, c.strategy, c.fear, c.reasons) for c in a] == \
           [(c.steering_deg, c.speed_limit_mps, c.mode, c.strategy, c.fear, c.reasons) for c in b]
