"""Frames from recordings: a video file, a folder of images, or a Donkey Car tub (Tub v2).

``open_source(path)`` detects the kind; ``FrameSource.iter_frames(start, stop, every)`` yields ``Frame``
values (index in the recording, ``t_s``, BGR image, per-frame record). Recordings are read robustly:
a frame that cannot be read becomes a ``Skip`` with a reason, a video that ends before its header says
it should sets ``stopped_early``, and everything that does decode is still yielded. Only problems that
make the whole recording unusable (missing path, a format OpenCV cannot decode, an empty folder, a broken
tub manifest) raise ``SourceError``, whose message says what to do.

Video frame indices follow the stream's timestamps after a read error, so a frame lost to corrupt data
shifts neither the indices nor ``t_s`` of the frames after it.
"""

from __future__ import annotations

import math
import os
import re
import statistics
from abc import ABC, abstractmethod
from collections.abc import Generator, Iterator, Mapping
from dataclasses import dataclass, field
from itertools import pairwise
from pathlib import Path
from types import MappingProxyType
from typing import TYPE_CHECKING, Any, ClassVar

import cv2
import numpy as np

from fearguard.errors import SourceError
from fearguard.files.reader import loads_json
from fearguard.readings import finite_reading, whole_number

if TYPE_CHECKING:
    from fearguard.replay.sensor_log import Readings

DEFAULT_FPS = 20.0  # [Hz] frame rate assumed when none is known (Donkey Car's default DRIVE_LOOP_HZ)
MAX_PLAUSIBLE_FPS = 1000.0  # [Hz] a container frame rate above this (or ≤ 0, NaN) is treated as missing
MIN_RETRY_READS = 16  # [reads] failed reads tried in a row past a bad spot before the video is declared over
FPS_ESTIMATE_RECORDS = 200  # [records] tub records whose _timestamp_ms intervals estimate the frame rate
IMAGE_SUFFIXES = (".jpg", ".jpeg", ".png", ".bmp")
VIDEO_SUFFIXES = (".mp4", ".m4v", ".mov", ".avi", ".mkv", ".webm", ".h264", ".mjpeg")
TUB_IMAGE_TYPES = ("image_array",)  # Tub v2 input types whose value is an image file name in images/
_EMPTY_RECORD: Mapping[str, Any] = MappingProxyType({})
_DONKEY_ANGLE = "Donkey angle [-1..1], -1 = full left, + = right (fearguard's steering_deg: degrees, + = left)"
_DONKEY_THROTTLE = "Donkey throttle [-1..1], the fraction of full throttle (not a speed); < 0 brakes or reverses"
# a tub channel → (its replay-log key, units and sign); pilot/* is what drove an autopilot tub (user/mode "local")
TUB_COMMANDS: Mapping[str, tuple[str, str]] = MappingProxyType({
    "user/angle": ("user_angle_donkey", f"{_DONKEY_ANGLE}; what the user commanded"),
    "user/throttle": ("user_throttle_donkey", f"{_DONKEY_THROTTLE}; what the user commanded"),
    "pilot/angle": ("pilot_angle_donkey", f"{_DONKEY_ANGLE}; what the autopilot commanded"),
    "pilot/throttle": ("pilot_throttle_donkey", f"{_DONKEY_THROTTLE}; what the autopilot commanded"),
    "user/mode": ("user_mode_donkey", "Donkey drive mode: 'user' (user/* drove), 'local_angle' (pilot/angle steered, "
                                     "user/throttle), 'local' (pilot/* drove)"),
})
_CONVERT_ADVICE = "convert it with `ffmpeg -i {src} -c:v libx264 -pix_fmt yuv420p out.mp4`"


