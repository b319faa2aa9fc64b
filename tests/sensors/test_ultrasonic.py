"""Ultrasonic range filter: conversion, rejection rules, spike confirmation, dropouts, Kalman closing speed and TTC."""

from __future__ import annotations

import copy
import math

import pytest
from hypothesis import assume, given
from hypothesis import strategies as st

from fearguard.sensors.ultrasonic import (
    CONFIRM_CLOSER,
    CONFIRM_FARTHER,
    DROPOUT_HOLD_S,
    GATE_SIGMA,
    HC_SR04_MAX_RANGE_M,
    HC_SR04_MIN_RANGE_M,
    MEASUREMENT_STD_M,
    MIN_GATE_M,
    RangeEstimate,
    ReadingKind,
    UltrasonicFilter,
    classify_reading,
    echo_to_range_m,
    time_to_collision_s,
)

INCH_M = 0.0254  # [m]
DT_S = 0.1  # [s] 10 readings per second in the example tests


def tracked(range_m: float = 2.0, frames: int = 5, dt_s: float = DT_S, **kwargs: float) -> tuple[UltrasonicFilter, float]:
    """A filter that has seen ``frames`` steady readings at ``range_m``; returns it and the time of the next frame."""
    f = UltrasonicFilter(**kwargs)
    for k in range(frames):
        f.update(k * dt_s, range_m)
    return f, frames * dt_s


def feed(f: UltrasonicFilter, t0_s: float, values: list[object], dt_s: float = DT_S) -> list[RangeEstimate]:
    return [f.update(t0_s + k * dt_s, v) for k, v in enumerate(values)]


# -- limits and pure helpers ----------------------------------------------------------------
def test_limits_are_the_hc_sr04_literature_values_and_sane() -> None:
    assert HC_SR04_MIN_RANGE_M == pytest.approx(6 * INCH_M, abs=0.005)
    assert HC_SR04_MAX_RANGE_M == pytest.approx(156 * INCH_M, abs=0.005)
    assert 0 < HC_SR04_MIN_RANGE_M < HC_SR04_MAX_RANGE_M
    assert 0 < DROPOUT_HOLD_S <= 0.5  # bridging longer than half a second would hide a dead sensor
    assert CONFIRM_CLOSER <= CONFIRM_FARTHER  # believing danger is never slower than believing it is gone


@pytest.mark.parametrize(("echo_s", "range_m"), [(1e-3, 0.1715), (0.01, 1.715), (0.02, 3.43), (math.inf, math.inf)])
def test_echo_to_range_is_17150_cm_per_second(echo_s: float, range_m: float) -> None:
    assert echo_to_range_m(echo_s) == pytest.approx(range_m)


@pytest.mark.parametrize("echo_s", [0.0, -1e-3, math.nan, -math.inf, None, "0.01", True, [0.01], b"\x01"])
def test_echo_to_range_is_none_for_impossible_or_non_numbers(echo_s: object) -> None:
    assert echo_to_range_m(echo_s) is None


@pytest.mark.parametrize(
    ("value", "kind", "reason"),
    [
        (None, ReadingKind.NONE, "no reading"),
        (0.0, ReadingKind.INVALID, "not a positive distance"),
        (-0.5, ReadingKind.INVALID, "not a positive distance"),
        (math.nan, ReadingKind.INVALID, "NaN"),
        ("1.0", ReadingKind.INVALID, "not a number"),
        (True, ReadingKind.INVALID, "not a number"),
        (0.10, ReadingKind.INVALID, "below the minimum range 0.15 m"),
        (HC_SR04_MAX_RANGE_M, ReadingKind.CLEAR, "nothing in range"),
        (math.inf, ReadingKind.CLEAR, "nothing in range"),
        (HC_SR04_MIN_RANGE_M, ReadingKind.RANGE, ""),
        (1.5, ReadingKind.RANGE, ""),
    ],
)
def test_classify_reading(value: object, kind: ReadingKind, reason: str) -> None:
    reading = classify_reading(value)
    assert reading.kind is kind
    assert reason in reading.reason


