"""Sensor logs: CSV / JSON Lines round trips, malformed lines with their line numbers, strict mode, time alignment."""

from __future__ import annotations

import csv
import dataclasses
import json
import math
import tempfile
from pathlib import Path

import pytest
from hypothesis import given
from hypothesis import strategies as st

from fearguard.errors import FearguardError
from fearguard.replay.sensor_log import (
    KNOWN_COLUMNS,
    MAX_AGE_S,
    NO_READING,
    LogIssue,
    SensorLog,
    SensorLogError,
    SensorLogWarning,
    SensorSample,
    load_sensor_log,
)

ROWS = (
    SensorSample(t_s=0.0, ultrasonic_range_m=1.5, speed_mps=0.8, odometer_m=0.0),
    SensorSample(t_s=0.1, ultrasonic_range_m=1.42, echo_s=0.00828, speed_mps=0.81, odometer_m=0.08, qr_payload="sector=3;pos=12.5"),
    SensorSample(t_s=0.2, ultrasonic_range_m=math.inf, lead_x=400.0, lead_y=300.0, lead_w=120.0, lead_h=90.0),
    SensorSample(t_s=0.3, qr_payload="a,b \"quoted\""),
)


def write(path: Path, text: str) -> Path:
    path.write_text(text, encoding="utf-8")
    return path


def write_csv(path: Path, samples: tuple[SensorSample, ...] | list[SensorSample]) -> Path:
    with path.open("w", newline="", encoding="utf-8") as fh:
        writer = csv.DictWriter(fh, fieldnames=list(KNOWN_COLUMNS))
        writer.writeheader()
        for s in samples:
            writer.writerow({k: "" if v is None else repr(v) if isinstance(v, float) else v for k, v in dataclasses.asdict(s).items()})
    return path


def write_jsonl(path: Path, samples: tuple[SensorSample, ...] | list[SensorSample]) -> Path:
    lines = [json.dumps({k: v for k, v in dataclasses.asdict(s).items() if v is not None}) for s in samples]
    return write(path, "\n".join(lines) + "\n")


# ------------------------------------------------------------------------------------------ loading


def test_csv_round_trip(tmp_path: Path) -> None:
    log = load_sensor_log(write_csv(tmp_path / "log.csv", ROWS))
    assert log.samples == ROWS
    assert log.issues == () and log.unknown_columns == ()
    assert log.columns == KNOWN_COLUMNS
    assert log.samples[2].lead_box_px() == (400.0, 300.0, 120.0, 90.0) and log.samples[0].lead_box_px() is None


def test_jsonl_round_trip_and_columns_present(tmp_path: Path) -> None:
    log = load_sensor_log(write_jsonl(tmp_path / "log.jsonl", ROWS))
    assert log.samples == ROWS and log.issues == ()
    assert "echo_s" in log.columns and "lead_h" in log.columns


def test_format_is_sniffed_without_a_known_extension(tmp_path: Path) -> None:
    as_csv = load_sensor_log(write(tmp_path / "a.log", "t_s,speed_mps\n0.5,1.25\n"))
    as_jsonl = load_sensor_log(write(tmp_path / "b.log", '{"t_s": 0.5, "speed_mps": 1.25}\n'))
    assert as_csv.samples == as_jsonl.samples == (SensorSample(t_s=0.5, speed_mps=1.25),)


def test_empty_values_are_none_and_crlf_and_bom_are_fine(tmp_path: Path) -> None:
    path = tmp_path / "log.csv"
    path.write_bytes(b"\xef\xbb\xbft_s,ultrasonic_range_m,qr_payload\r\n0.0,,\r\n0.1, 2.5 ,P1\r\n")
    log = load_sensor_log(path)
    assert log.samples == (SensorSample(t_s=0.0), SensorSample(t_s=0.1, ultrasonic_range_m=2.5, qr_payload="P1"))


def test_csv_malformed_lines_are_reported_with_their_line_numbers(tmp_path: Path) -> None:
    text = (
        "t_s,ultrasonic_range_m,speed_mps\n"  # 1
        "0.0,1.0,0.5\n"  # 2 ok
        "0.1,near,0.5\n"  # 3 text in a number column
        "\n"  # 4 blank: ignored
        ",1.0,0.5\n"  # 5 t_s missing
        "0.3,1.0\n"  # 6 too few fields (a line cut by a power loss)
        "nan,1.0,0.5\n"  # 7 t_s not finite
        "0.5,0.9,0.4\n"  # 8 ok
    )
    log = load_sensor_log(write(tmp_path / "log.csv", text))
    assert [s.t_s for s in log.samples] == [0.0, 0.5]
    assert [i.line for i in log.issues] == [3, 5, 6, 7]
    assert "'ultrasonic_range_m'" in log.issues[0].problem and "'near'" in log.issues[0].problem
    assert "missing" in log.issues[1].problem
    assert "2 fields" in log.issues[2].problem and "3" in log.issues[2].problem
    assert "finite" in log.issues[3].problem