@dataclass(frozen=True, eq=False)  # eq=False: holds an image, so compared by identity
class Frame:
    """One recorded frame: its index in the recording, its time, its pixels and extra per-frame data."""

    index: int
    t_s: float
    image_bgr: np.ndarray  # uint8, H×W×3
    record: Mapping[str, Any]  # e.g. a tub's user/angle, user/throttle; an image folder's file name
    log_fields: Mapping[str, Any] = field(default_factory=lambda: _EMPTY_RECORD)  # added to the replay log (TUB_COMMANDS)
    source_frame: int | str | None = None  # the picture in the recording: video frame, image file, tub index, bag stamp [ns]
    stamp_ns: int | None = None  # [ns] the recording's own clock (a bag's receive time, a tub's _timestamp_ms), None: none


@dataclass(frozen=True)
class Skip:
    """A frame that was wanted but could not be read; ``index`` is None when it is not known."""

    index: int | None
    reason: str


class FrameSource(ABC):
    """A recording to iterate: ``skipped`` and ``stopped_early`` describe the latest ``iter_frames`` run."""

    kind: ClassVar[str]

    def __init__(
        self, path: Path, fps: float, expected_frames: int | None, frame_size: tuple[int, int] | None, notes: list[str],
    ) -> None:
        self.path = path
        self.fps = fps  # [Hz] used for t_s where the recording has no clock, and by parse_position
        self.expected_frames = expected_frames  # frames the recording should hold (header/manifest), None if unknown
        self.frame_size = frame_size  # (width_px, height_px) of the first frame, None if unknown
        self.notes: tuple[str, ...] = tuple(notes)  # assumptions made while opening (default fps, fallbacks)
        self.skipped: list[Skip] = []
        self.stopped_early: str | None = None
        self.log_field_units: Mapping[str, str] = _EMPTY_RECORD  # units and sign of each field a Frame adds to the log
        self.sensors: Readings | None = None  # sensor readings the recording carries itself (a bag's Range, Odometry, ...)

    def iter_frames(self, start: int = 0, stop: int | None = None, every: int = 1) -> Generator[Frame, None, None]:
        """Frames with start ≤ index < stop, every ``every``-th; resets ``skipped`` and ``stopped_early``."""
        if not (_is_int(start) and start >= 0):
            raise SourceError(self.path, "start", f"must be a frame index ≥ 0, got {start!r}")
        if stop is not None and not (_is_int(stop) and stop >= start):
            raise SourceError(self.path, "stop", f"must be a frame index ≥ start ({start}), got {stop!r}: --from must come before --to")
        if not (_is_int(every) and every >= 1):
            raise SourceError(self.path, "every", f"must be a whole number ≥ 1, got {every!r}")
        self.skipped = []
        self.stopped_early = None
        return self._frames(start, stop, every)

    @abstractmethod
    def _frames(self, start: int, stop: int | None, every: int) -> Generator[Frame, None, None]:
        """The kind-specific iteration; arguments are already checked."""

    def _skip(self, index: int | None, reason: str) -> None:
        self.skipped.append(Skip(index, reason))

    def __repr__(self) -> str:
        size = f"{self.frame_size[0]}x{self.frame_size[1]}" if self.frame_size else "size unknown"
        return f"<{type(self).__name__} {self.path} {self.expected_frames} frames {size} at {self.fps:g} Hz>"


def _is_int(value: object) -> bool:
    return whole_number(value) is not None


def _sampled(index: int, start: int, stop: int | None, every: int) -> bool:
    return index >= start and (stop is None or index < stop) and (index - start) % every == 0


# --------------------------------------------------------------------------------------------- video


