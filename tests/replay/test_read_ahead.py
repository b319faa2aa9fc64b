"""Decoding ahead on another core: the same items in the same order, errors passed on, the reader stopped (and the
source closed) as soon as the consumer stops; a replay with it writes the very same log as one without."""

from __future__ import annotations

import threading
from collections.abc import Iterator
from pathlib import Path

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from fearguard.outputs.report import read_jsonl
from fearguard.replay.read_ahead import read_ahead, usable_cores
from fearguard.replay.run import ReplayOptions, replay

VIDEO = Path("road") / "video" / "solidWhiteRight.mp4"


class Counted:
    """A source that counts what was read from it and whether it was closed."""

    def __init__(self, items: list[int], fail_at: int | None = None) -> None:
        self.items, self.fail_at, self.read, self.closed = items, fail_at, 0, False

    def __iter__(self) -> Iterator[int]:
        try:
            for i, item in enumerate(self.items):
                if i == self.fail_at:
                    raise ValueError(f"unreadable item {i}")
                self.read += 1
                yield item
        finally:
            self.closed = True


def _readers() -> list[threading.Thread]:
    return [t for t in threading.enumerate() if t.name == "fearguard-read-ahead"]


@settings(max_examples=40, deadline=None)
@given(st.lists(st.integers(), max_size=30), st.integers(1, 5))
def test_every_item_arrives_in_order(items: list[int], depth: int) -> None:
    source = Counted(items)
    assert list(read_ahead(iter(source), depth)) == items
    assert source.closed and not _readers()


@settings(max_examples=30, deadline=None)
@given(st.integers(0, 12), st.integers(1, 4))
def test_an_error_in_the_source_arrives_after_the_items_before_it(fail_at: int, depth: int) -> None:
    source = Counted(list(range(20)), fail_at)
    got: list[int] = []
    with pytest.raises(ValueError, match=f"unreadable item {fail_at}"):
        for item in read_ahead(iter(source), depth):
            got.append(item)
    assert got == list(range(fail_at)) and source.closed and not _readers()


@settings(max_examples=30, deadline=None)
@given(st.integers(0, 10), st.integers(1, 4))
def test_closing_early_stops_the_reader_and_closes_the_source(taken: int, depth: int) -> None:
    source = Counted(list(range(1000)))
    ahead = read_ahead(iter(source), depth)
    got = [next(ahead) for _ in range(taken)]
    ahead.close()
    assert got == list(range(taken))
    assert (source.closed or source.read == 0) and not _readers()  # closed before close() returned (or never started)
    assert source.read <= taken + depth + 1  # read ahead by at most the queue and the item in the reader's hands


def test_an_exception_in_the_consumer_stops_the_reader() -> None:
    source = Counted(list(range(1000)))
    with pytest.raises(RuntimeError):
        for item in read_ahead(iter(source)):
            if item == 5:
                raise RuntimeError("the consumer failed")
    assert source.closed and not _readers()


def test_usable_cores_follows_the_affinity() -> None:
    assert 1 <= usable_cores()


def _without_timing(summary: dict) -> dict:
    return {k: v for k, v in summary.items() if k != "processing_fps"}


def _replays(video: Path, out: Path) -> dict[bool, tuple[list[dict], dict]]:
    runs = {}
    for ahead in (False, True):
        result = replay(video, out / f"ahead-{ahead}", ReplayOptions(plots=False, every=3, read_ahead=ahead))
        runs[ahead] = (read_jsonl(out / f"ahead-{ahead}" / "log.jsonl"), _without_timing(result.summary))
        assert not _readers() and not result.interrupted
    return runs


def test_a_replay_reading_ahead_writes_the_same_files(shared_data: Path, tmp_path: Path) -> None:
    runs = _replays(shared_data / VIDEO, tmp_path)
    assert runs[True] == runs[False] and len(runs[True][0]) == 74


def test_a_damaged_video_read_ahead_loses_and_reports_the_same_frames(shared_data: Path, tmp_path: Path) -> None:
    """Garbage in the middle: the frames lost are found (and reported) on the reader's thread. The pixels FFmpeg
    conceals the damage with differ from run to run (its threads), so frames and reports are compared, not cues."""
    data = bytearray((shared_data / VIDEO).read_bytes())
    middle, size = len(data) // 2, 200_000
    data[middle : middle + size] = np.random.default_rng(7).integers(0, 256, size, dtype=np.uint8).tobytes()
    damaged = tmp_path / "damaged.mp4"
    damaged.write_bytes(bytes(data))
    runs = _replays(damaged, tmp_path)
    frames = {ahead: [r["frame"] for r in log] for ahead, (log, _) in runs.items()}
    assert frames[True] == frames[False]
    assert runs[True][1]["skipped"] == runs[False][1]["skipped"] != []
    assert runs[True][1]["stopped_early"] == runs[False][1]["stopped_early"] is None