def test_jsonl_malformed_lines_are_reported_with_their_line_numbers(tmp_path: Path) -> None:
    text = (
        '{"t_s": 0.0, "speed_mps": 1.0}\n'  # 1 ok
        '{"t_s": 0.1, "speed_mps": 1.0\n'  # 2 not JSON
        '[0.2, 1.0]\n'  # 3 not an object
        '{"speed_mps": 1.0}\n'  # 4 no t_s
        '{"t_s": 0.4, "speed_mps": true}\n'  # 5 boolean is not a number
        '{"t_s": "0.5", "speed_mps": "fast"}\n'  # 6 text in a number column
        '{"t_s": "0.6", "odometer_m": null, "qr_payload": 42}\n'  # 7 ok: numeric text, null, number as payload text
    )
    log = load_sensor_log(write(tmp_path / "log.jsonl", text))
    assert log.samples == (SensorSample(t_s=0.0, speed_mps=1.0), SensorSample(t_s=0.6, qr_payload="42"))
    assert [i.line for i in log.issues] == [2, 3, 4, 5, 6]
    assert "JSON" in log.issues[0].problem and "object" in log.issues[1].problem


def test_invalid_utf8_costs_one_line(tmp_path: Path) -> None:
    path = tmp_path / "log.csv"
    path.write_bytes(b"t_s,qr_payload\n0.0,A\n0.1,\xff\xfe\n0.2,C\n")
    log = load_sensor_log(path)
    assert [s.qr_payload for s in log.samples] == ["A", "C"]
    assert log.issues == (LogIssue(3, "not valid UTF-8 text"),)


def test_strict_raises_on_the_first_malformed_line(tmp_path: Path) -> None:
    path = write(tmp_path / "log.csv", "t_s,speed_mps\n0.0,1\n0.1,x\n0.2,y\n")
    with pytest.raises(SensorLogError) as info:
        load_sensor_log(path, strict=True)
    assert isinstance(info.value, FearguardError)
    assert info.value.line == 3 and str(path) in str(info.value) and "line 3" in str(info.value)
    assert len(load_sensor_log(path).issues) == 2  # not strict: both reported, neither raised


def test_unknown_columns_warn_but_load(tmp_path: Path) -> None:
    path = write(tmp_path / "log.csv", "t_s,speed_mps,battery_v,lidar_m\n0.0,1.0,7.4,2.0\n")
    with pytest.warns(SensorLogWarning, match="battery_v, lidar_m"):
        log = load_sensor_log(path, strict=True)
    assert log.unknown_columns == ("battery_v", "lidar_m")
    assert log.samples == (SensorSample(t_s=0.0, speed_mps=1.0),)


def test_rows_out_of_order_are_reported_and_sorted(tmp_path: Path) -> None:
    path = write(tmp_path / "log.csv", "t_s,speed_mps\n0.0,1\n0.2,3\n0.1,2\n0.2,4\n")
    log = load_sensor_log(path)
    assert [s.speed_mps for s in log.samples] == [1.0, 2.0, 3.0, 4.0]  # sorted, equal times keep file order
    assert [i.line for i in log.issues] == [4] and "line 3" in log.issues[0].problem
    assert log.at(0.15).speed_mps == 2.0 and log.at(0.2).speed_mps == 4.0
    with pytest.raises(SensorLogError, match="line 4"):
        load_sensor_log(path, strict=True)


@pytest.mark.parametrize(
    ("name", "text", "match"),
    [
        ("empty.csv", "", "empty"),
        ("blank.csv", "\n \n", "empty"),
        ("no_t.csv", "time,speed_mps\n0,1\n", "no 't_s' column"),
        ("no_header.csv", "0.0,1.0\n0.1,1.1\n", "first row must name the columns"),
        ("dup.csv", "t_s,speed_mps,speed_mps\n0,1,1\n", "twice"),
        ("unnamed.csv", "t_s,,speed_mps\n0,1,1\n", "column 2 has no name"),
        ("array.json", '[{"t_s": 0}]\n', "JSON Lines"),
    ],
)
def test_unusable_files_raise_naming_the_file(tmp_path: Path, name: str, text: str, match: str) -> None:
    path = write(tmp_path / name, text)
    with pytest.raises(SensorLogError, match=match) as info:
        load_sensor_log(path)
    assert str(path) in str(info.value)


