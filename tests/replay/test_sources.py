"""Frame sources: real videos (whole, truncated, damaged), image folders, Donkey Car tubs, --from/--to parsing."""

from __future__ import annotations

import json
import math
import shutil
from collections.abc import Iterator
from pathlib import Path

import cv2
import numpy as np
import pytest
from hypothesis import given
from hypothesis import strategies as st

from fearguard.errors import FearguardError
from fearguard.replay import sources
from fearguard.replay.sources import DEFAULT_FPS, Skip, SourceError, natural_key, open_source, parse_position

VIDEO = "road/video/solidWhiteRight.mp4"  # 221 frames, 960×540, 25 Hz, moov atom at the start
STILL = "road/images/solidWhiteRight.jpg"
T0_MS = 1_700_000_000_000  # [ms] first tub record's wall-clock time


def reference_frames(path: Path, wanted: set[int] | None = None) -> Iterator[tuple[int, np.ndarray]]:
    """Frames decoded straight with cv2.VideoCapture.read, the way a person would check by hand."""
    cap = cv2.VideoCapture(str(path))
    index = 0
    try:
        while True:
            ok, image = cap.read()
            if not ok:
                return
            if wanted is None or index in wanted:
                yield index, image
            index += 1
    finally:
        cap.release()


class CaptureSpy:
    """cv2.VideoCapture stand-in that counts BGR conversions and can pretend the file has no frame rate."""

    real = cv2.VideoCapture
    retrieved = 0
    hide_fps = False
    seek_error = 0  # [frames] where CAP_PROP_POS_FRAMES lands relative to where it was asked to

    def __init__(self, *args: object) -> None:
        self._cap = CaptureSpy.real(*args)

    def __getattr__(self, name: str) -> object:
        return getattr(self._cap, name)

    def retrieve(self, *args: object) -> tuple[bool, np.ndarray]:
        CaptureSpy.retrieved += 1
        return self._cap.retrieve(*args)

    def get(self, prop: int) -> float:
        return 0.0 if CaptureSpy.hide_fps and prop == cv2.CAP_PROP_FPS else self._cap.get(prop)

    def set(self, prop: int, value: float) -> bool:
        return self._cap.set(prop, value + CaptureSpy.seek_error if prop == cv2.CAP_PROP_POS_FRAMES else value)


@pytest.fixture
def spy(monkeypatch: pytest.MonkeyPatch) -> type[CaptureSpy]:
    monkeypatch.setattr(CaptureSpy, "retrieved", 0)
    monkeypatch.setattr(CaptureSpy, "hide_fps", False)
    monkeypatch.setattr(CaptureSpy, "seek_error", 0)
    monkeypatch.setattr(sources.cv2, "VideoCapture", CaptureSpy)
    return CaptureSpy


# -------------------------------------------------------------------------------------------- video


def test_video_reports_what_its_header_says(shared_data: Path) -> None:
    source = open_source(shared_data / VIDEO)
    assert (source.kind, source.fps, source.expected_frames, source.frame_size) == ("video", 25.0, 221, (960, 540))
    assert source.notes == () and source.skipped == [] and source.stopped_early is None


def test_start_stop_every_give_the_same_frames_as_reading_by_hand(shared_data: Path) -> None:
    source = open_source(shared_data / VIDEO)
    frames = list(source.iter_frames(start=100, stop=110, every=3))
    assert [f.index for f in frames] == [100, 103, 106, 109]
    assert [f.t_s for f in frames] == [i / 25.0 for i in (100, 103, 106, 109)]
    by_hand = dict(reference_frames(shared_data / VIDEO, {100, 103, 106, 109}))
    assert all(np.array_equal(f.image_bgr, by_hand[f.index]) for f in frames)
    assert all(f.image_bgr.dtype == np.uint8 and f.image_bgr.shape == (540, 960, 3) and dict(f.record) == {} for f in frames)


def test_frames_not_sampled_are_grabbed_not_converted(shared_data: Path, spy: type[CaptureSpy]) -> None:
    source = open_source(shared_data / VIDEO)
    spy.retrieved = 0
    frames = list(source.iter_frames(stop=60, every=20))
    assert [f.index for f in frames] == [0, 20, 40]
    assert spy.retrieved == 3


