"""QR track markers and the qr_staleness_s cue: payload format, fixes, rejections, time and odometer faults."""

from __future__ import annotations

import math

import pytest
from hypothesis import assume, example, given
from hypothesis import strategies as st

from fearguard.sensors.localisation import (
    MARKER_SPACING_M,
    POSITION_TOLERANCE_M,
    LocalisationState,
    QrLocaliser,
    TrackMarker,
    fix_tolerance_m,
    format_marker,
    parse_marker,
    plausible_fix,
    staleness_s,
)

M12 = "FG1;route=campus;sector=3;pos_m=12.5"
M17 = "FG1;route=campus;sector=4;pos_m=17.5"
M80 = "FG1;route=campus;sector=16;pos_m=80.0"


def marker(pos_m: float, sector: int = 0, route: str = "campus") -> str:
    return format_marker(route, sector, pos_m)


# -- payload format ----------------------------------------------------------------------------------------
def test_the_documented_example_parses() -> None:
    assert parse_marker(M12) == TrackMarker("campus", 3, 12.5)


@pytest.mark.parametrize(
    ("payload", "expected"),
    [
        ("FG1;pos_m=0;sector=0;route=a-b_C9", TrackMarker("a-b_C9", 0, 0.0)),  # any key order
        ("FG1;route=campus;sector=3;pos_m=12.5;lane=2;note=x y", TrackMarker("campus", 3, 12.5)),  # extra keys ignored
        (" FG1; route = campus ;sector=3;pos_m=12.5;\n", TrackMarker("campus", 3, 12.5)),  # spaces, trailing ; and newline
        ("FG1;route=r;sector=007;pos_m=1234.125", TrackMarker("r", 7, 1234.125)),
    ],
)
def test_valid_payloads(payload: str, expected: TrackMarker) -> None:
    assert parse_marker(payload) == expected


@pytest.mark.parametrize(
    ("payload", "why"),
    [
        ("xyz", "not a track marker"),
        ("", "not a track marker"),
        ("fg1;route=campus;sector=3;pos_m=12.5", "not a track marker"),  # the prefix is case-sensitive
        ("http://example.com/FG1", "not a track marker"),
        ("FG2;route=campus;sector=3;pos_m=12.5", "unsupported marker version 'FG2'"),
        ("FG1", "missing key 'route'"),
        ("FG1;route=campus;sector=3", "missing key 'pos_m'"),
        ("FG1;route=campus;pos_m=1", "missing key 'sector'"),
        ("FG1;route;sector=3;pos_m=1", "malformed field 'route'"),
        ("FG1;=x;route=a;sector=3;pos_m=1", "malformed field"),
        ("FG1;route=a;route=b;sector=3;pos_m=1", "key 'route' given twice"),
        ("FG1;route=cam pus;sector=3;pos_m=1", "route 'cam pus'"),
        ("FG1;route=;sector=3;pos_m=1", "route ''"),
        ("FG1;route=a;sector=-1;pos_m=1", "sector '-1' is not an integer ≥ 0"),
        ("FG1;route=a;sector=3.0;pos_m=1", "sector '3.0'"),
        ("FG1;route=a;sector=3;pos_m=-1", "pos_m '-1' is not a decimal number ≥ 0"),
        ("FG1;route=a;sector=3;pos_m=1e3", "pos_m '1e3'"),
        ("FG1;route=a;sector=3;pos_m=nan", "pos_m 'nan'"),
        ("FG1;route=a;sector=3;pos_m=inf", "pos_m 'inf'"),
        ("FG1;route=a;sector=3;pos_m=12.", "pos_m '12.'"),
        ("FG1;route=a;sector=3;pos_m=" + "9" * 20, "pos_m"),
        ("FG1;route=a;sector=3;pos_m=1;" + "x" * 600, "longer than 512 characters"),
    ],
)
def test_invalid_payloads_say_why(payload: str, why: str) -> None:
    got = parse_marker(payload)
    assert isinstance(got, str) and why in got


@pytest.mark.parametrize("payload", [None, 5, 1.5, b"FG1;route=a;sector=3;pos_m=1", ["FG1"]])
def test_non_text_is_not_a_marker(payload) -> None:
    assert parse_marker(payload).startswith("not text")


def test_format_marker_makes_the_documented_example() -> None:
    assert format_marker("campus", 3, 12.5) == M12
    assert format_marker("campus", 3, 12.5, decimals=2) == "FG1;route=campus;sector=3;pos_m=12.50"
    assert format_marker("campus", 3, 12, decimals=0) == "FG1;route=campus;sector=3;pos_m=12"


