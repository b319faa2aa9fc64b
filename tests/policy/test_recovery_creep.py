"""Recovery (analyse, then act): dwell at standstill, bounded creeps, then stay stopped and say why."""

from __future__ import annotations

from hypothesis import given
from hypothesis import strategies as st

from fearguard.policy import PolicyConfig, Recovery, next_recovery, recovery_exhausted, recovery_status

CFG = PolicyConfig()


def drive(frames):
    """frames: (dt, eligible, speed). Returns the per-frame (recovery, creeping) and the distances crept."""
    rec, t, out = Recovery(), 0.0, []
    for dt, eligible, speed in frames:
        t += dt
        rec, why = next_recovery(rec, eligible, t, dt, speed, CFG)
        out.append((rec, bool(why), t, dt, speed, eligible))
    return out


def test_dwell_then_creep_then_exhausted() -> None:
    states = drive([(0.1, True, 0.0)] * 11)
    assert not any(c for _, c, *_ in states[:10]) and states[10][1]  # creep 1 after 1.0 s at standstill
    rec, t = states[-1][0], states[-1][2]
    creeps = 1
    for _ in range(400):  # creeping at 0.3 m/s, stopping between creeps
        t += 0.1
        speed = 0.3 if rec.creep_since_s is not None else 0.0
        before = rec.creeps
        rec, _ = next_recovery(rec, True, t, 0.1, speed, CFG)
        creeps += rec.creeps - before
    assert rec.creeps == CFG.recovery_max_creeps and recovery_exhausted(rec, CFG)
    assert rec.total_m <= CFG.recovery_max_total_m + 0.3 * 0.1 + 1e-9
    assert "staying stopped" in recovery_status(rec, True, CFG, t)


def test_not_eligible_never_creeps_and_ends_a_creep() -> None:
    rec, why = next_recovery(Recovery(creeps=1, creep_since_s=0.0), False, 0.5, 0.1, 0.3, CFG)
    assert not why and rec.creep_since_s is None and rec.creeps == 1
    assert recovery_status(rec, False, CFG, 0.5) == ""


def test_moving_car_does_not_dwell() -> None:
    states = drive([(0.1, True, 0.5)] * 40)
    assert not any(c for _, c, *_ in states)
    assert "waiting for standstill" in recovery_status(states[-1][0], True, CFG, 4.0)


steps = st.lists(st.tuples(st.floats(0.01, 0.5), st.booleans(), st.floats(0.0, 1.0)), max_size=200)


@given(steps)
def test_property_every_creep_is_bounded_and_only_when_eligible(frames) -> None:
    states = drive(frames)
    crept_total, creep_m, creep_t, starts = 0.0, 0.0, 0.0, 0
    for rec, creeping, _t, dt, speed, eligible in states:
        if creeping:
            assert eligible  # never with an obstacle in range, never after a fault (the caller's eligibility)
            starts += rec.creep_m == 0.0
            creep_m += speed * dt if rec.creep_m else 0.0
            creep_t += dt if rec.creep_m else 0.0
            crept_total += speed * dt if rec.creep_m else 0.0
            assert rec.creep_m <= CFG.recovery_creep_m + 1.0 * 0.5  # at most one frame beyond the bound
        assert rec.creeps <= CFG.recovery_max_creeps
        assert rec.total_m <= CFG.recovery_max_total_m + 1.0 * 0.5
    assert starts <= CFG.recovery_max_creeps


@given(speed=st.floats(0.05, 2.0), dt=st.floats(0.02, 0.2), seen_every=st.integers(0, 5))
def test_blind_metres_never_pass_the_blind_budget_by_more_than_a_frame(speed: float, dt: float, seen_every: int) -> None:
    """Issue 35: a creep may run with nothing of the lane in sight, but its blind metres per EMERGENCY are bounded apart
    (steering blind leaves a curve within metres); metres crept with the lane in sight do not count."""
    rec, t = Recovery(), 0.0
    for k in range(3000):
        t += dt
        blind = seen_every == 0 or k % seen_every != 0
        moving = speed if rec.creep_since_s is not None else 0.0
        rec, _ = next_recovery(rec, True, t, dt, moving, CFG, blind=blind)
        assert rec.blind_m <= CFG.recovery_blind_m + speed * dt + 1e-9
        assert rec.blind_m <= rec.total_m + 1e-9
    if seen_every == 0:  # always blind: it ends, standing, and says why
        assert rec.creep_since_s is None and rec.blind_m >= CFG.recovery_blind_m
        assert "nothing of the lane in sight" in recovery_status(rec, True, CFG, t, blind=True)
