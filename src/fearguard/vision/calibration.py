"""Chessboard camera calibration with OpenCV: photos of a printed board → a CameraModel.

Each image: ``cv2.findChessboardCorners`` refined by ``cv2.cornerSubPix``, with ``cv2.findChessboardCornersSB`` as the
fallback when the classic detector fails or returns a bent grid (one corner clearly off its neighbours — it happens
near the image border). The boards found go to ``cv2.calibrateCamera`` (pinhole + k1, k2, p1, p2, k3); the result
keeps the overall and per-image RMS reprojection error, so a bad photo can be spotted and removed.
"""

from __future__ import annotations

import math
import re
from collections import Counter
from collections.abc import Callable, Sequence
from dataclasses import dataclass
from pathlib import Path

import cv2
import numpy as np

from fearguard.camera import CameraModel
from fearguard.errors import CalibrationError
from fearguard.readings import finite_reading

DEFAULT_PATTERN = (9, 6)  # inner corners (columns, rows) of the usual OpenCV sample board
MIN_BOARDS = 3  # boards needed for a calibration (OpenCV's docs ask for at least 10 for a good one)
SIZE_TOLERANCE_PX = 2  # [px] images this close to the common size are cropped/padded to it (right/bottom edge)
GRID_BEND_MAX = 0.3  # [squares] largest second difference of the corner grid; good boards stay below ~0.15
SUBPIX_WINDOW_FRACTION = 0.25  # half-window of cornerSubPix as a share of the square side (stays inside one square)
SUBPIX_HALF_WINDOW_PX = (3, 11)  # [px] its bounds; 11 is the value of OpenCV's tutorial
IMAGE_SUFFIXES = (".jpg", ".jpeg", ".png")
_SUBPIX_CRITERIA = (cv2.TERM_CRITERIA_EPS + cv2.TERM_CRITERIA_MAX_ITER, 30, 1e-3)
_CLASSIC_FLAGS = cv2.CALIB_CB_ADAPTIVE_THRESH | cv2.CALIB_CB_NORMALIZE_IMAGE | cv2.CALIB_CB_FAST_CHECK


@dataclass(frozen=True)
class CalibrationResult:
    """The calibrated camera, its RMS reprojection error, and which images were used (errors in ``found`` order)."""

    camera: CameraModel
    rms_px: float
    found: tuple[Path, ...]
    missed: tuple[Path, ...]
    per_image_error_px: tuple[float, ...]
    missed_reasons: tuple[str, ...] = ()  # one per ``missed`` image, same order
    notes: tuple[str, ...] = ()  # what was adjusted on the way (an image cropped to the common size, the SB fallback used)


@dataclass(frozen=True)
class BoardDetection:
    """One image's chessboard: corners (N, 1, 2) float32 pixels, or None; ``reason`` says why it was missed or needed SB."""

    corners_px: np.ndarray | None
    method: str  # "classic", "sb" or "" when not found
    reason: str


# -- small pure helpers ----------------------------------------------------------------------
def parse_pattern(text: str) -> tuple[int, int]:
    """``"9x6"`` → (9, 6): inner corners per row and per column, each at least 3."""
    match = re.fullmatch(r"\s*(\d+)\s*[xX×]\s*(\d+)\s*", str(text))
    if not match:
        raise CalibrationError(f"--pattern {text!r}: expected COLSxROWS inner corners, e.g. 9x6 (a board of 10×7 squares)")
    return check_pattern((int(match.group(1)), int(match.group(2))))


def check_pattern(pattern: Sequence[int]) -> tuple[int, int]:
    """The pattern as (cols, rows) ints ≥ 3, or CalibrationError saying what is wrong."""
    try:
        cols, rows = (int(k) for k in pattern)
    except (TypeError, ValueError):
        raise CalibrationError(f"pattern {pattern!r}: expected two integers (inner corners per row, per column), e.g. (9, 6)") from None
    if cols < 3 or rows < 3:
        raise CalibrationError(f"pattern {cols}x{rows}: count inner corners (where four squares meet), at least 3 each way")
    return cols, rows


def board_points_m(pattern: tuple[int, int], square_m: float) -> np.ndarray:
    """The board's corners in its own plane (z = 0), row by row as OpenCV returns them: (N, 3) float32 metres."""
    cols, rows = pattern
    grid = np.zeros((cols * rows, 3), np.float32)
    grid[:, :2] = np.mgrid[0:cols, 0:rows].T.reshape(-1, 2) * square_m
    return grid


def grid_bend(corners_px: np.ndarray, pattern: tuple[int, int]) -> float:
    """Largest second difference of the corner grid along rows and columns, in squares (≈0.1 for a good board)."""
    cols, rows = pattern
    g = np.asarray(corners_px, dtype=float).reshape(rows, cols, 2)
    steps = np.concatenate([np.linalg.norm(np.diff(g, axis=1), axis=2).ravel(), np.linalg.norm(np.diff(g, axis=0), axis=2).ravel()])
    side = float(np.median(steps))
    if not side > 0:
        return math.inf
    along_rows = np.linalg.norm(g[:, :-2] - 2 * g[:, 1:-1] + g[:, 2:], axis=2).max()
    along_cols = np.linalg.norm(g[:-2] - 2 * g[1:-1] + g[2:], axis=2).max()
    return float(max(along_rows, along_cols)) / side


