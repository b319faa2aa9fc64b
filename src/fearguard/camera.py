"""Pinhole camera model: intrinsics, lens distortion and how the camera is mounted on the car.

Image axes: u to the right, v down (pixels). Vehicle axes: x forward, y left, z up (metres).
The camera sits ``mount_height_m`` above a flat ground, looking forward, pitched down by ``pitch_deg``, and
``front_offset_m`` behind the vehicle's front: ranges to what stands ahead are given from the front.
Used for undistortion, bearings of things in the image, and range to a point on the ground
(D = H / tan(pitch + arctan((v − cy) / fy)), the model-car paper's formula).
"""

from __future__ import annotations

import math
from dataclasses import dataclass, fields, replace
from functools import lru_cache
from pathlib import Path
from typing import Any

import cv2
import numpy as np

from fearguard.errors import CameraError
from fearguard.files.reader import Table, number_list, read_toml

DEFAULT_HFOV_DEG = 60.0  # [deg] horizontal field of view assumed when no calibration is given


@dataclass(frozen=True)
class CameraModel:
    """Intrinsics (pixels), OpenCV distortion (k1, k2, p1, p2, k3) and mounting (m, deg down)."""

    width_px: int
    height_px: int
    fx_px: float
    fy_px: float
    cx_px: float
    cy_px: float
    distortion: tuple[float, ...] = ()
    mount_height_m: float | None = None  # None: unknown, so no ground-plane ranges
    pitch_deg: float = 0.0  # positive = looking down
    rms_px: float | None = None  # calibration's reprojection error, when calibrated
    front_offset_m: float = 0.0  # the lens's distance behind the vehicle's front (bumper), along the car: what is ahead
    #   is reported from the front, where a collision happens and a range sensor measures (a windscreen camera: ~2 m)

    def __post_init__(self) -> None:
        if self.width_px <= 0 or self.height_px <= 0:
            raise ValueError(f"CameraModel image size must be positive, got {self.width_px}x{self.height_px}")
        for name in ("fx_px", "fy_px", "cx_px", "cy_px", "pitch_deg"):
            if not math.isfinite(getattr(self, name)):
                raise ValueError(f"CameraModel.{name} must be finite, got {getattr(self, name)!r}")
        if self.fx_px <= 0 or self.fy_px <= 0:
            raise ValueError(f"CameraModel focal lengths must be > 0, got fx={self.fx_px}, fy={self.fy_px}")
        if self.mount_height_m is not None and not (math.isfinite(self.mount_height_m) and self.mount_height_m > 0):
            raise ValueError(f"CameraModel.mount_height_m must be > 0 or None, got {self.mount_height_m!r}")
        if not (math.isfinite(self.front_offset_m) and self.front_offset_m >= 0.0):
            raise ValueError(f"CameraModel.front_offset_m must be finite and >= 0, got {self.front_offset_m!r}")
        if not all(math.isfinite(k) for k in self.distortion):
            raise ValueError(f"CameraModel.distortion must be finite, got {self.distortion!r}")

    @classmethod
    def default(
        cls, width_px: int, height_px: int, hfov_deg: float = DEFAULT_HFOV_DEG,
        mount_height_m: float | None = None, pitch_deg: float = 0.0,
    ) -> CameraModel:
        """An uncalibrated camera: square pixels, centred principal point, the given field of view."""
        f = (width_px / 2.0) / math.tan(math.radians(hfov_deg) / 2.0)
        return cls(width_px, height_px, f, f, width_px / 2.0, height_px / 2.0, (), mount_height_m, pitch_deg)

    def scaled_to(self, width_px: int, height_px: int) -> CameraModel:
        """The same camera at another resolution (a resized frame): intrinsics scale with the image."""
        if (width_px, height_px) == (self.width_px, self.height_px):
            return self
        sx, sy = width_px / self.width_px, height_px / self.height_px
        return replace(
            self, width_px=width_px, height_px=height_px, fx_px=self.fx_px * sx, fy_px=self.fy_px * sy,
            cx_px=self.cx_px * sx, cy_px=self.cy_px * sy,
        )

    @property
    def matrix(self) -> np.ndarray:
        """The 3×3 intrinsic matrix K."""
        return np.array([[self.fx_px, 0.0, self.cx_px], [0.0, self.fy_px, self.cy_px], [0.0, 0.0, 1.0]])

    def bearing_deg(self, u_px: float) -> float:
        """Horizontal angle of image column u from the optical axis (deg, + = left, ISO 8855)."""
        return -math.degrees(math.atan2(u_px - self.cx_px, self.fx_px))

    def horizon_v_px(self) -> float:
        """Image row of the horizon (flat ground, far away)."""
        return self.cy_px - self.fy_px * math.tan(math.radians(self.pitch_deg))

    def ground_range_m(self, v_px: float) -> float | None:
        """Forward distance to the ground point seen at image row v; None at/above the horizon or if height unknown."""
        if self.mount_height_m is None:
            return None
        angle = math.radians(self.pitch_deg) + math.atan2(v_px - self.cy_px, self.fy_px)
        if angle <= 1e-6:
            return None
        return self.mount_height_m / math.tan(angle)

    def ground_row_px(self, range_m: float) -> float | None:
        """Image row of the ground straight ahead ``range_m`` from the camera (``ground_range_m``'s inverse; it may lie
        outside the image); None without a mount height or for a range the camera cannot face (≤ 0, not finite, or so
        near below a camera pitched up that it lies behind the image plane)."""
        if self.mount_height_m is None or not (0.0 < range_m < math.inf):
            return None
        below_axis = math.atan2(self.mount_height_m, range_m) - math.radians(self.pitch_deg)
        if below_axis >= 0.5 * math.pi - 1e-6:
            return None  # nearer than the ground straight below the lens' plane: behind the image plane
        return self.cy_px + self.fy_px * math.tan(below_axis)

    def range_ahead_m(self, v_px: float) -> float | None:
        """Distance from the vehicle's front to the ground point seen at image row v: the ground range less
        ``front_offset_m``, never below 0 (None as ``ground_range_m``). The range of an object standing on that row."""
        ground = self.ground_range_m(v_px)
        return None if ground is None else max(0.0, ground - self.front_offset_m)

    def project_ground(self, x_fwd_m: np.ndarray, y_left_m: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """Image (u, v) of ground points in vehicle axes, and a mask of those in front of the camera."""
        h = self.mount_height_m if self.mount_height_m is not None else 1.0
        return self.project_points(x_fwd_m, y_left_m, np.zeros_like(np.asarray(x_fwd_m, dtype=float)) - h)

    def project_points(
        self, x_fwd_m: np.ndarray, y_left_m: np.ndarray, z_up_m: np.ndarray
    ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """Image (u, v) of points given relative to the camera centre (vehicle axes), no distortion."""
        p = math.radians(self.pitch_deg)
        x, y, z = (np.asarray(a, dtype=float) for a in (x_fwd_m, y_left_m, z_up_m))
        depth = x * math.cos(p) - z * math.sin(p)
        down = -x * math.sin(p) - z * math.cos(p)
        front = depth > 1e-6
        safe = np.where(front, depth, 1.0)
        u = self.cx_px + self.fx_px * (-y) / safe
        v = self.cy_px + self.fy_px * down / safe
        return u, v, front

    def undistort(self, frame: np.ndarray) -> np.ndarray:
        """The frame with lens distortion removed (same size and intrinsics); unchanged if none."""
        if not any(self.distortion):
            return frame
        h, w = frame.shape[:2]
        map1, map2 = _undistort_maps(self.scaled_to(w, h))
        return cv2.remap(frame, map1, map2, cv2.INTER_LINEAR)


@lru_cache(maxsize=8)
def _undistort_maps(camera: CameraModel) -> tuple[np.ndarray, np.ndarray]:
    """Remap tables, computed once per camera (undistorting a frame is then one cv2.remap)."""
    size = (camera.width_px, camera.height_px)
    dist = np.array(camera.distortion, dtype=float)
    return cv2.initUndistortRectifyMap(camera.matrix, dist, None, camera.matrix, size, cv2.CV_16SC2)


# -- camera.toml ------------------------------------------------------------------------------
_TABLE = "camera"


def save_camera(camera: CameraModel, path: str | Path) -> None:
    """Write ``camera.toml`` (the format ``load_camera`` reads, and ``fearguard calibrate`` writes)."""
    lines = [f"[{_TABLE}]"]
    for f in fields(camera):
        value = getattr(camera, f.name)
        if value is None:
            continue
        if isinstance(value, tuple):
            lines.append(f"{f.name} = [{', '.join(repr(float(k)) for k in value)}]")
        elif isinstance(value, int):
            lines.append(f"{f.name} = {value}")
        else:
            lines.append(f"{f.name} = {float(value)!r}")
    Path(path).write_text("\n".join(lines) + "\n", encoding="utf-8")


_DISTORTION_COUNTS = (0, 4, 5, 8, 12, 14)  # [-] coefficient counts OpenCV's distortion models take
_REQUIRED = ("width_px", "height_px", "fx_px", "fy_px", "cx_px", "cy_px")


def load_camera(path: str | Path) -> CameraModel:
    """Read ``camera.toml``; a wrong file raises CameraError naming the file, the line and the key."""
    data, src = read_toml(path, CameraError, "run `fearguard calibrate` to make one")
    if _TABLE not in data:
        raise src.error(_TABLE, f"missing table; expected [{_TABLE}] with {', '.join(_REQUIRED)}, ...")
    t = Table(src, data[_TABLE], _TABLE, [f.name for f in fields(CameraModel)])
    missing = [n for n in _REQUIRED if not t.has(n)]
    if missing:
        raise src.error(_TABLE, f"missing key(s) {', '.join(missing)}")
    kwargs: dict[str, Any] = {}
    for name in t.known:
        if not t.has(name):
            continue
        if name == "distortion":
            coefficients = number_list(t.data[name])
            if coefficients is None or len(coefficients) not in _DISTORTION_COUNTS:
                raise t.fail(name, f"expected a list of 4, 5, 8, 12 or 14 finite numbers, got {t.data[name]!r}")
            kwargs[name] = tuple(coefficients)
        elif name in ("width_px", "height_px"):
            kwargs[name] = t.integer(name, low=1, high=1_000_000)
        else:
            kwargs[name] = t.number(name)
    try:
        return CameraModel(**kwargs)
    except ValueError as exc:
        raise src.error(_TABLE, str(exc)) from exc


# -- presets for the common cars ----------------------------------------------------------------
# Raspberry Pi Camera Module v2 (Sony IMX219): f = 3.04 mm, 1.12 µm pixels, 3280×2464 full sensor; the 4:3
# binned modes keep the full field of view (62.2° × 48.8°), so fx = 3.04 / 1.12e-3 × width / 3280.
_PICAM_V2_FX_PER_WIDTH = 3.04 / 1.12e-3 / 3280  # [px per px of width]
# The 160° "wide-angle" OV5647 modules sold with Donkey Car kits: a typical calibration at 640×480 gives
# fx ≈ 330 px (≈ 88° horizontal for the pinhole part) with strong barrel distortion; calibrate yours to be exact.
_WIDE_FX_PER_WIDTH = 330.0 / 640.0  # [px per px of width]
_WIDE_DISTORTION = (-0.32, 0.11, 0.0, 0.0, -0.015)  # (k1, k2, p1, p2, k3), typical for those lenses
DONKEY_CAMERA_HEIGHT_M = 0.18  # [m] lens above the ground on the stock Donkey roll cage; measure yours
DONKEY_CAMERA_PITCH_DEG = 20.0  # [deg] looking down on the stock mount; measure yours


def _preset(width_px: int, height_px: int, fx_per_width: float, distortion: tuple[float, ...] = ()) -> CameraModel:
    f = fx_per_width * width_px
    return CameraModel(
        width_px, height_px, f, f, width_px / 2.0, height_px / 2.0, distortion, DONKEY_CAMERA_HEIGHT_M, DONKEY_CAMERA_PITCH_DEG
    )


CAMERA_PRESETS: dict[str, CameraModel] = {
    "picam-v2-160x120": _preset(160, 120, _PICAM_V2_FX_PER_WIDTH),  # Donkey's default IMAGE_W × IMAGE_H
    "picam-v2-320x240": _preset(320, 240, _PICAM_V2_FX_PER_WIDTH),
    "donkey-wide-160x120": _preset(160, 120, _WIDE_FX_PER_WIDTH, _WIDE_DISTORTION),
}


def camera_preset(name: str) -> CameraModel:
    """A named camera of a common car (``CAMERA_PRESETS``), to start without a calibration."""
    try:
        return CAMERA_PRESETS[name]
    except KeyError:
        raise ValueError(f"unknown camera preset {name!r}; expected one of {', '.join(CAMERA_PRESETS)} or a camera.toml") from None