class VideoSource(FrameSource):
    """A video file decoded by OpenCV (FFmpeg backend); t_s = index / fps."""

    kind = "video"

    def __init__(self, path: Path, fps: float | None) -> None:
        cap = cv2.VideoCapture(str(path))
        try:
            if not cap.isOpened():
                raise SourceError(path, "", f"OpenCV cannot open or decode this file as a video; {_CONVERT_ADVICE.format(src=path)}")
            ok = cap.grab()
            ok, first = cap.retrieve() if ok else (False, None)
            if not ok or first is None:
                raise SourceError(
                    path, "", f"OpenCV opened the file but cannot decode its first frame (codec not supported, or the file "
                    f"starts corrupt); {_CONVERT_ADVICE.format(src=path)}",
                )
            file_fps = cap.get(cv2.CAP_PROP_FPS)
            count = cap.get(cv2.CAP_PROP_FRAME_COUNT)
        finally:
            cap.release()
        notes: list[str] = []
        self.file_fps = file_fps  # [Hz] the container's rate: maps frame timestamps to indices
        self.file_fps_ok = math.isfinite(file_fps) and 0.0 < file_fps <= MAX_PLAUSIBLE_FPS
        if fps is not None:
            if self.file_fps_ok and not math.isclose(fps, file_fps):
                notes.append(f"fps={fps:g} given: overrides the file's {file_fps:g} Hz for t_s")
            self.clock_fps: float | None = fps
        elif self.file_fps_ok:
            self.clock_fps = file_fps
        else:
            self.clock_fps = None
            notes.append(
                f"the file reports a frame rate of {file_fps!r}: t_s comes from frame timestamps (CAP_PROP_POS_MSEC); "
                f"--from/--to in seconds assume {DEFAULT_FPS:g} Hz",
            )
        expected = int(count) if math.isfinite(count) and count >= 1 else None
        height, width = first.shape[:2]
        super().__init__(path, self.clock_fps or DEFAULT_FPS, expected, (int(width), int(height)), notes)

    def _retry_budget(self, next_index: int) -> int:
        """Failed reads to try in a row: enough to pass a corrupt stretch, or to reach the expected end (~15 µs each there)."""
        if self.expected_frames is None:
            return MIN_RETRY_READS
        if next_index >= self.expected_frames:
            return 0
        return max(MIN_RETRY_READS, self.expected_frames - next_index)

    def _stream_index(self, cap: cv2.VideoCapture) -> int | None:
        """Index of the frame just grabbed, from its timestamp (None without a usable file frame rate)."""
        if not self.file_fps_ok:
            return None
        msec = cap.get(cv2.CAP_PROP_POS_MSEC)
        if not math.isfinite(msec) or msec < 0:
            return None
        return round(msec * self.file_fps / 1000.0)

    def _frames(self, start: int, stop: int | None, every: int) -> Generator[Frame, None, None]:
        cap = cv2.VideoCapture(str(self.path))
        try:
            next_index = 0  # index the next successful read should have
            if start > 0 and self.file_fps_ok and cap.set(cv2.CAP_PROP_POS_FRAMES, start):
                next_index = start  # exact on the H.264 files tested; checked below by the first frame's timestamp
            check_seek = next_index > 0
            failed = 0  # failed reads in a row
            while stop is None or next_index < stop:
                if not cap.grab():
                    failed += 1
                    if failed > self._retry_budget(next_index):
                        if self.expected_frames is not None and next_index < self.expected_frames:
                            self.stopped_early = (
                                f"video ended at frame {next_index} of {self.expected_frames} expected: file truncated or corrupt "
                                f"({self.expected_frames - next_index} frames not read)"
                            )
                        return
                    continue
                index, stream_index = next_index, self._stream_index(cap)
                if check_seek:
                    check_seek = False
                    if stream_index is None or stream_index > start:  # cannot confirm, or overshot: read forward from 0
                        cap.release()
                        cap = cv2.VideoCapture(str(self.path))
                        next_index = 0
                        continue
                    index = stream_index
                elif failed:
                    if stream_index is not None and stream_index >= index:
                        index = stream_index  # frames next_index..stream_index-1 were lost to the bad data
                    else:  # no usable timestamps: the loss cannot be measured
                        lost_note = f"{failed} failed reads before frame {index}: an unknown number of frames lost"
                        self._skip(None, f"{lost_note}, later indices may be early")
                    for lost in range(next_index, index):
                        if _sampled(lost, start, stop, every):
                            self._skip(lost, "lost to corrupt data: the decoder could not read it")
                failed = 0
                next_index = index + 1
                if stop is not None and index >= stop:
                    return
                if not _sampled(index, start, stop, every):
                    continue  # grabbed only: not converted to BGR
                ok, image = cap.retrieve()
                if not ok or image is None:
                    self._skip(index, "read but could not be converted to a BGR image")
                    continue
                t_s = index / self.clock_fps if self.clock_fps else cap.get(cv2.CAP_PROP_POS_MSEC) / 1000.0
                yield Frame(index, t_s, image, _EMPTY_RECORD, source_frame=index)
        finally:
            cap.release()