@pytest.mark.parametrize("seek_error", [-4, 3])
def test_a_seek_that_lands_off_target_is_corrected(shared_data: Path, spy: type[CaptureSpy], seek_error: int) -> None:
    spy.seek_error = seek_error  # lands early: read forward to it; overshoots: start again from frame 0
    frames = list(open_source(shared_data / VIDEO).iter_frames(start=30, stop=32))
    by_hand = dict(reference_frames(shared_data / VIDEO, {30, 31}))
    assert [f.index for f in frames] == [30, 31]
    assert all(np.array_equal(f.image_bgr, by_hand[f.index]) for f in frames)


def test_without_a_frame_rate_t_s_comes_from_frame_timestamps(shared_data: Path, spy: type[CaptureSpy]) -> None:
    spy.hide_fps = True
    source = open_source(shared_data / VIDEO)
    assert source.fps == DEFAULT_FPS and any("CAP_PROP_POS_MSEC" in note for note in source.notes)
    frames = list(source.iter_frames(start=3, stop=6))  # no seeking without a frame rate: read forward
    assert [f.index for f in frames] == [3, 4, 5]
    assert [f.t_s for f in frames] == pytest.approx([0.12, 0.16, 0.20])  # the file's clock is 25 Hz


def test_fps_given_overrides_the_files_rate_and_says_so(shared_data: Path) -> None:
    source = open_source(shared_data / VIDEO, fps=10.0)
    assert source.fps == 10.0 and "overrides" in source.notes[0]
    assert [f.t_s for f in source.iter_frames(start=5, stop=7)] == [0.5, 0.6]


def test_truncated_video_yields_every_frame_before_the_cut(shared_data: Path, tmp_path: Path) -> None:
    full = shared_data / VIDEO
    cut = tmp_path / "cut.mp4"
    shutil.copyfile(full, cut)
    with cut.open("r+b") as fh:
        fh.truncate(int(full.stat().st_size * 0.4))
    source = open_source(cut)
    assert source.expected_frames == 221  # the moov atom at the start still describes the whole video
    count = 0
    for frame, (index, image) in zip(source.iter_frames(), reference_frames(full), strict=False):
        assert frame.index == index == count
        assert np.array_equal(frame.image_bgr, image)
        count += 1
    assert 0 < count < 221
    expected = f"video ended at frame {count} of 221 expected: file truncated or corrupt ({221 - count} frames not read)"
    assert source.stopped_early == expected
    assert source.skipped == []


def test_truncated_video_started_after_the_cut_reports_it(shared_data: Path, tmp_path: Path) -> None:
    full = shared_data / VIDEO
    cut = tmp_path / "cut.mp4"
    cut.write_bytes(full.read_bytes()[: int(full.stat().st_size * 0.4)])
    source = open_source(cut)
    assert list(source.iter_frames(start=150)) == []
    assert source.stopped_early is not None and "frame 150 of 221" in source.stopped_early


def test_garbage_inside_the_video_loses_only_the_damaged_stretch(shared_data: Path, tmp_path: Path) -> None:
    full = shared_data / VIDEO
    data = bytearray(full.read_bytes())
    middle, size = len(data) // 2, 200_000  # [bytes] inside mdat, which runs from byte 4583 to the end
    data[middle : middle + size] = np.random.default_rng(7).integers(0, 256, size, dtype=np.uint8).tobytes()
    damaged = tmp_path / "damaged.mp4"
    damaged.write_bytes(bytes(data))

    source = open_source(damaged)
    frames = {f.index: f for f in source.iter_frames(every=10)}
    lost = [s.index for s in source.skipped]
    assert source.stopped_early is None  # the source got past the damage instead of giving up
    assert lost and all(i is not None and 100 < i < 160 and i % 10 == 0 for i in lost)
    assert sorted(frames) == [i for i in range(0, 221, 10) if i not in lost]  # every sampled frame: read or reported
    assert all(frames[i].t_s == i / 25.0 for i in frames)
    by_hand = dict(reference_frames(full, {*range(0, 100, 10), *range(170, 221, 10)}))
    assert all(np.array_equal(frames[i].image_bgr, image) for i, image in by_hand.items())  # indices stay honest after it


def test_a_text_file_named_mp4_raises_with_advice(tmp_path: Path) -> None:
    fake = tmp_path / "drive.mp4"
    fake.write_text("this is not a video\n" * 50)
    with pytest.raises(SourceError, match="ffmpeg -i") as info:
        open_source(fake)
    assert str(fake) in str(info.value) and isinstance(info.value, FearguardError)