def test_the_simulator_prints_payloads_this_reader_parses() -> None:
    from fearguard.sim.qr import payload

    assert payload("campus", 3, 12.5) == format_marker("campus", 3, 12.5)
    assert parse_marker(payload("loop_2", 0, 0.0)) == TrackMarker("loop_2", 0, 0.0)


@pytest.mark.parametrize(
    ("route", "sector", "pos_m", "decimals"),
    [("a;b", 1, 1.0, 1), ("", 1, 1.0, 1), ("x=y", 1, 1.0, 1), (None, 1, 1.0, 1), ("a", -1, 1.0, 1), ("a", True, 1.0, 1),
     ("a", 1.0, 1.0, 1), ("a", 1, -0.5, 1), ("a", 1, math.nan, 1), ("a", 1, math.inf, 1), ("a", 1, "1", 1), ("a", 1, 1.0, 7)],
)
def test_format_marker_refuses_what_it_cannot_encode(route, sector, pos_m, decimals) -> None:
    with pytest.raises(ValueError):
        format_marker(route, sector, pos_m, decimals)


@given(st.from_regex(r"[A-Za-z0-9_-]{1,16}", fullmatch=True), st.integers(0, 10_000), st.floats(0, 1e6), st.integers(0, 6))
def test_format_then_parse_round_trips(route: str, sector: int, pos_m: float, decimals: int) -> None:
    assert parse_marker(format_marker(route, sector, pos_m, decimals)) == TrackMarker(route, sector, float(f"{pos_m:.{decimals}f}"))


@given(st.one_of(st.text(), st.text(alphabet="FG1;=routesectorpos_m0123456789.- ", max_size=60)))
def test_parse_never_raises(payload: str) -> None:
    got = parse_marker(payload)
    assert isinstance(got, (TrackMarker, str))
    if isinstance(got, TrackMarker):
        assert got.sector >= 0 and got.pos_m >= 0 and math.isfinite(got.pos_m)


# -- fixes and staleness -------------------------------------------------------------------------------------
def test_staleness_is_inf_until_the_first_fix_then_counts_from_it() -> None:
    loc = QrLocaliser()
    s0 = loc.update(0.0, [], 0.0)
    assert s0.staleness_s == math.inf and s0.position_m is None and s0.last_marker is None
    assert s0.reasons == ("never localised by QR: staleness inf",)
    s1 = loc.update(1.0, [M12], 0.0)
    assert (s1.staleness_s, s1.position_m, s1.since_fix_m, s1.missed_markers, s1.fix_t_s) == (0.0, 12.5, 0.0, 0, 1.0)
    assert s1.last_marker == TrackMarker("campus", 3, 12.5) and s1.reasons == ("QR fix sector 3 at 12.5 m",)
    s2 = loc.update(3.5, [], 4.0)
    assert (s2.staleness_s, s2.position_m, s2.since_fix_m, s2.missed_markers) == (2.5, 16.5, 4.0, 0)
    assert s2.reasons == ("no QR fix for 2.5 s, 0 markers missed (spacing 5.0 m)",)
    s3 = loc.update(8.2, [], 12.0)
    assert s3.missed_markers == 2 and s3.reasons == ("no QR fix for 7.2 s, 2 markers missed (spacing 5.0 m)",)
    assert loc.state is s3


def test_a_spoofed_marker_is_rejected_and_does_not_refresh() -> None:
    loc = QrLocaliser()
    loc.update(1.0, [M12], 0.0)
    s = loc.update(2.0, [M80], 0.0)
    assert s.staleness_s == 1.0 and s.last_marker.pos_m == 12.5
    assert s.reasons[0] == "QR marker at 80.0 m rejected: implausible jump of 67.5 m (odometer says 12.5 ± 1.5 m)"
    s = loc.update(3.0, [M17], 5.1)  # the next board where the odometer says it is: accepted
    assert s.staleness_s == 0.0 and s.last_marker.pos_m == 17.5


@pytest.mark.parametrize(("offset_m", "accepted"), [(0.0, True), (2.9, True), (-2.9, True), (3.1, False), (-3.1, False)])
def test_the_tolerance_grows_with_distance_driven(offset_m: float, accepted: bool) -> None:
    loc = QrLocaliser()
    loc.update(0.0, [marker(10.0)], 0.0)
    s = loc.update(10.0, [marker(40.0 + offset_m)], 30.0)  # 30 m driven: ±max(1.5, 0.1 × 30) = ±3.0 m
    assert (s.staleness_s == 0.0) is accepted