# ------------------------------------------------------------------------------------- image folder


def natural_key(name: str) -> tuple[tuple[int, int | str], ...]:
    """Sort key that orders embedded numbers by value, so ``img2`` < ``img10``."""
    return tuple((0, int(part)) if part.isdigit() else (1, part) for part in re.split(r"(\d+)", name.casefold()) if part)


def _read_image(path: Path) -> tuple[np.ndarray | None, str]:
    """Decode an image file to 8-bit BGR, or (None, why not)."""
    try:
        data = np.fromfile(path, dtype=np.uint8)  # fromfile + imdecode: cv2.imread fails on non-ASCII paths on Windows
    except OSError as exc:  # also a name too long to exist: asking path.exists() would raise again
        return None, "is missing" if isinstance(exc, FileNotFoundError) else f"cannot be read ({exc.strerror})"
    if data.size == 0:
        return None, "is empty"
    image = cv2.imdecode(data, cv2.IMREAD_COLOR)
    if image is None:
        return None, "cannot be decoded as an image"
    return image, ""


class ImageFolderSource(FrameSource):
    """Images in one folder (jpg, jpeg, png, bmp), natural-sorted by name; t_s = index / fps."""

    kind = "images"

    def __init__(self, path: Path, files: list[Path], fps: float | None) -> None:
        self.files = tuple(files)
        notes = [] if fps is not None else [f"no fps given: assuming {DEFAULT_FPS:g} Hz for t_s (pass fps to change)"]
        size = None
        for file in self.files[:5]:
            image, _ = _read_image(file)
            if image is not None:
                size = (int(image.shape[1]), int(image.shape[0]))
                break
        super().__init__(path, fps or DEFAULT_FPS, len(self.files), size, notes)

    def _frames(self, start: int, stop: int | None, every: int) -> Generator[Frame, None, None]:
        end = len(self.files) if stop is None else min(stop, len(self.files))
        for index in range(start, end, every):
            file = self.files[index]
            image, why = _read_image(file)
            if image is None:
                self._skip(index, f"{file.name} {why}")
                continue
            yield Frame(index, index / self.fps, image, MappingProxyType({"file": file.name}), source_frame=file.name)


# ---------------------------------------------------------------------------------------- Donkey tub