def test_a_missing_path_raises(tmp_path: Path) -> None:
    with pytest.raises(SourceError, match="no such file or folder") as info:
        open_source(tmp_path / "nowhere.mp4")
    assert "nowhere.mp4" in str(info.value)


@pytest.mark.parametrize(("kwargs", "match"), [({"start": -1}, "start"), ({"start": 5, "stop": 4}, "--from must come before --to"),
                                               ({"every": 0}, "every"), ({"every": 1.5}, "every")])
def test_bad_ranges_raise(shared_data: Path, kwargs: dict[str, object], match: str) -> None:
    source = open_source(shared_data / STILL)
    with pytest.raises(SourceError, match=match):
        source.iter_frames(**kwargs)  # type: ignore[arg-type]


@pytest.mark.parametrize("fps", [0.0, -5.0, math.nan, math.inf, True])
def test_bad_fps_raises(shared_data: Path, fps: float) -> None:
    with pytest.raises(SourceError, match="fps"):
        open_source(shared_data / STILL, fps=fps)


# ------------------------------------------------------------------------------------- image folder


@pytest.fixture(scope="module")
def small_still(shared_data: Path) -> np.ndarray:
    return cv2.resize(cv2.imread(str(shared_data / STILL)), (160, 120), interpolation=cv2.INTER_AREA)


def test_image_folder_natural_order_timestamps_and_skips(tmp_path: Path, small_still: np.ndarray) -> None:
    cv2.imwrite(str(tmp_path / "img10.png"), small_still[::-1])
    cv2.imwrite(str(tmp_path / "img2.PNG"), small_still[:, ::-1])
    cv2.imwrite(str(tmp_path / "img1.png"), small_still)
    (tmp_path / "img3.jpg").write_text("not a jpeg")
    (tmp_path / "._img4.jpg").write_bytes(b"\x00\x05\x16\x07")  # macOS resource fork: hidden, ignored
    (tmp_path / "notes.txt").write_text("drive 3")
    (tmp_path / "sub").mkdir()
    source = open_source(tmp_path)
    assert (source.kind, source.expected_frames, source.frame_size, source.fps) == ("images", 4, (160, 120), DEFAULT_FPS)
    assert "20 Hz" in source.notes[0]
    frames = list(source.iter_frames())
    assert [(f.index, f.record["file"], f.t_s) for f in frames] == [(0, "img1.png", 0.0), (1, "img2.PNG", 0.05), (3, "img10.png", 0.15)]
    assert [np.array_equal(f.image_bgr, img) for f, img in zip(frames, (small_still, small_still[:, ::-1], small_still[::-1]),
                                                                strict=True)] == [True, True, True]
    assert source.skipped == [Skip(2, "img3.jpg cannot be decoded as an image")]


def test_image_folder_with_fps_and_a_single_image(tmp_path: Path, small_still: np.ndarray) -> None:
    for i in range(3):
        cv2.imwrite(str(tmp_path / f"f{i}.bmp"), small_still)
    assert [f.t_s for f in open_source(tmp_path, fps=4.0).iter_frames()] == [0.0, 0.25, 0.5]
    single = open_source(tmp_path / "f1.bmp")
    assert single.kind == "images" and [f.record["file"] for f in single.iter_frames()] == ["f1.bmp"]


def test_an_image_removed_while_replaying_is_skipped(tmp_path: Path, small_still: np.ndarray) -> None:
    for i in range(3):
        cv2.imwrite(str(tmp_path / f"f{i}.png"), small_still)
    source = open_source(tmp_path)
    (tmp_path / "f1.png").unlink()
    assert [f.index for f in source.iter_frames()] == [0, 2]
    assert source.skipped == [Skip(1, "f1.png is missing")]


@pytest.mark.parametrize(
    ("files", "match"),
    [
        ({}, "no images"),
        ({"notes.txt": "x"}, "no images"),
        ({"drive.mp4": "x"}, "give the video file itself"),
        ({"catalog_0.catalog": "{}"}, "no manifest.json"),
        ({"meta.json": "{}", "record_0.json": "{}"}, "convert_to_tub_v2"),
    ],
)
def test_folders_without_frames_raise_with_advice(tmp_path: Path, files: dict[str, str], match: str) -> None:
    for name, text in files.items():
        (tmp_path / name).write_text(text)
    with pytest.raises(SourceError, match=match):
        open_source(tmp_path)


@given(st.lists(st.integers(0, 10**6), min_size=2, max_size=20, unique=True))
def test_natural_key_orders_numbers_by_value(numbers: list[int]) -> None:
    names = [f"img{n}.jpg" for n in numbers]
    assert sorted(names, key=natural_key) == [f"img{n}.jpg" for n in sorted(numbers)]