def test_missing_file_raises(tmp_path: Path) -> None:
    with pytest.raises(SensorLogError, match="cannot read"):
        load_sensor_log(tmp_path / "nope.csv")


# ---------------------------------------------------------------------------------------- alignment

LOG = SensorLog(Path("mem"), tuple(SensorSample(t_s=t, ultrasonic_range_m=r) for t, r in [(1.0, 2.0), (1.1, 1.9), (1.2, 1.8), (3.0, 0.5)]))


def test_a_frame_between_rows_sees_the_earlier_row() -> None:
    assert LOG.at(1.15).ultrasonic_range_m == 1.9
    assert LOG.at(1.15).t_s == 1.1


def test_a_frame_exactly_on_a_row_sees_that_row() -> None:
    assert LOG.at(1.2).ultrasonic_range_m == 1.8
    assert LOG.at(3.0).ultrasonic_range_m == 0.5


def test_after_a_long_gap_there_is_no_reading() -> None:
    assert LOG.at(1.2 + MAX_AGE_S).ultrasonic_range_m == 1.8  # exactly max_age_s old: still used
    assert LOG.at(1.2 + MAX_AGE_S + 0.01) == NO_READING  # older: the sensor is silent, the caller treats it as unknown
    assert LOG.at(2.5, max_age_s=2.0).ultrasonic_range_m == 1.8
    assert LOG.at(0.99) == NO_READING  # before the first row: nothing from the future


@pytest.mark.parametrize("bad", [math.nan, math.inf, -math.inf, None, "soon", object(), [1.1]])
def test_at_never_raises_on_bad_input(bad: object) -> None:
    assert LOG.at(bad) == NO_READING  # type: ignore[arg-type]
    if bad is not math.inf:
        assert LOG.at(1.1, max_age_s=bad) == NO_READING  # type: ignore[arg-type]


def test_infinite_max_age_takes_the_latest_row_however_old() -> None:
    assert LOG.at(1e9, max_age_s=math.inf).ultrasonic_range_m == 0.5


def test_negative_or_nan_max_age_gives_no_reading() -> None:
    assert LOG.at(1.1, max_age_s=-0.1) == NO_READING
    assert LOG.at(1.1, max_age_s=math.nan) == NO_READING
    assert LOG.at(1.1, max_age_s=0.0).ultrasonic_range_m == 1.9


def test_no_reading_is_all_none() -> None:
    assert all(v is None for v in dataclasses.asdict(NO_READING).values())


times = st.lists(st.floats(-100, 100, allow_nan=False), min_size=0, max_size=30)


@given(times, st.floats(-120, 120, allow_nan=False), st.floats(0, 50, allow_nan=False))
def test_at_is_the_latest_row_in_the_window_never_future_never_too_old(ts: list[float], t: float, age: float) -> None:
    log = SensorLog(Path("mem"), tuple(SensorSample(t_s=x, odometer_m=float(i)) for i, x in enumerate(ts)))
    got = log.at(t, max_age_s=age)
    in_window = [s for s in log.samples if s.t_s is not None and s.t_s <= t and t - s.t_s <= age]
    if got == NO_READING:
        assert in_window == []
    else:
        assert got.t_s is not None and got.t_s <= t and t - got.t_s <= age
        assert got is in_window[-1]  # the latest; among equal times the last one in the file


@given(st.lists(st.tuples(st.floats(-1e6, 1e6, allow_nan=False), st.one_of(st.none(), st.floats(allow_nan=False)),
                          st.one_of(st.none(), st.text(st.characters(codec="utf-8", exclude_categories=("Cs", "Cc")), min_size=1))),
                min_size=1, max_size=20))
def test_csv_and_jsonl_round_trip_any_values(rows: list[tuple[float, float | None, str | None]]) -> None:
    samples = [SensorSample(t_s=t, speed_mps=v, qr_payload=q if q is None or q.strip() else None) for t, v, q in rows]
    expected = tuple(sorted(samples, key=lambda s: s.t_s))  # type: ignore[arg-type, return-value]
    with tempfile.TemporaryDirectory() as folder:
        from_csv = load_sensor_log(write_csv(Path(folder) / "log.csv", samples))
        from_jsonl = load_sensor_log(write_jsonl(Path(folder) / "log.jsonl", samples))
    assert from_csv.samples == expected
    assert from_jsonl.samples == expected
    assert all("sorted into place" in issue.problem for issue in from_csv.issues)