def square_side_px(corners_px: np.ndarray, pattern: tuple[int, int]) -> float:
    """Median distance between neighbouring corners along rows (pixels)."""
    cols, rows = pattern
    g = np.asarray(corners_px, dtype=float).reshape(rows, cols, 2)
    return float(np.median(np.linalg.norm(np.diff(g, axis=1), axis=2)))


def _natural_key(path: Path) -> list[object]:
    """calibration2 before calibration10."""
    return [int(part) if part.isdigit() else part.lower() for part in re.split(r"(\d+)", path.name)]


def expand_image_paths(items: Sequence[str | Path]) -> list[Path]:
    """Files as given; a folder becomes its *.jpg/*.jpeg/*.png files in natural order (a missing file stays, to be reported)."""
    paths: list[Path] = []
    for item in items:
        path = Path(item)
        if path.is_dir():
            paths.extend(sorted((p for p in path.iterdir() if p.suffix.lower() in IMAGE_SUFFIXES and p.is_file()), key=_natural_key))
        else:
            paths.append(path)
    return paths


# -- detection -------------------------------------------------------------------------------
def detect_board(gray: np.ndarray, pattern: tuple[int, int]) -> BoardDetection:
    """Chessboard corners in one 8-bit grey image: classic detector + sub-pixel refinement, SB detector as fallback."""
    found, corners = cv2.findChessboardCorners(gray, pattern, flags=_CLASSIC_FLAGS)
    bent = ""
    if found:
        low, high = SUBPIX_HALF_WINDOW_PX
        half = int(np.clip(round(SUBPIX_WINDOW_FRACTION * square_side_px(corners, pattern)), low, high))
        corners = cv2.cornerSubPix(gray, corners, (half, half), (-1, -1), _SUBPIX_CRITERIA)
        bend = grid_bend(corners, pattern)
        if bend <= GRID_BEND_MAX:
            return BoardDetection(corners.astype(np.float32), "classic", "")
        bent = f"classic detector's grid is bent ({bend:.2f} squares)"
    found, corners = cv2.findChessboardCornersSB(gray, pattern)  # returns sub-pixel corners already
    if found:
        bend = grid_bend(corners, pattern)
        if bend <= GRID_BEND_MAX:
            return BoardDetection(corners.reshape(-1, 1, 2).astype(np.float32), "sb", bent or "classic detector found none")
        return BoardDetection(None, "", f"corner grid is bent ({bend:.2f} squares > {GRID_BEND_MAX}): a corner was mis-detected")
    cols, rows = pattern
    detail = f" ({bent}; SB detector found none)" if bent else ""
    return BoardDetection(None, "", f"no {cols}x{rows} chessboard found{detail}: is the whole board in view and sharp?")


def _fit_size(image: np.ndarray, size: tuple[int, int]) -> np.ndarray:
    """Crop or pad (replicating the edge) the right/bottom to ``size`` (w, h); pixel coordinates stay the same."""
    w, h = size
    image = image[:h, :w]
    pad_h, pad_w = h - image.shape[0], w - image.shape[1]
    if pad_h or pad_w:
        image = cv2.copyMakeBorder(image, 0, pad_h, 0, pad_w, cv2.BORDER_REPLICATE)
    return image


def _common_size(images: dict[Path, np.ndarray]) -> tuple[int, int]:
    """The most common (w, h); images more than SIZE_TOLERANCE_PX off it raise CalibrationError naming them."""
    sizes = {p: (img.shape[1], img.shape[0]) for p, img in images.items()}
    size, count = Counter(sizes.values()).most_common(1)[0]
    odd = [p for p, s in sizes.items() if max(abs(s[0] - size[0]), abs(s[1] - size[1])) > SIZE_TOLERANCE_PX]
    if odd:
        listed = ", ".join(f"{p.name} is {sizes[p][0]}x{sizes[p][1]}" for p in odd[:5]) + (" ..." if len(odd) > 5 else "")
        raise CalibrationError(
            f"images must share one size: {count} are {size[0]}x{size[1]}, but {listed}; "
            f"calibrate one camera at one resolution (remove those files or take them again)"
        )
    return size