def test_the_neighbouring_board_is_told_apart() -> None:
    loc = QrLocaliser()
    loc.update(0.0, [marker(10.0)], 0.0)
    assert loc.update(1.0, [marker(20.0)], 5.0).staleness_s == 1.0  # odometer says 15 m: the board at 20 m is not here


def test_the_same_board_read_again_keeps_its_first_odometer_anchor() -> None:
    """Re-anchoring at the last reading would put the next board 3 m off (approach distance) and reject it."""
    loc = QrLocaliser()
    loc.update(0.0, [marker(10.0)], 0.0)  # first read 3 m before the board
    for k in range(1, 4):
        s = loc.update(0.5 * k, [marker(10.0)], 1.0 * k)  # read while approaching it
        assert s.staleness_s == 0.0 and s.position_m == 10.0 + k
    s = loc.update(2.5, [marker(15.0)], 5.0)  # the next board, first read from the same distance
    assert s.staleness_s == 0.0 and s.last_marker.pos_m == 15.0


@pytest.mark.parametrize(("driven_m", "accepted"), [(-1.5, True), (-1.6, False), (0.0, True), (5.0, True), (5.1, False), (40.0, False)])
def test_the_last_board_read_again_is_a_fix_only_within_one_spacing_of_its_first_reading(driven_m: float, accepted: bool) -> None:
    """A copy of the last board further down the road cannot keep the fix fresh for ever."""
    loc = QrLocaliser()
    loc.update(0.0, [marker(10.0)], 0.0)
    s = loc.update(1.0, [marker(10.0)], driven_m)
    assert (s.fix_t_s == 1.0) is accepted
    if not accepted:
        assert "the last fix's board" in s.reasons[0] or "implausible" in s.reasons[0]


def test_two_markers_in_one_frame_the_one_nearest_the_prediction_wins() -> None:
    loc = QrLocaliser()
    loc.update(0.0, [marker(10.0)], 0.0)
    s = loc.update(1.0, [marker(16.0, 2), marker(15.0, 1)], 5.2)
    assert s.last_marker == TrackMarker("campus", 1, 15.0)


def test_first_fix_with_two_boards_in_view_takes_the_nearer_one_ahead() -> None:
    s = QrLocaliser().update(0.0, [marker(20.0, 2), marker(15.0, 1)], 0.0)
    assert s.last_marker.pos_m == 15.0


def test_wrong_route_is_rejected() -> None:
    loc = QrLocaliser(route="campus")
    s = loc.update(0.0, [marker(12.5, 3, "other")], 0.0)
    assert s.staleness_s == math.inf and s.reasons[0] == "QR marker route 'other' rejected: expected route 'campus'"


def test_without_a_route_the_first_route_seen_is_kept() -> None:
    loc = QrLocaliser()
    loc.update(0.0, [marker(12.5, 3, "north")], 0.0)
    s = loc.update(1.0, [marker(12.5, 3, "south")], 0.0)
    assert s.staleness_s == 1.0 and "expected route 'north'" in s.reasons[0]


def test_a_marker_beyond_the_route_length_is_rejected() -> None:
    loc = QrLocaliser(route_length_m=100.0)
    assert loc.update(0.0, [marker(150.0)], 0.0).staleness_s == math.inf
    assert loc.update(0.0, [marker(100.0)], 0.0).staleness_s == 0.0


def test_garbage_is_reported_and_never_a_fix() -> None:
    loc = QrLocaliser()
    s = loc.update(0.0, ["xyz", "", "FG1;route=a", "http://x.org/" + "y" * 100], 0.0)
    assert s.staleness_s == math.inf
    assert s.reasons[0] == "QR payload 'xyz' rejected: not a track marker"
    assert any(r.startswith("QR payload 'http://x.org/yyy") and "…" in r for r in s.reasons)


@pytest.mark.parametrize("payloads", [None, (), 5, 3.5, [None, 5, b"FG1"], {"a": 1}, iter(["xyz"])])
def test_odd_payload_containers_never_raise_and_never_fix(payloads) -> None:
    loc = QrLocaliser()
    assert loc.update(0.0, payloads, 0.0).staleness_s == math.inf


def test_a_bare_string_counts_as_one_payload() -> None:
    assert QrLocaliser().update(0.0, M12, 0.0).staleness_s == 0.0