@pytest.mark.parametrize(
    ("range_m", "closing_mps", "ttc_s"),
    [(2.0, 1.0, 2.0), (1.0, 0.5, 2.0), (2.0, 0.0, math.inf), (2.0, -1.0, math.inf), (math.inf, 1.0, math.inf)],
)
def test_time_to_collision(range_m: float, closing_mps: float, ttc_s: float) -> None:
    assert time_to_collision_s(range_m, closing_mps) == ttc_s


def test_time_to_collision_unknown_when_an_input_is_unknown() -> None:
    assert math.isnan(time_to_collision_s(math.nan, 1.0)) and math.isnan(time_to_collision_s(1.0, math.nan))


@pytest.mark.parametrize(
    "kwargs",
    [{"min_range_m": 0.0}, {"min_range_m": 2.0, "max_range_m": 1.0}, {"max_range_m": math.inf}, {"dropout_hold_s": 0.0},
     {"measurement_std_m": math.nan}, {"confirm_closer": 0}, {"confirm_farther": 4}],
)
def test_bad_settings_raise_value_error(kwargs: dict) -> None:
    with pytest.raises(ValueError):
        UltrasonicFilter(**kwargs)


# -- start-up, acceptance, nothing in range ------------------------------------------------
def test_first_range_starts_the_track_at_once() -> None:
    first = UltrasonicFilter().update(0.0, 1.2)  # believing an obstacle is the safe side
    assert first.accepted and first.range_m == 1.2 and "track started" in first.reason


def test_very_first_nothing_in_range_is_believed_so_a_car_can_start_on_an_empty_road() -> None:
    first = UltrasonicFilter().update(0.0, math.inf)
    assert first.accepted and math.isinf(first.range_m)


def test_nothing_in_range_after_a_silence_needs_a_second_agreeing_reading() -> None:
    f = UltrasonicFilter()
    feed(f, 0.0, [1.0])
    silent = [f.update(0.1 + k * DT_S, None) for k in range(int(2.0 / DT_S))]  # > memory: the track is forgotten
    assert math.isnan(silent[-1].range_m)
    t = 0.1 + len(silent) * DT_S
    first, second = f.update(t, math.inf), f.update(t + DT_S, 4.5)  # a lost echo alone must not declare the road clear
    assert math.isnan(first.range_m) and not first.accepted and "not yet confirmed" in first.reason
    assert second.accepted and math.isinf(second.range_m)


def test_readings_at_or_beyond_max_range_or_inf_mean_nothing_in_range() -> None:
    f = UltrasonicFilter()
    estimates = feed(f, 0.0, [math.inf, 5.0, HC_SR04_MAX_RANGE_M, math.inf])
    last = estimates[-1]
    assert (last.range_m, last.closing_speed_mps, last.ttc_s, last.accepted) == (math.inf, 0.0, math.inf, True)
    assert estimates[1].raw_m == 5.0  # the raw value is kept as given


def test_echo_input_gives_exactly_the_same_estimates_as_the_converted_range() -> None:
    echoes = [0.0117, 0.0116, 0.0, 0.0114, None, 0.0040, 0.0039, 0.03, math.nan, 0.0037]
    by_echo, by_range = UltrasonicFilter(), UltrasonicFilter()
    for k, echo in enumerate(echoes):
        e = by_echo.update(k * DT_S, echo_s=echo)
        converted = echo_to_range_m(echo)
        r = by_range.update(k * DT_S, range_m=converted if converted is not None else (None if echo is None else math.nan))
        assert (e.range_m, e.closing_speed_mps, e.accepted) == pytest.approx((r.range_m, r.closing_speed_mps, r.accepted), nan_ok=True)


def test_range_m_wins_over_echo_s_when_both_are_given() -> None:
    f = UltrasonicFilter()
    est = feed(f, 0.0, [1.0, 1.0])[-1]
    assert f.update(0.2, range_m=1.0, echo_s=0.02).raw_m == 1.0 and est.accepted


