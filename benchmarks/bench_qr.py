"""Cost of detect_qr (cheap and thorough) per frame, against cv2.imread + cv2.resize of the same frame, and decode counts.

    python benchmarks/bench_qr.py [DATA_DIR]        (default ../shared/data)

One OpenCV thread (the perception budget is ≤ 5 ms per 640×480 frame on one core). Road stills are
resized to 640×480 (and 320×240, the simulator's size); the QR photos are used as stored. Reference and
detector are timed alternately, frame by frame, round by round, so both see the same machine: read the
ratios, not the absolute times (the machine is shared). Decode counts compare with plain
``cv2.QRCodeDetector().detectAndDecode`` on the zxing photos (expected text: UTF-8, CRLF → LF, right-stripped).
"""

from __future__ import annotations

import statistics
import sys
import time
from collections import Counter
from pathlib import Path

import cv2
import numpy as np

from fearguard.vision.qr import detect_qr_traced

ROUNDS = 5  # timing rounds over every frame; the median per frame is kept
FOLDERS = ("zxing-qrcode-1", "zxing-qrcode-3", "zxing-qrcode-5")
DEFAULT_DATA = Path(__file__).resolve().parents[2] / "shared" / "data"
BOARD_PAYLOAD = "FG1;route=campus;sector=3;pos_m=12.5"
BOARD_PX = 120  # [px] a board in view: about 1.7 m away for a 0.4 m board and a 62° 640×480 camera


def _ms(fn, *args) -> float:
    start = time.perf_counter()
    fn(*args)
    return (time.perf_counter() - start) * 1e3


def _load(path: Path, size: tuple[int, int]) -> np.ndarray:
    return cv2.resize(cv2.imread(str(path)), size, interpolation=cv2.INTER_AREA)


def with_board(frame: np.ndarray, width_px: int) -> np.ndarray:
    """The frame with a cv2.QRCodeEncoder board (a track marker), ``width_px`` wide, pasted left of centre."""
    code = cv2.QRCodeEncoder.create().encode(BOARD_PAYLOAD)
    board = cv2.resize(cv2.resize(code, None, fx=16, fy=16, interpolation=cv2.INTER_NEAREST), (width_px, width_px),
                       interpolation=cv2.INTER_AREA)
    out = frame.copy()
    y, x = frame.shape[0] // 3, frame.shape[1] // 4
    out[y:y + width_px, x:x + width_px] = board[..., None]
    return out


def time_frames(paths: list[Path], size: tuple[int, int] | None, board_px: int = 0) -> dict[str, float]:
    """Median ms per frame of the reference (imread + resize to 640×480) and of both detect_qr paths."""
    frames = [_load(p, size) if size else cv2.imread(str(p)) for p in paths]
    frames = [with_board(f, board_px) for f in frames] if board_px else frames
    times: dict[str, list[float]] = {"reference": [], "cheap": [], "thorough": []}
    for _ in range(ROUNDS):
        for p, frame in zip(paths, frames, strict=True):
            times["reference"].append(_ms(_load, p, (640, 480)))
            times["cheap"].append(_ms(detect_qr_traced, frame, False))
        for p, frame in zip(paths, frames, strict=True):
            times["reference"].append(_ms(_load, p, (640, 480)))
            times["thorough"].append(_ms(detect_qr_traced, frame, True))
    return {k: statistics.median(v) for k, v in times.items()}


def expected(txt: Path) -> str:
    return txt.read_bytes().decode("utf-8").replace("\r\n", "\n").rstrip()


def decode_counts(folder: Path) -> tuple[int, dict[str, int], dict[str, Counter]]:
    plain = cv2.QRCodeDetector()
    pngs = sorted(folder.glob("*.png"))
    counts, steps = {"baseline": 0, "cheap": 0, "thorough": 0}, {"cheap": Counter(), "thorough": Counter()}
    for png in pngs:
        img, want = cv2.imread(str(png)), expected(png.with_suffix(".txt"))
        counts["baseline"] += plain.detectAndDecode(img)[0].replace("\r\n", "\n").rstrip() == want
        for path, thorough in (("cheap", False), ("thorough", True)):
            markers, step = detect_qr_traced(img, thorough)
            if want in [m.payload.replace("\r\n", "\n").rstrip() for m in markers]:
                counts[path] += 1
                steps[path][step] += 1
    return len(pngs), counts, steps


def main() -> None:
    data = Path(sys.argv[1]) if len(sys.argv) > 1 else DEFAULT_DATA
    cv2.setNumThreads(1)
    roads = sorted((data / "road" / "images").glob("*.jpg"))
    photos = sorted(p for f in FOLDERS for p in (data / "qr" / f).glob("*.png"))
    print(f"OpenCV {cv2.__version__}, 1 thread, median of {ROUNDS} rounds; reference = cv2.imread + cv2.resize to 640×480")
    print(f"{'frames':36s} {'reference':>10s} {'cheap':>17s} {'thorough':>19s}")
    for label, paths, size, board in ((f"road stills, 640×480 ({len(roads)}, no QR)", roads, (640, 480), 0),
                                      (f"road stills, 320×240 ({len(roads)}, no QR)", roads, (320, 240), 0),
                                      (f"road stills 640×480 + {BOARD_PX} px board", roads, (640, 480), BOARD_PX),
                                      (f"zxing QR photos as stored ({len(photos)})", photos, None, 0)):
        t = time_frames(paths, size, board)
        ref = t["reference"]
        print(f"{label:36s} {ref:7.2f} ms {t['cheap']:7.2f} ms {t['cheap'] / ref:5.2f}× "
              f"{t['thorough']:7.2f} ms {t['thorough'] / ref:6.2f}×")
    print("\ndecoded photos (expected text found)   baseline = cv2.QRCodeDetector().detectAndDecode")
    for folder in FOLDERS:
        n, c, steps = decode_counts(data / "qr" / folder)
        print(f"{folder}: {n:2d} photos  baseline {c['baseline']:2d}  cheap {c['cheap']:2d}  thorough {c['thorough']:2d}   "
              f"cheap by {dict(steps['cheap'])}  thorough by {dict(steps['thorough'])}")


if __name__ == "__main__":
    main()
