"""Rebuild the development corpus (the frames ``eval_corpus.py`` scores) from the public repositories it comes from.

    python benchmarks/build_corpus.py --mirrors DIR --out DIR [--only SOURCE,...] [--corpus DIR]

Why: the corpus's labels and each source's ``meta.json`` are kept in the repository (``benchmarks/data/corpus``),
its frames are not: they come from 10 public GitHub repositories with their own licences (one source is
non-commercial, see ``SOURCES.md``) and weigh about 200 MB. This tool rebuilds ``OUT/<source_id>/frames/NNNNNN.jpg``
with ``frames_src.txt`` (frame number → original file or video frame), ``labels.csv`` (that source's labels) and
``meta.json`` per source, plus ``SOURCES.md`` and ``labels.csv`` at the top: the layout ``eval_corpus.py --corpus``
reads. Where the source frames are JPEG files (Donkey tubs and sessions, JetRacer, OpenBot, Dride stills) they are
copied byte-for-byte; video frames (decoded with PyAV / FFmpeg) and the KITTI PNG stills (decoded with OpenCV) are
written with OpenCV at JPEG quality 95, which gives the same bytes with the same OpenCV build (the same pictures
otherwise). Each source's recipe follows its ``path_in_repo`` in ``meta.json`` and ``SOURCES.md``.

Before running it, fetch every repository snapshot: one bare git directory per repository at
``MIRRORS/<owner>+<name>/repo`` — the layout the ``fetch`` tool of this project's tooling produces, or a
``git clone --mirror https://github.com/<owner>/<name>`` renamed accordingly. Files are read at the commit recorded
as ``"commit"`` in the source's ``meta.json`` (not the snapshot's HEAD). Needs numpy, OpenCV and PyAV (the
``video`` extra).

After each source it checks that the number of frames equals ``"frames"`` in ``meta.json`` and that every image its
labels name exists; otherwise (or when a snapshot, commit or file is missing) it stops with a one-line error naming
the source and exit status 2. A source's ``meta.json`` is written last, so an interrupted source is not picked up by
``eval_corpus.py``. Frame folders are replaced, not merged.
"""

from __future__ import annotations

import argparse
import csv
import io
import json
import re
import shutil
import subprocess
import sys
import tarfile
from collections.abc import Callable, Iterator
from pathlib import Path
from typing import Any

import av
import cv2
import numpy as np

DEFAULT_MIRRORS = Path("/work/.mirror")
DEFAULT_OUT = Path("/work/devdata")  # eval_corpus.py's default --corpus
DEFAULT_CORPUS = Path(__file__).resolve().parent / "data" / "corpus"  # meta.json per source, labels.csv, SOURCES.md
JPEG_QUALITY = 95  # for frames that are decoded (videos, PNG) rather than copied

Frame = bytes | np.ndarray  # JPEG file contents (copied as they are) or a BGR image (encoded)
Frames = Iterator[tuple[str, Frame]]  # (where the frame comes from, the frame), in corpus order


class CorpusError(Exception):
    """A source cannot be rebuilt as its recipe says (missing snapshot, commit or file; wrong frame count)."""