# -- calibration -----------------------------------------------------------------------------
def calibrate_chessboard(
    paths: Sequence[Path],
    pattern: tuple[int, int] = DEFAULT_PATTERN,
    square_m: float = 1.0,
    mount_height_m: float | None = None,
    pitch_deg: float = 0.0,
    on_image: Callable[[int, int], None] | None = None,
) -> CalibrationResult:
    """Calibrate from chessboard photos; ``square_m`` only scales the board poses, not the intrinsics.

    ``on_image(done, total)`` is called after each image's board search (the slow part: a progress bar).
    """
    pattern = check_pattern(pattern)
    paths = [Path(p) for p in paths]
    if not paths:
        raise CalibrationError("no images given: pass chessboard photos (files, or a folder of *.jpg/*.png)")
    if not _positive(square_m):
        raise CalibrationError(f"square size {square_m!r} m: expected the side of one board square in metres, > 0")
    if mount_height_m is not None and not _positive(mount_height_m):
        raise CalibrationError(f"mount height {mount_height_m!r} m: expected the camera's height above the ground in metres, > 0")
    if finite_reading(pitch_deg) is None:
        raise CalibrationError(f"pitch {pitch_deg!r} deg: expected a finite angle (positive = looking down)")

    images: dict[Path, np.ndarray] = {}
    missed: dict[Path, str] = {}
    for path in paths:
        gray = cv2.imread(str(path), cv2.IMREAD_GRAYSCALE) if path.is_file() else None
        if gray is None:
            missed[path] = "no such file" if not path.exists() else "cannot read it as an image"
        else:
            images[path] = gray
    if not images:
        raise CalibrationError(f"none of the {len(paths)} image(s) could be read ({_where(paths)}): give JPEG or PNG chessboard photos")
    size = _common_size(images)

    found: list[Path] = []
    corners: list[np.ndarray] = []
    notes: list[str] = []
    report = on_image or (lambda done, total: None)
    report(0, len(images))
    for done, (path, gray) in enumerate(images.items(), start=1):
        if (gray.shape[1], gray.shape[0]) != size:
            notes.append(f"{path.name}: {gray.shape[1]}x{gray.shape[0]} fitted to {size[0]}x{size[1]} at the right/bottom edge")
        board = detect_board(_fit_size(gray, size), pattern)
        if board.corners_px is None:
            missed[path] = board.reason
        else:
            found.append(path)
            corners.append(board.corners_px)
            if board.method == "sb":
                notes.append(f"{path.name}: board found by the SB detector ({board.reason})")
        report(done, len(images))
    if len(found) < MIN_BOARDS:
        cols, rows = pattern
        raise CalibrationError(
            f"chessboard {cols}x{rows} found in only {len(found)} of {len(paths)} image(s) ({_where(paths)}); need at least "
            f"{MIN_BOARDS} (10 or more for a good calibration): check that --pattern counts inner corners "
            f"(9x6 for a board of 10×7 squares) and that the whole board is visible and sharp"
        )

    objects = [board_points_m(pattern, square_m)] * len(found)
    try:
        rms, matrix, dist, rvecs, tvecs = cv2.calibrateCamera(objects, corners, size, None, None)
    except cv2.error as exc:
        raise CalibrationError(f"OpenCV could not calibrate from {len(found)} board(s) ({_where(paths)}): {exc}") from exc
    errors = tuple(_reprojection_rms_px(o, c, r, t, matrix, dist) for o, c, r, t in zip(objects, corners, rvecs, tvecs, strict=True))
    try:
        camera = CameraModel(
            width_px=size[0], height_px=size[1], fx_px=float(matrix[0, 0]), fy_px=float(matrix[1, 1]),
            cx_px=float(matrix[0, 2]), cy_px=float(matrix[1, 2]), distortion=tuple(float(k) for k in dist.ravel()),
            mount_height_m=None if mount_height_m is None else float(mount_height_m), pitch_deg=float(pitch_deg), rms_px=float(rms),
        )
    except ValueError as exc:  # e.g. a degenerate solution with a non-positive focal length
        raise CalibrationError(f"calibration from {_where(paths)} gave an impossible camera: {exc}; add photos at varied angles") from exc
    ordered_missed = tuple(p for p in paths if p in missed)
    return CalibrationResult(
        camera=camera, rms_px=float(rms), found=tuple(found), missed=ordered_missed,
        per_image_error_px=errors, missed_reasons=tuple(missed[p] for p in ordered_missed), notes=tuple(notes),
    )


def _reprojection_rms_px(objects: np.ndarray, corners: np.ndarray, rvec: np.ndarray, tvec: np.ndarray,
                         matrix: np.ndarray, dist: np.ndarray) -> float:
    """RMS distance between detected and re-projected corners of one board (same measure as calibrateCamera's)."""
    projected, _ = cv2.projectPoints(objects, rvec, tvec, matrix, dist)
    return float(np.sqrt(np.mean(np.sum((projected.reshape(-1, 2) - corners.reshape(-1, 2)) ** 2, axis=1))))


def _positive(value: object) -> bool:
    """A finite number > 0 (bools are not numbers here)."""
    return (finite_reading(value) or 0.0) > 0


def _where(paths: Sequence[Path]) -> str:
    """The folder(s) the images came from, for error messages."""
    folders = sorted({str(p.parent) for p in paths})
    return "folder " + folders[0] if len(folders) == 1 else "folders " + ", ".join(folders[:3]) + (" ..." if len(folders) > 3 else "")
