"""Annotated videos that play anywhere and survive a killed run.

Two writers, chosen by ``open_video``:

- **H.264 in fragmented MP4** (``.mp4``) through PyAV (``pip install 'fearguard[video]'``): browsers,
  notebooks and editor previews play it. Every frame is its own fragment (``movflags=frag_every_frame+
  empty_moov+default_base_moof``, ``flush_packets=1``), so the file on disk is a playable video after
  every frame: a run killed with SIGKILL keeps all frames but the one being muxed (measured: a copy taken
  after frame N decodes N − 1 frames). OpenCV's writer cannot make fragmented MP4 (a killed run's
  ``mp4v`` file has no ``moov`` atom and does not play at all), hence the library.
- **Motion JPEG in AVI** (``.avi``) through OpenCV, when PyAV is missing: plays in VLC, mpv, ffplay and
  OpenCV; an AVI needs no index to be read, so a truncated file still decodes up to its last complete
  frame. OpenCV buffers its output, so a SIGKILL loses the frames still in that buffer (about 1 MiB);
  SIGINT and SIGTERM close the file properly and lose nothing.

Frames of another size than the first are scaled to the first frame's size (``rescaled`` counts them),
so no frame is dropped silently; H.264 needs even sides, so an odd first size is rounded down by one pixel.
"""

from __future__ import annotations

import importlib.util
from abc import ABC, abstractmethod
from fractions import Fraction
from pathlib import Path
from typing import Any, Protocol

import cv2
import numpy as np

DEFAULT_FPS = 20.0  # [Hz] used when the caller's rate is not a positive number
H264_OPTIONS = {"preset": "veryfast", "crf": "23", "tune": "zerolatency"}  # zerolatency: no frame held back by the encoder
MP4_OPTIONS = {"movflags": "frag_every_frame+empty_moov+default_base_moof", "flush_packets": "1"}
KINDS = ("h264", "mjpg")


class VideoSink(Protocol):
    """What the recorder writes frames to."""

    path: Path
    kind: str
    frames: int
    rescaled: int

    def write(self, frame_bgr: np.ndarray) -> None: ...

    def close(self) -> None: ...


def h264_available() -> bool:
    """True when PyAV (the ``video`` extra) is installed."""
    return importlib.util.find_spec("av") is not None


def open_video(stem: str | Path, fps: float, kind: str | None = None) -> VideoSink:
    """A writer for ``stem`` + ``.mp4`` (H.264, when PyAV is installed) or ``.avi`` (MJPG); ``kind`` forces one."""
    chosen = kind or ("h264" if h264_available() else "mjpg")
    if chosen not in KINDS:
        raise ValueError(f"unknown video kind {chosen!r}; choose one of {', '.join(KINDS)}")
    rate = fps if isinstance(fps, int | float) and fps > 0 else DEFAULT_FPS
    stem = Path(stem)
    if chosen == "h264":
        return H264Writer(stem.with_suffix(".mp4"), rate)
    return MjpgWriter(stem.with_suffix(".avi"), rate)


class _Sized(ABC):
    """Opens on the first frame (its size fixes the video's); later frames of another size are scaled to it."""

    even = False

    def __init__(self, path: Path, fps: float) -> None:
        self.path, self.fps = path, fps
        self.frames = 0
        self.rescaled = 0
        self.size: tuple[int, int] | None = None  # (width_px, height_px)

    def write(self, frame_bgr: np.ndarray) -> None:
        image = frame_bgr if frame_bgr.ndim == 3 else cv2.cvtColor(frame_bgr, cv2.COLOR_GRAY2BGR)
        h, w = image.shape[:2]
        if self.size is None:
            self.size = (w - w % 2, h - h % 2) if self.even else (w, h)
            self._open(*self.size)
        if (w, h) != self.size:
            if (w - w % 2, h - h % 2) == self.size:  # an odd side trimmed by one pixel: crop, do not blur
                image = image[: self.size[1], : self.size[0]]
            else:
                image = cv2.resize(image, self.size, interpolation=cv2.INTER_AREA)
                self.rescaled += 1
        self._write(np.ascontiguousarray(image))
        self.frames += 1

    @abstractmethod
    def _open(self, width_px: int, height_px: int) -> None:
        """Create the file for frames of this size."""

    @abstractmethod
    def _write(self, image: np.ndarray) -> None:
        """Append one BGR frame of the video's size."""

    @abstractmethod
    def close(self) -> None:
        """Finish the file (safe to call twice, and before any frame)."""


class H264Writer(_Sized):
    """H.264 (yuv420p) in a fragmented MP4, one fragment per frame (PyAV)."""

    kind = "h264"
    even = True

    def __init__(self, path: Path, fps: float) -> None:
        super().__init__(path, fps)
        self._container: Any = None
        self._stream: Any = None

    def _open(self, width_px: int, height_px: int) -> None:
        import av  # the optional ``video`` extra: imported only when an H.264 video is written

        self._av = av
        self._container = av.open(str(self.path), "w", format="mp4", options=MP4_OPTIONS)
        self._stream = self._container.add_stream("libx264", rate=Fraction(self.fps).limit_denominator(1001))
        self._stream.width, self._stream.height, self._stream.pix_fmt = width_px, height_px, "yuv420p"
        self._stream.options = dict(H264_OPTIONS)

    def _write(self, image: np.ndarray) -> None:
        frame = self._av.VideoFrame.from_ndarray(image, format="bgr24")
        self._container.mux(self._stream.encode(frame))

    def close(self) -> None:
        if self._container is not None:
            container, self._container = self._container, None
            try:
                container.mux(self._stream.encode(None))  # flush the encoder
            finally:
                container.close()


class MjpgWriter(_Sized):
    """Motion JPEG in AVI through OpenCV (no extra dependency; survives truncation up to OpenCV's buffer)."""

    kind = "mjpg"

    def __init__(self, path: Path, fps: float) -> None:
        super().__init__(path, fps)
        self._writer: cv2.VideoWriter | None = None

    def _open(self, width_px: int, height_px: int) -> None:
        self._writer = cv2.VideoWriter(str(self.path), cv2.VideoWriter_fourcc(*"MJPG"), self.fps, (width_px, height_px))

    def _write(self, image: np.ndarray) -> None:
        assert self._writer is not None
        self._writer.write(image)

    def close(self) -> None:
        if self._writer is not None:
            self._writer.release()
            self._writer = None


def count_frames(path: str | Path) -> int:
    """How many frames OpenCV decodes from a video file (0 for a missing or unreadable file)."""
    cap = cv2.VideoCapture(str(path))
    n = 0
    try:
        while cap.isOpened() and cap.read()[0]:
            n += 1
    finally:
        cap.release()
    return n