class Snapshot:
    """The files of one bare git snapshot at one commit, read through a single ``git cat-file --batch``."""

    def __init__(self, mirrors: Path, repo: str, commit: str) -> None:
        """Open ``mirrors/<owner>+<name>/repo`` at ``commit``."""
        self.git_dir = mirrors / repo.replace("/", "+") / "repo"
        self.commit = commit
        if not self.git_dir.is_dir():
            raise CorpusError(f"no snapshot of {repo} at {self.git_dir} (fetch it first)")
        if subprocess.run(self._git("cat-file", "-e", f"{commit}^{{commit}}"), capture_output=True).returncode != 0:
            raise CorpusError(f"commit {commit} is not in the snapshot {self.git_dir}")
        self._batch = subprocess.Popen(self._git("cat-file", "--batch"), stdin=subprocess.PIPE, stdout=subprocess.PIPE)

    def __enter__(self) -> Snapshot:
        """The snapshot itself."""
        return self

    def __exit__(self, *exc: object) -> None:
        """Stop the ``git cat-file`` process."""
        assert self._batch.stdin is not None
        self._batch.stdin.close()
        self._batch.wait()

    def _git(self, *args: str) -> list[str]:
        """A git command line on this snapshot."""
        return ["git", "--git-dir", str(self.git_dir), *args]

    def blob(self, path: str) -> bytes:
        """The contents of the file at ``path``."""
        stdin, stdout = self._batch.stdin, self._batch.stdout
        assert stdin is not None and stdout is not None
        stdin.write(f"{self.commit}:{path}\n".encode())
        stdin.flush()
        header = stdout.readline().decode().split()
        if len(header) != 3 or header[1] != "blob":
            raise CorpusError(f"{path} is not a file at {self.commit} in {self.git_dir}")
        data = stdout.read(int(header[2]))
        stdout.read(1)  # the newline after the contents
        return data

    def ls(self, folder: str) -> list[str]:
        """Every file under ``folder`` (recursively), as paths from the repository root."""
        done = subprocess.run(self._git("ls-tree", "-r", "-z", "--name-only", self.commit, "--", folder), capture_output=True)
        if done.returncode != 0:
            raise CorpusError(f"git ls-tree {folder} failed in {self.git_dir}: {done.stderr.decode().strip()}")
        return [name for name in done.stdout.decode().split("\0") if name]


def number(pattern: str, text: str) -> int:
    """The integer that the first group of ``pattern`` matches in ``text``."""
    match = re.search(pattern, text)
    if match is None:
        raise CorpusError(f"{text!r} does not match {pattern!r}")
    return int(match.group(1))


def record_range(meta: dict[str, Any]) -> tuple[int, int]:
    """The first and last tub record of a source ("records LO-HI" in its path_in_repo)."""
    match = re.search(r"records (\d+)-(\d+)", meta["path_in_repo"])
    if match is None:
        raise CorpusError("path_in_repo names no 'records LO-HI' range")
    return int(match.group(1)), int(match.group(2))


def tub_records(read: Callable[[str], bytes], base: str) -> tuple[list[dict[str, Any]], list[int]]:
    """A Donkey tub v2's records in catalog order and its deleted indexes (manifest.json's 5th line lists the catalogs)."""
    manifest = json.loads(read(f"{base}/manifest.json").decode().split("\n")[4])
    records: list[dict[str, Any]] = []
    for name in manifest["paths"]:
        records += [json.loads(line) for line in read(f"{base}/{name}").decode().splitlines() if line.strip()]
    return records, manifest["deleted_indexes"]


def tar_read(tar: tarfile.TarFile, name: str) -> bytes:
    """One file of an archive."""
    member = tar.extractfile(name)
    if member is None:
        raise CorpusError(f"{name} is not a file in the archive")
    return member.read()


def jpeg_files(snap: Snapshot, paths: list[str]) -> Frames:
    """The files at ``paths``, copied as they are."""
    for path in paths:
        yield path, snap.blob(path)


def video_frames(snap: Snapshot, path: str, stop: int | None = None, post: Callable[[np.ndarray], np.ndarray] | None = None) -> Frames:
    """Every frame of a video (``stop`` given: every 2nd of frames 0..stop-1, which must all decode), optionally transformed."""
    step = 1 if stop is None else 2
    last = -1
    with av.open(io.BytesIO(snap.blob(path))) as container:
        for last, frame in enumerate(container.decode(container.streams.video[0])):
            if stop is not None and last >= stop:
                break
            if last % step == 0:
                image = frame.to_ndarray(format="bgr24")
                yield f"{path} frame {last}", image if post is None else post(image)
    if stop is not None and last < stop - 1:
        raise CorpusError(f"{path}: only {last + 1} frames decode, the recipe needs {stop}")


def gyadav_forest_road(snap: Snapshot, meta: dict[str, Any]) -> Frames:
    """lane.mp4: every 2nd of frames 0..1198 (SOURCES.md's 1199 decodable frames; current FFmpeg decodes all 1231)."""
    return video_frames(snap, "lane.mp4", stop=1199)