class TubSource(FrameSource):
    """A Donkey Car Tub v2 folder (donkeycar ≥ 4): manifest.json, catalog_N.catalog, images/."""

    kind = "tub"

    def __init__(self, path: Path, fps: float | None) -> None:
        manifest = path / "manifest.json"
        inputs, types, catalog_meta = _read_manifest(manifest)
        image_keys = [name for name, kind in zip(inputs, types, strict=True) if kind in TUB_IMAGE_TYPES]
        if not image_keys:
            raise SourceError(manifest, "lines 1-2", f"no input of type 'image_array' among {inputs}: this tub holds no camera images")
        self.image_key = "cam/image_array" if "cam/image_array" in image_keys else image_keys[0]
        self.image_keys = frozenset(image_keys)
        self.deleted_indexes = frozenset(catalog_meta.get("deleted_indexes", []))
        self.catalogs = tuple(path / name for name in catalog_meta["paths"])
        for catalog in self.catalogs:
            if not catalog.is_file():
                raise SourceError(manifest, "line 5 'paths'", f"catalog {catalog.name} is missing from the tub folder; copy the whole tub")
        self.images_dir = path / "images"
        if not self.images_dir.is_dir():
            raise SourceError(path, "images/", "the tub has no images/ folder; copy the whole tub")
        current = catalog_meta.get("current_index")
        expected = current - sum(1 for i in self.deleted_indexes if 0 <= i < current) if _is_int(current) else None

        stamps: list[float] = []
        size = None
        for _, _, record in self._lines():
            if isinstance(record, dict):
                stamp = _timestamp_ms(record)
                if stamp is not None:
                    stamps.append(stamp)
                name = record.get(self.image_key)
                where = self._image_path(name) if size is None and isinstance(name, str) else None
                if where is not None:
                    image, _ = _read_image(where)
                    size = None if image is None else (int(image.shape[1]), int(image.shape[0]))
            if len(stamps) >= FPS_ESTIMATE_RECORDS:
                break
        self.t0_ms = stamps[0] if stamps else 0.0  # t_s = 0 at the tub's first record (deleted or not)
        notes: list[str] = []
        fps = fps if fps is not None else estimate_fps(stamps, 1000.0, "_timestamp_ms", "no usable _timestamp_ms", notes)
        super().__init__(path, fps, expected, size, notes)
        self.log_field_units = MappingProxyType({key: meaning for channel, (key, meaning) in TUB_COMMANDS.items() if channel in inputs})

    def _image_path(self, name: str) -> Path | None:
        """The image a record names, inside the tub; None for a name that points outside it (absolute, ``..``)."""
        parts = Path(name.replace("\\", "/")).parts
        if not parts or Path(name).is_absolute() or name.startswith(("/", "\\")) or ".." in parts or ":" in parts[0]:
            return None
        inside = self.images_dir / name
        if not os.path.exists(inside) and "/" in name:  # e.g. "images/0_cam_image_array_.jpg"; False for a too-long name
            return self.path / name
        return inside

    def _lines(self) -> Iterator[tuple[str, int, object]]:
        """(catalog name, 1-based line number, parsed JSON or the error text) for every non-blank catalog line."""
        for catalog in self.catalogs:
            with catalog.open(encoding="utf-8", errors="replace") as fh:  # donkeycar ends lines with \r\n
                for number, line in enumerate(fh, start=1):
                    if not line.strip():
                        continue
                    try:
                        yield catalog.name, number, loads_json(line)
                    except ValueError as exc:
                        yield catalog.name, number, f"not valid JSON ({exc})"

    def _frames(self, start: int, stop: int | None, every: int) -> Generator[Frame, None, None]:
        position = 0
        for catalog, number, record in self._lines():
            index, position = position, position + 1  # Tub v2 record index = position over all catalog lines
            if not isinstance(record, dict):
                why = record if isinstance(record, str) else "not a JSON object"
                if _sampled(index, start, stop, every):
                    self._skip(index, f"{catalog} line {number}: {why}; record skipped")
                continue
            if _is_int(record.get("_index")):
                index = int(record["_index"])
            if index in self.deleted_indexes:
                continue
            if stop is not None and index >= stop:
                return
            if not _sampled(index, start, stop, every):
                continue
            stamp = _timestamp_ms(record)
            if stamp is None:
                self._skip(index, f"{catalog} line {number}: no numeric _timestamp_ms; record skipped")
                continue
            name = record.get(self.image_key)
            if not isinstance(name, str) or not name:
                self._skip(index, f"{catalog} line {number}: no image file name under {self.image_key!r}")
                continue
            image_path = self._image_path(name)
            if image_path is None:
                self._skip(index, f"{catalog} line {number}: image name {name!r} points outside the tub (absolute or '..'); "
                                  "record skipped")
                continue
            image, why = _read_image(image_path)
            if image is None:
                self._skip(index, f"{image_path.relative_to(self.path)} {why} ({catalog} line {number})")
                continue
            extra = MappingProxyType({k: v for k, v in record.items() if k not in self.image_keys})
            yield Frame(index, (stamp - self.t0_ms) / 1000.0, image, extra, _tub_log_fields(record), source_frame=index,
                        stamp_ns=round(stamp * 1000) * 1000)  # via µs: an epoch in ns (~1.7e18) is beyond a float's 2**53