# -- rejections -------------------------------------------------------------------------------
@pytest.mark.parametrize(
    ("bad", "reason"),
    [
        (0.0, "reading 0 m is not a positive distance"),
        (-1.0, "reading -1 m is not a positive distance"),
        (math.nan, "reading is NaN"),
        ("far", "reading 'far' is not a number"),
        ([1.0], "reading [1.0] is not a number"),
        (True, "reading True is not a number"),
        (0.05, "reading 0.050 m is below the minimum range 0.15 m"),
    ],
)
def test_impossible_readings_are_rejected_with_the_reason_and_bridged(bad: object, reason: str) -> None:
    f, t = tracked(1.5)
    est = f.update(t, bad)
    assert not est.accepted
    assert reason in est.reason and "predicted over a 0.10 s gap" in est.reason
    assert est.range_m == pytest.approx(1.5, abs=0.01)


def test_bad_echo_is_rejected_with_the_reason() -> None:
    f, t = tracked(1.5)
    est = f.update(t, echo_s=-0.001)
    assert not est.accepted and "echo -0.001 s is not a positive number" in est.reason


def test_lone_far_spike_is_dropped() -> None:
    f, t = tracked(1.0)
    spike, after = feed(f, t, [3.0, 1.0])
    assert not spike.accepted and "far from the track" in spike.reason
    assert spike.range_m == pytest.approx(1.0, abs=0.01)
    assert after.accepted and after.range_m == pytest.approx(1.0, abs=0.01)


def test_lone_lost_echo_does_not_clear_an_obstacle_but_three_do() -> None:
    f, t = tracked(1.0)
    flicker = feed(f, t, [math.inf, 1.0, math.inf, 1.0])
    assert all(math.isfinite(e.range_m) for e in flicker)
    cleared = feed(f, t + 4 * DT_S, [math.inf] * CONFIRM_FARTHER)
    assert [math.isinf(e.range_m) for e in cleared] == [False] * (CONFIRM_FARTHER - 1) + [True]
    assert "farther reading confirmed" in cleared[-1].reason


def test_closer_spike_waits_one_frame_then_two_agreeing_readings_reinitialise_the_track() -> None:
    f, t = tracked(2.0)
    spike, confirm = feed(f, t, [0.60, 0.55])
    assert not spike.accepted and "1.40 m closer than the track" in spike.reason
    assert spike.range_m == pytest.approx(2.0, abs=0.01)
    assert confirm.accepted and confirm.range_m == pytest.approx(0.55)
    assert "closer obstacle confirmed" in confirm.reason and "2 of the last 3 readings agree" in confirm.reason
    assert confirm.closing_speed_mps == pytest.approx(0.5)  # from the two agreeing readings: 5 cm in 0.1 s


@pytest.mark.parametrize("dt_s", [0.05, 0.1, 0.2, 0.25])
def test_readings_on_the_track_never_confirm_a_spike_whatever_the_rate(dt_s: float) -> None:
    f, t = tracked(2.0, frames=20, dt_s=dt_s)
    spike = f.update(t, 1.5)  # within "agreement" of the previous track readings once widened by 3 m/s × Δt
    assert not spike.accepted and spike.range_m == pytest.approx(2.0, abs=0.01)


def test_two_of_the_last_three_confirm_even_with_a_reading_in_between() -> None:
    f, t = tracked(2.0)
    first, between, second = feed(f, t, [0.5, 2.0, 0.5])
    assert not first.accepted and between.accepted
    assert second.accepted and second.range_m == pytest.approx(0.5)


def test_closer_reading_after_nothing_in_range_is_confirmed_by_the_next() -> None:
    f = UltrasonicFilter()
    feed(f, 0.0, [math.inf, math.inf])
    appear, confirm = feed(f, 0.2, [1.0, 0.98])
    assert math.isinf(appear.range_m) and "closer candidate" in appear.reason
    assert confirm.range_m == pytest.approx(0.98)


def test_small_steps_inside_the_gate_are_smoothed_not_jumped() -> None:
    f, t = tracked(2.0, frames=20)
    est = f.update(t, 2.0 + MIN_GATE_M * 0.8)
    assert est.accepted and 2.0 < est.range_m < 2.0 + MIN_GATE_M * 0.8


