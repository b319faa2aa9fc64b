"""Annotated videos: H.264 in fragmented MP4 (plays while being written, survives a kill), MJPG AVI without PyAV."""

from __future__ import annotations

import shutil
from pathlib import Path

import numpy as np
import pytest

from fearguard.outputs.video import H264Writer, MjpgWriter, count_frames, h264_available, open_video


def frames(n: int, w: int = 64, h: int = 48) -> list[np.ndarray]:
    out = []
    for k in range(n):
        img = np.zeros((h, w, 3), np.uint8)
        img[:, (3 * k) % w] = (40 * k % 255, 255, 90)
        out.append(img)
    return out


def test_h264_is_chosen_when_pyav_is_installed(tmp_path: Path) -> None:
    assert h264_available()  # the test extra installs PyAV
    video = open_video(tmp_path / "v", 20.0)
    assert isinstance(video, H264Writer) and video.path == tmp_path / "v.mp4" and video.kind == "h264"
    video.close()  # before any frame: nothing to finish
    assert not video.path.exists()


def test_every_copy_of_a_growing_h264_file_plays_up_to_the_frame_before(tmp_path: Path) -> None:
    video = open_video(tmp_path / "v", 20.0, "h264")
    for k, img in enumerate(frames(12), start=1):
        video.write(img)
        cut = tmp_path / f"cut{k}.mp4"
        shutil.copy(video.path, cut)  # what SIGKILL would leave on disk now
        assert count_frames(cut) >= k - 1, k
    video.close()
    video.close()
    assert count_frames(video.path) == 12 and video.frames == 12


def test_h264_needs_even_sides_so_an_odd_frame_is_trimmed_by_a_pixel(tmp_path: Path) -> None:
    video = open_video(tmp_path / "odd", 0.0, "h264")  # a bad rate falls back to 20 Hz
    for img in frames(3, 65, 49):
        video.write(img)
    video.write(np.zeros((49, 65), np.uint8))  # grey frames are converted
    video.close()
    assert video.size == (64, 48) and video.rescaled == 0 and video.fps == 20.0 and count_frames(video.path) == 4


def test_mjpg_avi_plays_and_a_truncated_copy_decodes_its_complete_frames(tmp_path: Path) -> None:
    video = open_video(tmp_path / "m", 10.0, "mjpg")
    assert isinstance(video, MjpgWriter) and video.path.suffix == ".avi"
    rng = np.random.default_rng(0)
    for _ in range(30):
        video.write(rng.integers(0, 255, (240, 320, 3), dtype=np.uint8))  # noisy: ~100 kB per frame
    video.close()
    video.close()
    assert count_frames(video.path) == 30
    data = video.path.read_bytes()
    cut = tmp_path / "cut.avi"
    cut.write_bytes(data[: len(data) // 2])  # no index, half the frames: still plays up to the cut
    assert 10 <= count_frames(cut) < 30


def test_frames_of_another_size_are_scaled_not_dropped(tmp_path: Path) -> None:
    video = open_video(tmp_path / "s", 10.0, "mjpg")
    for w, h in [(64, 48), (128, 96), (64, 48), (30, 70)]:
        video.write(np.full((h, w, 3), 128, np.uint8))
    video.close()
    assert video.rescaled == 2 and count_frames(video.path) == 4


def test_an_unknown_kind_is_refused(tmp_path: Path) -> None:
    with pytest.raises(ValueError, match="h264, mjpg"):
        open_video(tmp_path / "x", 10.0, "gif")
    assert count_frames(tmp_path / "missing.mp4") == 0