def test_the_same_text_twice_in_a_frame_is_one_reading() -> None:
    s = QrLocaliser().update(0.0, ["xyz", "xyz", M12, M12], 0.0)
    assert s.reasons == ("QR payload 'xyz' rejected: not a track marker", "QR fix sector 3 at 12.5 m")


# -- time and odometer faults ------------------------------------------------------------------------------------
@pytest.mark.parametrize("bad_t", [math.nan, math.inf, -math.inf, None, "3.0", True, 1.0])
def test_bad_or_backward_time_ignores_the_payloads_and_keeps_staleness(bad_t) -> None:
    loc = QrLocaliser()
    loc.update(1.0, [M12], 0.0)
    before = loc.update(4.0, [], 2.0)
    s = loc.update(bad_t, [M17], 5.0)  # a valid marker, but at a time that cannot be trusted
    assert s.staleness_s == before.staleness_s == 3.0 and s.last_marker.pos_m == 12.5
    assert s.reasons[0].endswith(": QR payloads ignored")
    assert loc.update(4.5, [], 2.0).staleness_s == 3.5  # measured from the last valid time again


def test_equal_time_is_valid() -> None:
    loc = QrLocaliser()
    loc.update(1.0, [], 0.0)
    assert loc.update(1.0, [M12], 0.0).staleness_s == 0.0


@pytest.mark.parametrize("odometer", [None, math.nan, math.inf, "12", True])
def test_without_odometer_position_is_unknown_but_staleness_counts(odometer) -> None:
    loc = QrLocaliser()
    s = loc.update(1.0, [M12], odometer)
    assert (s.staleness_s, s.position_m, s.since_fix_m, s.missed_markers) == (0.0, None, None, None)
    s = loc.update(3.0, [], odometer)
    assert s.staleness_s == 2.0 and s.reasons == ("no QR fix for 2.0 s, markers missed unknown (no odometer) (spacing 5.0 m)",)


def test_without_odometer_a_fix_may_move_at_most_max_speed_times_time() -> None:
    loc = QrLocaliser(max_speed_mps=5.0)
    loc.update(0.0, [marker(10.0)], None)
    s = loc.update(1.0, [marker(40.0)], None)  # 30 m in 1 s: impossible
    assert s.staleness_s == 1.0 and "farther than 6.5 m reachable without odometer" in s.reasons[0]
    assert loc.update(2.0, [marker(20.0)], None).staleness_s == 0.0  # 10 m in 2 s: possible


def test_an_odometer_that_appears_later_anchors_at_the_next_fix() -> None:
    loc = QrLocaliser()
    loc.update(0.0, [marker(10.0)], None)
    assert loc.update(0.5, [], 1.0).position_m is None  # no anchor yet
    s = loc.update(1.0, [marker(10.0)], 2.0)  # the same board again, now with odometer
    assert loc.update(2.0, [], 4.0).position_m == 12.0 and s.staleness_s == 0.0


# -- re-localisation -----------------------------------------------------------------------------------------------
def test_two_distinct_markers_agreeing_by_odometer_relocalise() -> None:
    """The car was carried elsewhere: one far marker is a candidate, a second that agrees with it is a fix."""
    loc = QrLocaliser()
    loc.update(0.0, [marker(12.5)], 0.0)
    s = loc.update(10.0, [marker(60.0)], 0.5)
    assert s.staleness_s == 10.0 and "implausible jump" in s.reasons[0]
    s = loc.update(12.0, [marker(65.0)], 5.6)
    assert s.staleness_s == 0.0 and s.last_marker.pos_m == 65.0
    assert s.reasons[0] == "QR re-localised: markers at 60.0 m and 65.0 m agree by odometer, fix at 12.5 m abandoned"


def test_one_spoofed_board_seen_many_times_never_relocalises() -> None:
    loc = QrLocaliser()
    loc.update(0.0, [marker(12.5)], 0.0)
    for k in range(1, 30):
        s = loc.update(0.1 * k, [M80], 0.1 * k)
        assert s.fix_t_s == 0.0


def test_reset_forgets_everything() -> None:
    loc = QrLocaliser()
    loc.update(5.0, [M12], 0.0)
    loc.reset()
    assert loc.update(1.0, [], 0.0).staleness_s == math.inf  # time may restart after a reset