# -- dropouts and time ----------------------------------------------------------------------
def test_short_dropout_is_bridged_by_the_prediction() -> None:
    f, t = tracked(1.0)
    gap = feed(f, t, [None, None, None])
    assert all(math.isfinite(e.range_m) and not e.accepted for e in gap)
    assert "no reading; predicted over a 0.30 s gap" in gap[-1].reason


def test_long_dropout_gives_unknown_with_the_gap_in_the_reason() -> None:
    f = UltrasonicFilter()
    feed(f, 0.0, [1.0, 1.0])
    est = f.update(0.62, None)
    assert math.isnan(est.range_m) and math.isnan(est.closing_speed_mps) and math.isnan(est.ttc_s)
    assert est.reason == "ultrasonic: no valid reading for 0.52 s (no reading): range unknown"


def test_only_rejected_readings_for_too_long_give_unknown() -> None:
    f, t = tracked(1.0)
    estimates = feed(f, t, [0.0, 3.5, math.nan, 0.02])
    assert all(math.isfinite(e.range_m) for e in estimates[:3])
    assert math.isnan(estimates[3].range_m) and "no valid reading for 0.40 s" in estimates[3].reason


def test_after_a_lost_track_nothing_in_range_must_be_confirmed_again() -> None:
    f, t = tracked(1.0)
    assert math.isnan(f.update(t + 1.0, None).range_m)
    first, second = feed(f, t + 1.1, [math.inf, math.inf])
    assert math.isnan(first.range_m) and "no valid reading for 1.20 s" in first.reason
    assert math.isinf(second.range_m)


def test_a_reading_after_a_long_silence_is_not_gated_against_the_stale_track() -> None:
    f, t = tracked(1.0)  # no call at all for a second, then a reading far from the old track
    est = f.update(t + 1.0, 3.0)
    assert est.accepted and est.range_m == 3.0 and "track started" in est.reason


def test_after_the_hold_the_range_is_unknown_but_the_track_still_gates_new_readings() -> None:
    f, t = tracked(1.0)  # last reading at 0.4 s
    gap = feed(f, t, [None, None, None, None])  # 0.5 … 0.8 s
    assert math.isnan(gap[-1].range_m) and "no valid reading for 0.40 s" in gap[-1].reason
    far, back = feed(f, t + 0.4, [3.0, 1.0])
    assert math.isnan(far.range_m) and "far from the track" in far.reason  # a far spike is still dropped
    assert back.accepted and back.range_m == pytest.approx(1.0, abs=0.02) and "accepted (innovation" in back.reason


def test_prediction_never_moves_a_receding_obstacle_beyond_its_last_reading() -> None:
    f = UltrasonicFilter()
    feed(f, 0.0, [1.0, 1.1, 1.2, 1.3, 1.4])  # receding at 1 m/s
    bridged = feed(f, 0.5, [None, None])
    assert all(e.range_m <= 1.4 for e in bridged)


def test_approaching_obstacle_prediction_comes_closer_during_a_gap() -> None:
    f = UltrasonicFilter()
    feed(f, 0.0, [2.0, 1.9, 1.8, 1.7, 1.6])
    bridged = feed(f, 0.5, [None, None])
    assert bridged[0].range_m < 1.6 and bridged[1].range_m < bridged[0].range_m


@pytest.mark.parametrize(("t_s", "reason"), [(0.1, "time did not increase"), (0.4, "time did not increase"),
                                             (math.nan, "is not a finite number"), ("soon", "is not a finite number"),
                                             (math.inf, "is not a finite number")])
def test_bad_time_gives_unknown_for_that_call_and_the_next_frame_is_read_again(t_s: object, reason: str) -> None:
    f, t = tracked(1.0)  # last frame at 0.4 s
    est = f.update(t_s, 1.0)
    assert math.isnan(est.range_m) and reason in est.reason
    after = f.update(t, 1.0)
    assert after.accepted and after.range_m == pytest.approx(1.0, abs=0.01)