def muchlisin_highway_dusk(snap: Snapshot, meta: dict[str, Any]) -> Frames:
    """driving.mp4: every frame."""
    return video_frames(snap, "driving.mp4")


def dride_highway_glare(snap: Snapshot, meta: dict[str, Any]) -> Frames:
    """A sideways dashcam clip: every frame, rotated 90° counter-clockwise to upright."""
    return video_frames(snap, "training/video/1492426505.mp4", post=lambda im: cv2.rotate(im, cv2.ROTATE_90_COUNTERCLOCKWISE))


def tsiggi_night_road(snap: Snapshot, meta: dict[str, Any]) -> Frames:
    """real_world.mp4: every frame, 1418×726 downscaled to 1280×655 (INTER_AREA)."""
    return video_frames(snap, "video_repository/real_world.mp4", post=lambda im: cv2.resize(im, (1280, 655), interpolation=cv2.INTER_AREA))


def tsiggi_bfmc_track(snap: Snapshot, meta: dict[str, Any]) -> Frames:
    """intersections2.mp4: every 2nd of frames 0..1198."""
    return video_frames(snap, "video_repository/intersections2.mp4", stop=1199)


def acdc_kitti_stills(snap: Snapshot, meta: dict[str, Any]) -> Frames:
    """The KITTI PNG stills in file-name order, decoded (re-encoded as JPEG on writing)."""
    for path in sorted(p for p in snap.ls("section_2_sensor_data_processing/datasets/kitti/image_2") if p.endswith(".png")):
        image = cv2.imdecode(np.frombuffer(snap.blob(path), np.uint8), cv2.IMREAD_COLOR)
        if image is None:
            raise CorpusError(f"OpenCV cannot decode {path}")
        yield path, image


def dride_lanechange_frames(snap: Snapshot, meta: dict[str, Any]) -> Frames:
    """training/road/1483*_{left,right}.jpg sorted by the millisecond timestamp in the name."""
    paths = [p for p in snap.ls("training/road") if re.search(r"/1483\d+_(left|right)\.jpg$", p)]
    return jpeg_files(snap, sorted(paths, key=lambda p: (number(r"/(\d+)_", p), p)))


def donkeycar_sidewalk2016(snap: Snapshot, meta: dict[str, Any]) -> Frames:
    """img/frame_08874..09173_*.jpg in frame-number order."""
    paths = [p for p in snap.ls("img") if re.search(r"img/frame_\d+_.*\.jpg$", p)]
    paths = [p for p in paths if 8874 <= number(r"frame_(\d+)_", p) <= 9173]
    return jpeg_files(snap, sorted(paths, key=lambda p: number(r"frame_(\d+)_", p)))


def donkeycar_whiteline2016(snap: Snapshot, meta: dict[str, Any]) -> Frames:
    """datasets/whiteline2.tar.gz: whiteline2/frame_00030..00688_*.jpg in frame-number order."""
    tar_path = "datasets/whiteline2.tar.gz"
    with tarfile.open(fileobj=io.BytesIO(snap.blob(tar_path)), mode="r:gz") as tar:
        jpegs = [m.name for m in tar.getmembers() if m.isfile() and re.fullmatch(r"whiteline2/[^/]+\.jpg", m.name)]
        names = [n for n in jpegs if 30 <= number(r"frame_(\d+)_", n) <= 688]
        for name in sorted(names, key=lambda n: number(r"frame_(\d+)_", n)):
            yield f"{Path(tar_path).name}:{name}", tar_read(tar, name)


def donkeycar_testtub_yellowdash(snap: Snapshot, meta: dict[str, Any]) -> Frames:
    """donkeycar/tests/tub/tub.tar.gz: the records LO-HI of path_in_repo by position in the catalog."""
    tar_path = "donkeycar/tests/tub/tub.tar.gz"
    lo, hi = record_range(meta)
    with tarfile.open(fileobj=io.BytesIO(snap.blob(tar_path)), mode="r:gz") as tar:
        records, deleted = tub_records(lambda name: tar_read(tar, name), "tub")
        if deleted:
            raise CorpusError(f"{tar_path}: the tub has deleted records, the recipe assumes none")
        for record in records[lo : hi + 1]:
            image = f"tub/images/{record['cam/image_array']}"
            yield f"{Path(tar_path).name}:{image} (_index {record['_index']})", tar_read(tar, image)