# -- configuration ------------------------------------------------------------------------------------------------
def test_defaults_are_sane() -> None:
    assert MARKER_SPACING_M == 5.0 and 0 < POSITION_TOLERANCE_M < MARKER_SPACING_M / 2
    assert QrLocaliser().position_tolerance_m == 1.5
    assert QrLocaliser(marker_spacing_m=3.0).position_tolerance_m == pytest.approx(0.9)  # the EMO paper's later 3 m spacing


@pytest.mark.parametrize(
    "kwargs",
    [{"marker_spacing_m": 0.0}, {"marker_spacing_m": math.nan}, {"marker_spacing_m": "5"}, {"position_tolerance_m": 2.5},
     {"position_tolerance_m": 0.0}, {"position_tolerance_m": math.nan}, {"route": "a;b"}, {"route": ""}, {"route_length_m": -1.0},
     {"odometer_rel_tol": 1.0}, {"odometer_rel_tol": -0.1}, {"max_speed_mps": 0.0}, {"max_speed_mps": math.inf}],
)
def test_impossible_configuration_is_refused(kwargs) -> None:
    with pytest.raises(ValueError):
        QrLocaliser(**kwargs)


# -- pure functions -------------------------------------------------------------------------------------------------
def test_pure_functions_by_hand() -> None:
    m = TrackMarker("campus", 4, 17.5)
    assert plausible_fix(m, None, None, None) is None
    assert plausible_fix(m, TrackMarker("campus", 3, 12.5), 5.0, 2.0) is None
    assert "implausible jump of 5.0 m" in plausible_fix(m, TrackMarker("campus", 3, 12.5), 0.0, 2.0)
    assert fix_tolerance_m(0.0) == 1.5 and fix_tolerance_m(-30.0) == 3.0
    assert staleness_s(5.0, None) == math.inf and staleness_s(5.0, 2.0) == 3.0


# -- properties ---------------------------------------------------------------------------------------------------
ROUTE_POS = st.floats(0.0, 200.0).map(lambda x: round(x, 1))
PAYLOAD = st.one_of(
    ROUTE_POS.map(marker),  # valid board anywhere: plausible or a spoof
    st.builds(lambda p: marker(p, 1, "other"), ROUTE_POS),  # another route
    st.text(max_size=40),
    st.sampled_from(["", "FG1", "FG2;route=campus;sector=1;pos_m=1", "FG1;route=campus;sector=-1;pos_m=1"]),
)
ANY = st.one_of(st.none(), st.floats(), st.integers(), st.text(max_size=10), st.booleans(), st.binary(max_size=5))
STEP = st.tuples(
    st.one_of(st.floats(0.0, 2.0), st.just(math.nan), st.floats(-5.0, -0.01)),  # time step: forward, NaN, backwards
    st.lists(PAYLOAD, max_size=3),
    st.one_of(st.floats(-1.0, 8.0), st.none(), st.just(math.nan)),  # odometer step (None/NaN: unknown this frame)
)


def drive(steps) -> list[tuple[float, LocalisationState]]:
    """Run a localiser through (dt, payloads, dodo) steps; NaN dt = a NaN time, negative dt = time going backwards."""
    loc, t, odo = QrLocaliser(route="campus"), 0.0, 0.0
    out = [(0.0, loc.update(0.0, [], 0.0))]  # a first valid time, so that a negative step runs backwards
    for dt, payloads, dodo in steps:
        t_in = math.nan if math.isnan(dt) else t + dt
        if not math.isnan(dt) and dt >= 0:
            t = t_in
        odo_in = None if dodo is None or math.isnan(dodo) else odo + dodo
        if odo_in is not None:
            odo = odo_in
        out.append((t_in, loc.update(t_in, payloads, odo_in)))
    return out


@given(st.lists(STEP, max_size=25))
def test_staleness_never_decreases_except_at_a_fix(steps) -> None:
    states = drive(steps)
    prev = math.inf
    for t_in, s in states:
        fixed = s.staleness_s == 0.0 and any(r.startswith(("QR fix", "QR re-localised")) for r in s.reasons)
        if not fixed:
            assert s.staleness_s >= prev or (prev == math.inf and s.staleness_s == math.inf)
        else:
            assert s.fix_t_s == t_in  # a fix resets staleness to 0 at that update's time
        assert s.staleness_s >= 0.0
        prev = s.staleness_s


@given(st.lists(STEP, max_size=25))
def test_staleness_is_inf_until_the_first_fix(steps) -> None:
    for _, s in drive(steps):
        if s.fix_t_s is None:
            assert s.staleness_s == math.inf and s.last_marker is None
        else:
            assert math.isfinite(s.staleness_s)