def test_reset_forgets_the_track_and_the_clock() -> None:
    f, _ = tracked(1.0)
    f.reset()
    est = f.update(0.0, 3.0)  # time may start again; 3.0 m would be a far spike for the old track
    assert est.accepted and est.range_m == 3.0


def test_an_internal_error_gives_unknown_and_resets(monkeypatch: pytest.MonkeyPatch) -> None:
    f, t = tracked(1.0)
    monkeypatch.setattr(f, "_predict", lambda t_s: 1 / 0)
    est = f.update(t, 1.0)
    assert math.isnan(est.range_m) and "internal error ZeroDivisionError" in est.reason and "filter reset" in est.reason
    monkeypatch.undo()
    assert f.update(0.0, 2.0).range_m == 2.0  # a fresh start: the clock was reset too


# -- Kalman estimate: closing speed and TTC --------------------------------------------------
def test_constant_approach_gives_the_closing_speed_and_ttc() -> None:
    f = UltrasonicFilter()
    speed_mps, est = 0.5, None
    for k in range(31):  # 3.5 m → 2.0 m in 3 s
        est = f.update(k * DT_S, 3.5 - speed_mps * k * DT_S)
    assert est.closing_speed_mps == pytest.approx(speed_mps, abs=0.02)
    assert est.range_m == pytest.approx(2.0, abs=0.01)
    assert est.ttc_s == pytest.approx(2.0 / speed_mps, rel=0.05)


def test_obstacle_entering_the_blind_zone_is_held_at_the_minimum_then_unknown() -> None:
    f = UltrasonicFilter()
    estimates = [f.update(k * DT_S, 1.0 - 0.1 * k) for k in range(9)]  # 1.0 m → 0.2 m at 1 m/s
    blind = [f.update((9 + k) * DT_S, 0.1 - 0.01 * k) for k in range(4)]  # below 0.15 m: rejected readings
    assert estimates[-1].accepted and estimates[-1].closing_speed_mps == pytest.approx(1.0, abs=0.05)
    assert [e.range_m for e in blind[:3]] == pytest.approx([HC_SR04_MIN_RANGE_M] * 3)  # predicted closer, shown at the minimum
    assert all(e.ttc_s < 0.3 for e in blind[:3])
    assert math.isnan(blind[3].range_m)  # then unknown, which the supervisor counts as 0 m


# -- properties -------------------------------------------------------------------------------
garbage = st.one_of(
    st.none(), st.floats(), st.floats(0.0, 5.0), st.integers(-10, 10), st.booleans(), st.text(max_size=5),
    st.lists(st.floats(), max_size=2), st.just(10**400), st.just(b"\x00"),
)
times = st.one_of(st.floats(-0.05, 0.6), st.just(math.nan), st.just(math.inf), st.text(max_size=2))


@given(steps=st.lists(st.tuples(times, garbage, garbage), max_size=40))
def test_never_raises_and_range_is_nan_inf_or_within_limits(steps: list[tuple[object, object, object]]) -> None:
    f, clock = UltrasonicFilter(), 0.0
    for dt, value, echo in steps:
        if isinstance(dt, float) and math.isfinite(dt):
            clock += dt  # may step backwards: dt can be negative
            t: object = clock
        else:
            t = dt  # garbage times (NaN, inf, text) are passed as they are
        est = f.update(t, value, echo)  # type: ignore[arg-type]
        assert isinstance(est, RangeEstimate) and est.reason.startswith("ultrasonic: ")
        r = est.range_m
        assert math.isnan(r) or (math.isinf(r) and r > 0) or HC_SR04_MIN_RANGE_M <= r <= HC_SR04_MAX_RANGE_M
        assert math.isnan(est.closing_speed_mps) == math.isnan(r)
        if not math.isnan(r):
            assert est.ttc_s == time_to_collision_s(r, est.closing_speed_mps)


valid = st.one_of(st.floats(0.16, 4.5), st.just(math.inf))
anything = st.one_of(st.none(), st.floats(allow_nan=True), st.floats(0.16, 4.5))


@given(history=st.lists(st.tuples(st.floats(0.01, 0.25), anything), max_size=20), hold=st.floats(0.05, 1.0),
       gap=st.floats(0.0, 2.0), rejected=st.booleans())