def estimate_fps(stamps: list[float] | list[int], units_per_s: float, source: str, without: str, notes: list[str]) -> float:
    """A recording's frame rate from its stamps: 1 / the median increasing interval (noted, naming ``source``), or
    DEFAULT_FPS when there is none (noted, saying ``without``); used by --from/--to in seconds."""
    steps = [b - a for a, b in pairwise(stamps) if b > a]
    if steps:
        fps = units_per_s / statistics.median(steps)
        notes.append(f"frame rate {fps:.3g} Hz estimated from {source} (median interval); used by --from/--to in seconds")
        return fps
    notes.append(f"{without} to estimate the frame rate: --from/--to in seconds assume {DEFAULT_FPS:g} Hz")
    return DEFAULT_FPS


def _tub_log_fields(record: Mapping[str, Any]) -> Mapping[str, Any]:
    """What a tub record adds to the replay log: the recorded commands, in Donkey units under names that say so
    (TUB_COMMANDS), kept apart from fearguard's degrees; a value that is not a finite number (a pilot's None in
    user mode) is logged as null."""
    fields: dict[str, Any] = {}
    for channel, (key, _meaning) in TUB_COMMANDS.items():
        if channel in record:
            value = record[channel]
            fields[key] = value if isinstance(value, str) and channel == "user/mode" else finite_reading(value)
    return MappingProxyType(fields) if fields else _EMPTY_RECORD


def _timestamp_ms(record: Mapping[str, Any]) -> float | None:
    stamp = record.get("_timestamp_ms")
    return finite_reading(stamp)


def _read_manifest(manifest: Path) -> tuple[list[str], list[str], dict[str, Any]]:
    """Lines 1, 2 and 5 of a Tub v2 manifest.json; anything else wrong raises SourceError naming the line."""
    try:
        lines = [line for line in manifest.read_text(encoding="utf-8").splitlines() if line.strip()]
    except (OSError, UnicodeDecodeError) as exc:
        raise SourceError(manifest, "", f"cannot read it ({exc})") from exc
    hint = "expected a Donkey Car Tub v2 manifest (5 JSON lines: inputs, types, metadata, manifest metadata, catalogs)"
    if len(lines) < 5:
        raise SourceError(manifest, "", f"has {len(lines)} non-blank lines; {hint}")
    parsed: list[object] = []
    for number in (1, 2, 5):
        try:
            parsed.append(loads_json(lines[number - 1]))
        except ValueError as exc:
            raise SourceError(manifest, f"line {number}", f"not valid JSON ({exc}); {hint}") from exc
    inputs, types, meta = parsed
    if not (isinstance(inputs, list) and all(isinstance(x, str) for x in inputs)):
        raise SourceError(manifest, "line 1", f"expected a JSON list of input names, got {lines[0][:80]!r}")
    if not (isinstance(types, list) and all(isinstance(x, str) for x in types) and len(types) == len(inputs)):
        raise SourceError(manifest, "line 2", f"expected a JSON list of {len(inputs)} type names (one per input), got {lines[1][:80]!r}")
    if not isinstance(meta, dict):
        raise SourceError(manifest, "line 5", f"expected a JSON object with 'paths' and 'deleted_indexes'; {hint}")
    paths = meta.get("paths")
    if not (isinstance(paths, list) and paths and all(isinstance(p, str) and p and Path(p).name == p for p in paths)):
        raise SourceError(manifest, "line 5 'paths'", f"expected a non-empty list of catalog file names, got {paths!r}")
    deleted = meta.get("deleted_indexes", [])
    if not (isinstance(deleted, list) and all(_is_int(i) for i in deleted)):
        raise SourceError(manifest, "line 5 'deleted_indexes'", f"expected a list of record indexes, got {deleted!r}")
    return inputs, types, meta