def tub_by_index(snap: Snapshot, meta: dict[str, Any]) -> Frames:
    """mycar/data: the tub records whose ``_index`` field is in LO..HI of path_in_repo, in catalog order."""
    base = "mycar/data"
    lo, hi = record_range(meta)
    records, deleted = tub_records(snap.blob, base)
    chosen = [r for r in records if lo <= r["_index"] <= hi]
    if len(chosen) != hi - lo + 1:
        raise CorpusError(f"{len(chosen)} records with _index {lo}..{hi}, expected {hi - lo + 1}")
    gone = set(deleted)
    flagged = sum(r["_index"] in gone for r in chosen)  # kept: the recipe selects by _index only
    print(f"  records _index {lo}..{hi}: {len(chosen)} ({flagged} of them listed as deleted in the manifest)", flush=True)
    for record in chosen:
        path = f"{base}/images/{record['cam/image_array']}"
        yield f"{path} (_index {record['_index']}, session {record.get('_session_id')})", snap.blob(path)


def fabo_jetracer_walls(snap: Snapshot, meta: dict[str, Any]) -> Frames:
    """notebooks/camera/a_all_001/xy/0_0_NNNNN.jpg: every 2nd of the 1600 in file-number order."""
    paths = [p for p in snap.ls("notebooks/camera/a_all_001/xy") if re.search(r"/0_0_\d+\.jpg$", p)]
    paths.sort(key=lambda p: number(r"0_0_(\d+)\.jpg$", p))
    if len(paths) != 1600:
        raise CorpusError(f"{len(paths)} files 0_0_*.jpg, expected 1600")
    return jpeg_files(snap, paths[0::2])


def openbot_testlog_mat(snap: Snapshot, meta: dict[str, Any]) -> Frames:
    """python/tests/test_data/logs1/data/images/*.jpeg in the order of sensor_data/rgbFrames.txt."""
    base = "python/tests/test_data/logs1/data"
    lines = snap.blob(f"{base}/sensor_data/rgbFrames.txt").decode().splitlines()
    if not lines or not lines[0].startswith("timestamp"):
        raise CorpusError("rgbFrames.txt has no 'timestamp' header")
    ids = [line.split(",")[1].strip() for line in lines[1:] if line.strip()]
    return jpeg_files(snap, [f"{base}/images/{i}.jpeg" for i in ids])


RECIPES: dict[str, Callable[[Snapshot, dict[str, Any]], Frames]] = {  # in SOURCES.md's order
    "gyadav_forest_road": gyadav_forest_road,
    "muchlisin_highway_dusk": muchlisin_highway_dusk,
    "dride_highway_glare": dride_highway_glare,
    "dride_lanechange_frames": dride_lanechange_frames,
    "acdc_kitti_stills": acdc_kitti_stills,
    "hzy_donkey_centreline": tub_by_index,
    "donkeycar_testtub_yellowdash": donkeycar_testtub_yellowdash,
    "donkeycar_whiteline2016": donkeycar_whiteline2016,
    "donkeycar_sidewalk2016": donkeycar_sidewalk2016,
    "criscola_donkey_printedmat": tub_by_index,
    "fabo_jetracer_walls": fabo_jetracer_walls,
    "openbot_testlog_mat": openbot_testlog_mat,
    "tsiggi_night_road": tsiggi_night_road,
    "tsiggi_bfmc_track": tsiggi_bfmc_track,
}