@pytest.fixture(scope="module")
def seven_images(tmp_path_factory: pytest.TempPathFactory) -> Path:
    folder = tmp_path_factory.mktemp("seven")
    for i in range(7):
        cv2.imwrite(str(folder / f"{i}.png"), np.full((4, 6, 3), i, np.uint8))
    return folder


@given(st.integers(0, 9), st.one_of(st.none(), st.integers(0, 9)), st.integers(1, 4))
def test_iter_frames_yields_exactly_the_requested_indices(seven_images: Path, start: int, stop_offset: int | None, every: int) -> None:
    stop = None if stop_offset is None else start + stop_offset
    source = open_source(seven_images)
    frames = list(source.iter_frames(start, stop, every))
    assert [f.index for f in frames] == list(range(start, 7 if stop is None else min(stop, 7), every))
    assert all(int(f.image_bgr[0, 0, 0]) == f.index for f in frames)  # the pixels belong to that index


# ---------------------------------------------------------------------------------------- Donkey tub


def make_tub(folder: Path, still: np.ndarray, n: int = 12, per_catalog: int = 8, deleted: tuple[int, ...] = (4,),
             missing_image: int = 7, malformed: int = 9) -> Path:
    """A Tub v2 as donkeycar's datastore_v2 writes it (\\r\\n line ends), with one deleted, one imageless and one cut record."""
    (folder / "images").mkdir(parents=True)
    catalogs: dict[int, list[str]] = {}
    for i in range(n):
        name = f"{i}_cam_image_array_.jpg"
        if i != missing_image:
            cv2.imwrite(str(folder / "images" / name), np.roll(still, 5 * i, axis=1))
        record = {"_index": i, "_session_id": "23-11-14_0", "_timestamp_ms": T0_MS + 50 * i, "cam/image_array": name,
                  "user/angle": round(-0.5 + i / 10, 3), "user/throttle": 0.3, "user/mode": "user"}
        line = json.dumps(record, sort_keys=True)
        catalogs.setdefault(i // per_catalog, []).append(line[: len(line) // 2] if i == malformed else line)
    for c, lines in catalogs.items():
        (folder / f"catalog_{c}.catalog").write_bytes("".join(f"{line}\r\n" for line in lines).encode())
        meta = {"created_at": 1700000000.0, "line_lengths": [len(line) + 2 for line in lines], "path": f"catalog_{c}.catalog_manifest",
                "start_index": c * per_catalog}
        (folder / f"catalog_{c}.catalog_manifest").write_bytes((json.dumps(meta, sort_keys=True) + "\r\n").encode())
    manifest = [
        ["cam/image_array", "user/angle", "user/throttle", "user/mode"],
        ["image_array", "float", "float", "str"],
        {},
        {"created_at": 1700000000.0, "sessions": {"all_full_ids": ["23-11-14_0"], "last_id": 0, "last_full_id": "23-11-14_0"}},
        {"paths": [f"catalog_{c}.catalog" for c in catalogs], "current_index": n, "max_len": per_catalog, "deleted_indexes": list(deleted)},
    ]
    (folder / "manifest.json").write_bytes("".join(json.dumps(x) + "\r\n" for x in manifest).encode())
    return folder


@pytest.fixture
def tub(tmp_path: Path, small_still: np.ndarray) -> Path:
    return make_tub(tmp_path / "tub_3_23-11-14", small_still)


def test_tub_yields_records_with_their_images_times_and_values(tub: Path) -> None:
    source = open_source(tub)
    assert (source.kind, source.expected_frames, source.frame_size) == ("tub", 11, (160, 120))
    assert source.fps == pytest.approx(20.0) and "estimated" in source.notes[0]
    frames = list(source.iter_frames())
    assert [f.index for f in frames] == [0, 1, 2, 3, 5, 6, 8, 10, 11]  # 4 deleted, 7 and 9 skipped
    assert [f.t_s for f in frames] == pytest.approx([0.05 * f.index for f in frames])
    assert all(np.array_equal(f.image_bgr, cv2.imread(str(tub / "images" / f"{f.index}_cam_image_array_.jpg"))) for f in frames)
    assert dict(frames[4].record) == {"_index": 5, "_session_id": "23-11-14_0", "_timestamp_ms": T0_MS + 250, "user/angle": 0.0,
                                      "user/throttle": 0.3, "user/mode": "user"}
    assert [s.index for s in source.skipped] == [7, 9]
    assert "images/7_cam_image_array_.jpg is missing" in source.skipped[0].reason
    assert source.skipped[1].reason.startswith("catalog_1.catalog line 2: not valid JSON")
    assert source.stopped_early is None


def test_tub_start_stop_every_count_tub_indexes(tub: Path) -> None:
    source = open_source(tub / "manifest.json")  # the manifest itself also opens the tub
    assert [f.index for f in source.iter_frames(start=1, every=3)] == [1, 10]  # 4 deleted (not a skip), 7 has no image
    assert source.skipped == [Skip(7, "images/7_cam_image_array_.jpg is missing (catalog_0.catalog line 8)")]
    assert [f.index for f in source.iter_frames(start=8, stop=11)] == [8, 10]
    assert [s.index for s in source.skipped] == [9]  # reset for each iteration


def test_tub_time_is_relative_to_the_first_record_even_when_it_is_deleted(tmp_path: Path, small_still: np.ndarray) -> None:
    source = open_source(make_tub(tmp_path / "t", small_still, deleted=(0, 1)))
    assert next(iter(source.iter_frames())).t_s == pytest.approx(0.1)


def edit_manifest(tub: Path, line: int, text: str) -> None:
    lines = (tub / "manifest.json").read_text().splitlines()
    lines[line - 1] = text
    (tub / "manifest.json").write_text("\n".join(lines) + "\n")


@pytest.mark.parametrize(
    ("line", "text", "match"),
    [
        (1, '["cam/image_array", "user/angle"', r"manifest.json, line 1: not valid JSON"),
        (2, '["image_array", "float"]', r"line 2: expected a JSON list of 4 type names"),
        (2, '["float", "float", "float", "str"]', r"no input of type 'image_array'"),
        (5, '{"paths": [], "deleted_indexes": []}', r"line 5 'paths'"),
        (5, '{"paths": ["catalog_0.catalog", "catalog_7.catalog"], "deleted_indexes": []}', r"catalog_7.catalog is missing"),
        (5, '{"paths": ["catalog_0.catalog"], "deleted_indexes": "4"}', r"line 5 'deleted_indexes'"),
    ],
)
def test_a_broken_tub_manifest_raises_naming_the_line(tub: Path, line: int, text: str, match: str) -> None:
    edit_manifest(tub, line, text)
    with pytest.raises(SourceError, match=match):
        open_source(tub)


def test_a_tub_without_its_images_folder_raises(tub: Path) -> None:
    shutil.rmtree(tub / "images")
    with pytest.raises(SourceError, match="no images/ folder"):
        open_source(tub)


# ----------------------------------------------------------------------------------- --from / --to


@pytest.mark.parametrize(
    ("text", "fps", "index"),
    [("12.5s", 20.0, 250), ("12.5", 20.0, 250), (" 12.5 S ", 20.0, 250), ("300f", 25.0, 300), ("300F", 0.0, 300), ("0", 25.0, 0),
     ("0.28s", 25.0, 7), ("1.01", 25.0, 26), (".5", 10.0, 5), ("7.", 2.0, 14)],
)
def test_parse_position_examples(text: str, fps: float, index: int) -> None:
    assert parse_position(text, fps) == index


@pytest.mark.parametrize("text", ["", "abc", "-1s", "12.5f", "1e3", "12,5", "1:30", "s", "f"])
def test_parse_position_rejects_bad_text_listing_the_forms(text: str) -> None:
    with pytest.raises(SourceError, match=r"'12.5s' or '12.5'.*'300f'"):
        parse_position(text, 25.0)


def test_parse_position_in_seconds_needs_a_frame_rate() -> None:
    with pytest.raises(SourceError, match="frame rate"):
        parse_position("2s", math.nan)


@given(st.integers(0, 10**7), st.floats(0.5, 240.0))
def test_parse_position_seconds_picks_the_first_frame_at_or_after(millis: int, fps: float) -> None:
    seconds = millis / 1000.0
    index = parse_position(f"{seconds:.3f}s", fps)
    assert (index - 1) / fps < seconds + 1e-6 / fps  # the frame before is earlier
    assert index / fps >= seconds - 1e-6 / fps  # this frame is not earlier


@given(st.integers(0, 10**9))
def test_parse_position_frames_round_trip(n: int) -> None:
    assert parse_position(f"{n}f", 25.0) == n