# ------------------------------------------------------------------------------------------ opening


def open_source(path: str | Path, fps: float | None = None) -> FrameSource:
    """Open a video file, a folder of images, or a Donkey Car tub folder (detected from what is there); ROS bags too:
    ``replay.recordings.open_recording``."""
    path = Path(path)
    if fps is not None and not ((finite_reading(fps) or 0.0) > 0):
        raise SourceError(path, "fps", f"must be a positive number of frames per second, got {fps!r}")
    if not path.exists():
        raise SourceError(path, "", "no such file or folder; give a video file, a folder of images, or a Donkey Car tub folder")
    if path.is_file() and path.name == "manifest.json":
        path = path.parent  # the tub's manifest was given: open the tub
    if path.is_dir():
        if (path / "manifest.json").is_file():
            return TubSource(path, fps)
        return ImageFolderSource(path, _image_files(path), fps)
    if path.suffix.lower() in IMAGE_SUFFIXES:
        return ImageFolderSource(path, [path], fps)
    return VideoSource(path, fps)


def _image_files(folder: Path) -> list[Path]:
    """Image files directly in ``folder`` in natural order (hidden files such as macOS ``._x.jpg`` left out)."""
    entries = [p for p in folder.iterdir() if p.is_file() and not p.name.startswith(".")]
    images = sorted((p for p in entries if p.suffix.lower() in IMAGE_SUFFIXES), key=lambda p: (natural_key(p.name), p.name))
    if images:
        return images
    videos = [p.name for p in entries if p.suffix.lower() in VIDEO_SUFFIXES]
    if videos:
        raise SourceError(folder, "", f"no images here but a video ({', '.join(sorted(videos)[:3])}); give the video file itself")
    if any(p.name.startswith("catalog_") and p.suffix == ".catalog" for p in entries):
        raise SourceError(folder, "manifest.json", "tub catalogs but no manifest.json; copy the whole Donkey Car tub folder")
    if (folder / "meta.json").is_file() and any(p.name.startswith("record_") for p in entries):
        raise SourceError(
            folder, "", "a Donkey Car Tub v1 (donkeycar 3.x), which is not supported; convert it with donkeycar's "
            "`python scripts/convert_to_tub_v2.py --tub=<this folder> --output=<new folder>`",
        )
    raise SourceError(folder, "", f"no images ({', '.join('*' + s for s in IMAGE_SUFFIXES)}) in this folder; is it the right one?")


_POSITION = re.compile(r"(?:(?P<frames>\d+)\s*f|(?P<seconds>\d+(?:\.\d*)?|\.\d+)\s*s?)", re.IGNORECASE)


POSITION_FORMS = "use seconds ('12.5s' or '12.5') or a frame number ('300f')"


def position_form_ok(text: object) -> bool:
    """Whether ``text`` reads as a position (the form only; whether it lies inside a recording needs the recording)."""
    return isinstance(text, str) and _POSITION.fullmatch(text.strip()) is not None


def parse_position(text: str, fps: float) -> int:
    """Frame index for ``--from/--to``: seconds ("12.5s" or "12.5") → first frame at or after it; frames ("300f")."""
    forms = POSITION_FORMS
    match = _POSITION.fullmatch(text.strip()) if isinstance(text, str) else None
    if match is None:
        raise SourceError(None, "", f"cannot read position {text!r}: {forms}")
    if match["frames"] is not None:
        return int(match["frames"])
    if not (isinstance(fps, int | float) and math.isfinite(fps) and fps > 0):
        raise SourceError(None, "", f"position {text!r} is in seconds but the frame rate {fps!r} is unknown; give frames ('300f')")
    frames = float(match["seconds"]) * fps
    if not math.isfinite(frames):
        raise SourceError(None, "", f"position {text!r} is too large: {forms}")
    return math.ceil(round(frames, 6))  # round first: 0.28 s × 25 Hz = 7.000000000000001 must be frame 7