def write_frames(folder: Path, frames: Frames) -> list[str]:
    """Write the frames as NNNNNN.jpg into a fresh ``folder``; returns frames_src.txt's lines."""
    if folder.exists():
        shutil.rmtree(folder)
    folder.mkdir(parents=True)
    lines = []
    for i, (origin, frame) in enumerate(frames):
        target = folder / f"{i:06d}.jpg"
        if isinstance(frame, bytes):
            if not frame.startswith(b"\xff\xd8"):
                raise CorpusError(f"{origin} is not a JPEG")
            target.write_bytes(frame)
        elif not cv2.imwrite(str(target), frame, [cv2.IMWRITE_JPEG_QUALITY, JPEG_QUALITY]):
            raise CorpusError(f"OpenCV could not write {target}")
        lines.append(f"{i:06d} {origin}\n")
    return lines


def source_labels(corpus: Path, source_id: str) -> tuple[bytes, list[str]]:
    """The source's labels.csv (the corpus file's header and its rows, bytes as they are) and the images they name."""
    raw = (corpus / "labels.csv").read_bytes().splitlines(keepends=True)
    rows = b"".join([raw[0], *(line for line in raw[1:] if line.startswith(f"{source_id},".encode()))])
    with (corpus / "labels.csv").open(newline="", encoding="utf-8") as f:
        images = [row["image"] for row in csv.DictReader(f) if row["source"] == source_id]
    return rows, images


def build_source(source_id: str, corpus: Path, mirrors: Path, out: Path) -> int:
    """Rebuild one source under ``out/source_id`` and check it; returns its frame count."""
    meta_file = corpus / f"{source_id}.meta.json"
    meta = json.loads(meta_file.read_text(encoding="utf-8"))
    folder = out / source_id
    (folder / "meta.json").unlink(missing_ok=True)  # written back only once the source is complete
    with Snapshot(mirrors, meta["repo"], meta["commit"]) as snap:
        lines = write_frames(folder / "frames", RECIPES[source_id](snap, meta))
    (folder / "frames_src.txt").write_text("".join(lines), encoding="utf-8")
    if len(lines) != meta["frames"]:
        raise CorpusError(f"{len(lines)} frames built, meta.json says {meta['frames']}")
    labels, images = source_labels(corpus, source_id)
    missing = [image for image in images if not (folder / image).is_file()]
    if missing:
        raise CorpusError(f"{len(missing)} labelled images missing, first {missing[0]}")
    (folder / "labels.csv").write_bytes(labels)
    shutil.copyfile(meta_file, folder / "meta.json")
    return len(lines)


def main(argv: list[str] | None = None) -> int:
    """Rebuild the chosen sources (all by default), then copy SOURCES.md and labels.csv to the top of ``--out``."""
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--mirrors", type=Path, default=DEFAULT_MIRRORS, help="folder of bare snapshots, <owner>+<name>/repo each")
    parser.add_argument("--out", type=Path, default=DEFAULT_OUT, help="corpus folder to (re)build (eval_corpus.py's default --corpus)")
    parser.add_argument("--only", default=None, help="comma-separated source ids (default: all)")
    parser.add_argument("--corpus", type=Path, default=DEFAULT_CORPUS, help="the repository's labels and meta.json files")
    args = parser.parse_args(argv)
    sources = list(RECIPES) if args.only is None else [s for s in args.only.split(",") if s]
    unknown = [s for s in sources if s not in RECIPES]
    if unknown or not sources:
        parser.error(f"unknown source id(s) {', '.join(unknown) or '(none given)'}; known: {', '.join(RECIPES)}")
    for source_id in sources:
        print(f"{source_id}: building", flush=True)
        try:
            n = build_source(source_id, args.corpus, args.mirrors, args.out)
        except (CorpusError, OSError, av.error.FFmpegError) as e:
            print(f"build_corpus: {source_id}: {' '.join(str(e).split())}", file=sys.stderr)  # one line
            return 2
        print(f"{source_id}: {n} frames, labelled images present", flush=True)
    args.out.mkdir(parents=True, exist_ok=True)
    for name in ("SOURCES.md", "labels.csv"):
        shutil.copyfile(args.corpus / name, args.out / name)
    return 0


if __name__ == "__main__":
    sys.exit(main())