@given(st.lists(STEP, max_size=20), st.lists(st.one_of(st.text(max_size=30), ANY), min_size=1, max_size=3))
def test_garbage_never_refreshes(steps, garbage) -> None:
    """Adding non-marker payloads to every frame changes nothing but the reasons."""
    assume(all(not isinstance(parse_marker(g), TrackMarker) for g in garbage))
    clean = [s.staleness_s for _, s in drive(steps)]
    dirty = [s.staleness_s for _, s in drive([(dt, [*p, *garbage], d) for dt, p, d in steps])]
    assert dirty == clean


@given(ROUTE_POS, st.floats(0.0, 50.0), st.floats(0.1, 10.0), st.floats(0.0, 500.0), st.integers(1, 5))
def test_a_spoofed_marker_never_refreshes(fix_pos: float, driven_m: float, dt_s: float, spoof_offset: float, repeats: int) -> None:
    loc = QrLocaliser()
    loc.update(0.0, [marker(fix_pos)], 0.0)
    predicted = fix_pos + driven_m
    spoof = round(predicted + math.copysign(fix_tolerance_m(driven_m) + 0.05 + spoof_offset, 1 if predicted < 100 else -1), 1)
    assume(spoof >= 0 and abs(spoof - predicted) > fix_tolerance_m(driven_m))
    for k in range(repeats):  # the same spoofed board in several frames never confirms itself
        s = loc.update(dt_s * (k + 1), [marker(spoof)], driven_m)
        assert s.fix_t_s == 0.0 and s.staleness_s == pytest.approx(dt_s * (k + 1))


@given(ANY, st.one_of(ANY, st.lists(ANY, max_size=3), st.lists(st.text(max_size=50), max_size=3)), ANY)
def test_update_never_raises(t_s, payloads, odometer_m) -> None:
    loc = QrLocaliser()
    loc.update(0.0, [M12], 0.0)
    s = loc.update(t_s, payloads, odometer_m)
    assert isinstance(s, LocalisationState) and s.staleness_s >= 0.0 and isinstance(s.reasons, tuple)


@given(st.lists(STEP, min_size=1, max_size=25))
@example(steps=[(0.0, [marker(0.0)], None), (1.0, [], 0.0), (0.0, [marker(2.0)], None)])  # no reading: the last one holds
def test_class_decisions_agree_with_the_pure_functions(steps) -> None:
    """Every accept/reject of a lone valid marker is what plausible_fix says (re-localisation aside); staleness likewise."""
    loc, t, odo = QrLocaliser(route="campus"), 0.0, 0.0
    prev, prev_odo = loc.update(0.0, [], 0.0), 0.0  # the last valid-time state and the odometer the localiser had with it
    for dt, payloads, dodo in steps:
        valid_time = not math.isnan(dt) and dt >= 0
        t_in = t + dt if valid_time else (math.nan if math.isnan(dt) else t + dt)
        odo_in = None if dodo is None or math.isnan(dodo) else odo + dodo
        odo = odo if odo_in is None else odo_in  # without a reading the localiser holds the last one (no speed is given)
        s = loc.update(t_in, payloads, odo_in)
        odo_in = odo
        if not valid_time:
            assert s.staleness_s == prev.staleness_s and s.fix_t_s == prev.fix_t_s
            continue
        t = t_in
        assert s.staleness_s == staleness_s(t, s.fix_t_s)
        markers = [m for m in map(parse_marker, payloads) if isinstance(m, TrackMarker)]
        relocalised = any(r.startswith("QR re-localised") for r in s.reasons)
        if len(set(markers)) == 1 and not relocalised:
            elapsed = None if prev.fix_t_s is None else t - prev.fix_t_s
            if prev.last_marker is None or odo_in is None:
                decidable, since = True, None
            elif prev.since_fix_m is not None and prev_odo is not None:
                decidable, since = True, odo_in - (prev_odo - prev.since_fix_m)  # the fix's odometer anchor, from public values
            else:
                decidable, since = False, None  # anchor not visible in the public state
            if decidable and prev.fix_t_s != t:  # a fix at this very time already: fix_t_s cannot show the decision
                pure = plausible_fix(markers[0], prev.last_marker, since, elapsed, "campus", marker_spacing_m=loc.marker_spacing_m)
                assert (s.fix_t_s == t) == (pure is None), (pure, prev, s)
        prev, prev_odo = s, odo_in