def test_a_gap_longer_than_the_hold_always_ends_in_unknown(
    history: list[tuple[float, object]], hold: float, gap: float, rejected: bool
) -> None:
    f, t = UltrasonicFilter(dropout_hold_s=hold), 0.0
    for dt, value in history:
        t += dt
        f.update(t, value)
    step = 0.05
    for k in range(1, int((hold + gap) / step) + 3):  # no valid reading (None, or only impossible ones) for > hold
        est = f.update(t + k * step, 0.0 if rejected else None)
    assert math.isnan(est.range_m) and "range unknown" in est.reason


@given(history=st.lists(st.tuples(st.floats(0.01, 0.25), valid), max_size=10), target=st.floats(0.16, 3.9),
       dt=st.floats(0.03, 0.25))
def test_a_steady_reading_converges_to_it(history: list[tuple[float, float]], target: float, dt: float) -> None:
    f, t = UltrasonicFilter(), 0.0
    for step, value in history:
        t += step
        f.update(t, value)
    for _ in range(60):
        t += dt
        est = f.update(t, target)
    assert est.accepted and est.range_m == pytest.approx(target, abs=0.005)
    assert abs(est.closing_speed_mps) < 0.02


@given(start=st.floats(1.0, 3.9), speed=st.floats(0.1, 2.0), dt=st.floats(0.04, 0.25), frames=st.integers(3, 40))
def test_an_approaching_obstacle_gives_positive_closing_speed_and_finite_ttc(start: float, speed: float, dt: float, frames: int) -> None:
    assume(start - speed * dt * (frames - 1) >= 0.3)
    f = UltrasonicFilter()
    for k in range(frames):
        est = f.update(k * dt, start - speed * dt * k)
    assert est.closing_speed_mps > 0 and math.isfinite(est.ttc_s)


@given(track=st.floats(1.0, 3.9), frames=st.integers(8, 30), jump=st.floats(0.4, 3.0), wobble=st.floats(-0.1, 0.1),
       dt=st.floats(0.04, 0.25))
def test_a_single_closer_spike_waits_and_two_agreeing_readings_are_accepted(
    track: float, frames: int, jump: float, wobble: float, dt: float
) -> None:
    spike_m = track - jump
    f = UltrasonicFilter()
    assume(spike_m >= 0.2 and spike_m + wobble >= f.min_range_m)  # the confirming reading is a valid one (0.125 m is not)
    for k in range(frames):
        f.update(k * dt, track)
    gate_m = copy.deepcopy(f).update(frames * dt, None).gate_m  # the gate the spike will meet
    assume(gate_m < jump)  # the spike really lies outside the gate
    spike = f.update(frames * dt, spike_m)
    assert not spike.accepted and spike.range_m > spike_m + 0.1
    confirm = f.update((frames + 1) * dt, spike_m + wobble)
    assert confirm.accepted
    # re-initialised there, or (the gate having widened while bridging) taken through the filter, which leaves at most
    # (1 − K)·|innovation| ≤ R/S · GATE_SIGMA·√S ≤ GATE_SIGMA·√R between estimate and reading
    assert abs(confirm.range_m - (spike_m + wobble)) <= GATE_SIGMA * MEASUREMENT_STD_M + 1e-9


@given(steps=st.lists(st.tuples(st.floats(0.01, 0.2), anything), min_size=1, max_size=60))
def test_the_filtered_range_never_hides_an_obstacle_beyond_the_gate(steps: list[tuple[float, object]]) -> None:
    """Output ≤ last accepted reading (+ the gate on the frame it was accepted through the filter)."""
    f, t, last_accepted = UltrasonicFilter(), 0.0, math.nan
    for dt, value in steps:
        t += dt
        est = f.update(t, value)
        if est.accepted:
            last_accepted = math.inf if est.raw_m >= HC_SR04_MAX_RANGE_M else est.raw_m
        if math.isfinite(est.range_m):
            slack = est.gate_m if est.accepted and math.isfinite(est.gate_m) else 0.0
            assert est.range_m <= last_accepted + slack + 1e-9
