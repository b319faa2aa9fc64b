"""QR markers in camera pixels: OpenCV's two QR detectors, a cheap per-frame path and a fallback cascade.

OpenCV 5 offers ``cv2.QRCodeDetector`` (finder patterns by line scans) and ``cv2.QRCodeDetectorAruco``
(finder patterns found as ArUco-like squares); each decodes codes the other misses. Small codes
(< ~3 px per module) are found more often than they are decoded, so a quadrilateral that was found but
did not decode is cut out, enlarged and sharpened, and decoded again ("refine").

Cheap path (``thorough=False``, the per-frame default): one ArUco-based detection pass with a single
threshold window on the grey frame scaled to a 640 px long side; each quadrilateral found is decoded
in a crop of the frame, and only one that does not decode escalates to the (quick) refine attempts.
A frame without any QR costs one detection pass (~2 ms at 640×480), a frame with a board ~6 ms.
Thorough path (stills, offline, a stopped car): whole-frame steps that run only while nothing decoded —
ArUco, plain, ½× (big frames), 2× (small frames), pad + 3× (bare codes without quiet zone), adaptive and
Otsu binarisation — each followed by the refine cascade on its undecoded candidates.
cv2.QRCodeDetector is never given a binarised image: OpenCV 5.0 aborts the process (heap corruption)
on some (tests/vision/test_qr.py names one). Measured counts and costs: docs/qr.md, benchmarks/bench_qr.py.
"""

from __future__ import annotations

import math
from collections.abc import Callable, Iterable
from dataclasses import dataclass
from functools import cache

import cv2
import numpy as np

CHEAP_WORK_SIDE_PX = 640  # [px] the cheap pass works at this long side: bigger frames shrink (cost), smaller grow (recall)
CHEAP_RESIZE_MIN = 0.05  # [-] frames within 5 % of that size are used as they are
CHEAP_THRESH_WIN_PX = 13  # [px] one adaptive-threshold window for the cheap pass (ArUco default tries 3, 13, 23)
# [-] of the 640 px side: the cheap pass skips contours shorter than 32 px (a finder pattern of 7 modules < 8 px a side, a
# module < 1.2 px: not decodable); ArUco's default 0.02 keeps them, ~10 % of the pass, for the same decodes (docs/qr.md)
CHEAP_MIN_PERIMETER_RATE = 0.05
MIN_SIDE_PX = 21  # [px] smaller images cannot hold a QR code (version 1 is 21 modules)
UPSCALE_BELOW_PX = 1000  # [px] the thorough cascade enlarges 2× frames whose long side is below this
DOWNSCALE_ABOVE_PX = 1000  # [px] ... and halves frames whose long side is above this
TINY_BELOW_PX = 400  # [px] frames this small may be a bare code without quiet zone: pad and enlarge 3×
REFINE_MARGIN = 0.35  # [-] crop margin around a candidate, share of its size (room for a quiet zone)
REFINE_TARGET_PX = 240  # [px] a candidate is enlarged until its size is about this ...
REFINE_MAX_SCALE = 6.0  # [-] ... but never more than this
REFINE_MIN_SIZE_PX = 12  # [px] candidates smaller than this are noise, not codes
CANDIDATE_MAX = 4  # [-] the thorough path refines at most this many undecoded candidates per step (largest first)
CHEAP_DECODE_MAX = 2  # [-] the cheap path decodes at most the two largest quadrilaterals (~2 ms each)
CHEAP_CANDIDATE_MAX = 1  # [-] ... and refines only the largest undecoded one (nearest board; the next frames see it bigger)
CROP_MARGIN_PX = 8  # [px] margin of the crop a found quadrilateral is decoded in
SAME_PLACE_SHARE = 0.25  # [-] candidates whose centres are closer than this share of their size are the same code
UNSHARP_SIGMA_MODULES = 0.9  # [px at source scale] unsharp-mask blur radius, about one module of a small code
DEBLUR_SIGMA_PX = 1.0  # [px] blur the deconvolution undoes: a slightly soft lens / motion at 640×480
DEBLUR_ITERATIONS = 30  # [-] Richardson–Lucy iterations (10: no gain; 30: +4 of 18 boards at 70 px and at 80 px, sigma 1)
UNSHARP_AMOUNT = 2.0  # [-] unsharp-mask strength (restores module contrast lost to ~1 px of blur)


@dataclass(frozen=True)
class QrMarker:
    """One decoded QR code: its text and its four corners in the frame's pixels (x right, y down)."""

    payload: str
    corners_px: tuple[tuple[float, float], ...]


# -- detectors -------------------------------------------------------------------------------------
@cache
def _plain() -> cv2.QRCodeDetector:
    return cv2.QRCodeDetector()


@cache
def _aruco() -> cv2.QRCodeDetectorAruco:
    return cv2.QRCodeDetectorAruco()


@cache
def _aruco_fast() -> cv2.QRCodeDetectorAruco:
    """ArUco-based detector with one threshold window (~2× cheaper than the default three, finds 98 instead of 110
    of 144 boards of 70–120 px) and no contours too short to decode (docs/qr.md)."""
    det = cv2.QRCodeDetectorAruco()
    params = det.getArucoParameters()
    params.adaptiveThreshWinSizeMin = CHEAP_THRESH_WIN_PX
    params.adaptiveThreshWinSizeMax = CHEAP_THRESH_WIN_PX
    params.minMarkerPerimeterRate = CHEAP_MIN_PERIMETER_RATE
    det.setArucoParameters(params)
    return det


# (decoded markers, undecoded candidate quadrilaterals), both in the coordinates of the image given
_Found = tuple[list[QrMarker], list[np.ndarray]]


def _quads(points: object) -> list[np.ndarray]:
    if points is None:
        return []
    arr = np.asarray(points, dtype=np.float64)
    if arr.size % 8 != 0 or arr.size == 0:
        return []
    return [q for q in arr.reshape(-1, 4, 2) if np.all(np.isfinite(q))]


def _marker(text: object, quad: np.ndarray) -> QrMarker | None:
    if not isinstance(text, str) or not text:
        return None
    return QrMarker(text, _corners(quad))


def _run_single(det: cv2.QRCodeDetector | cv2.QRCodeDetectorAruco, img: np.ndarray) -> _Found:
    try:
        text, points, _ = det.detectAndDecode(img)
    except cv2.error:
        return [], []
    quads = _quads(points)
    if not quads:
        return [], []
    m = _marker(text, quads[0])
    return ([m], []) if m else ([], quads[:1])


def _run_multi(det: cv2.QRCodeDetector | cv2.QRCodeDetectorAruco, img: np.ndarray) -> _Found:
    try:
        ok, texts, points, _ = det.detectAndDecodeMulti(img)
    except cv2.error:
        return [], []
    if not ok:
        return [], []
    quads = _quads(points)
    found, undecoded = [], []
    for text, quad in zip(texts, quads, strict=False):
        m = _marker(text, quad)
        if m:
            found.append(m)
        else:
            undecoded.append(quad)
    return found, undecoded


# -- pre-processing ---------------------------------------------------------------------------------
def _otsu(grey: np.ndarray) -> np.ndarray:
    return cv2.threshold(grey, 0, 255, cv2.THRESH_BINARY | cv2.THRESH_OTSU)[1]


def _adaptive(grey: np.ndarray) -> np.ndarray:
    return cv2.adaptiveThreshold(grey, 255, cv2.ADAPTIVE_THRESH_GAUSSIAN_C, cv2.THRESH_BINARY, 31, 5)


def _unsharp(grey: np.ndarray, sigma_px: float) -> np.ndarray:
    blurred = cv2.GaussianBlur(grey, (0, 0), sigma_px)
    return cv2.addWeighted(grey, 1.0 + UNSHARP_AMOUNT, blurred, -UNSHARP_AMOUNT, 0)


def _deblurred(crop: np.ndarray, scale: float) -> np.ndarray:
    """Richardson–Lucy deconvolution of a Gaussian blur (sigma DEBLUR_SIGMA_PX), then enlarged by ``scale``.

    Written here because OpenCV has no deconvolution (scikit-image is not a dependency); a few lines of GaussianBlur.
    """
    observed = crop.astype(np.float32) + 1.0  # +1: no division by zero in dark areas
    estimate = observed.copy()
    for _ in range(DEBLUR_ITERATIONS):
        ratio = observed / (cv2.GaussianBlur(estimate, (0, 0), DEBLUR_SIGMA_PX) + 1e-3)
        estimate *= cv2.GaussianBlur(ratio, (0, 0), DEBLUR_SIGMA_PX)
    sharp = np.clip(estimate - 1.0, 0, 255).astype(np.uint8)
    return _resize(sharp, scale, cv2.INTER_CUBIC) if scale > 1.0 else sharp


def _resize(grey: np.ndarray, factor: float, interpolation: int) -> np.ndarray:
    return cv2.resize(grey, None, fx=factor, fy=factor, interpolation=interpolation)


# -- refine: cut a candidate out, enlarge, sharpen, decode ----------------------------------------------
def _refine(grey: np.ndarray, quad: np.ndarray, thorough: bool) -> QrMarker | None:
    """Decode one undecoded candidate (quad in ``grey``'s pixels) from an enlarged, sharpened (thorough: deblurred) crop."""
    x0, y0 = quad.min(axis=0)
    x1, y1 = quad.max(axis=0)
    size = max(x1 - x0, y1 - y0)
    if not math.isfinite(size) or size < REFINE_MIN_SIZE_PX:
        return None
    margin = REFINE_MARGIN * size
    h, w = grey.shape
    c0, r0 = int(max(0.0, x0 - margin)), int(max(0.0, y0 - margin))
    c1, r1 = int(min(w, x1 + margin + 1)), int(min(h, y1 + margin + 1))
    if c1 - c0 < MIN_SIDE_PX or r1 - r0 < MIN_SIDE_PX:
        return None
    crop = grey[r0:r1, c0:c1]
    scale = float(np.clip(REFINE_TARGET_PX / size, 1.0, REFINE_MAX_SCALE))
    big = _resize(crop, scale, cv2.INTER_CUBIC) if scale > 1.0 else crop
    sharp = _unsharp(big, UNSHARP_SIGMA_MODULES * scale)
    attempts = [(_aruco, lambda: big), (_plain, lambda: big), (_aruco, lambda: sharp)]
    if thorough:  # no binarised image for _plain (see the module docstring)
        attempts += [(_aruco, lambda: _otsu(sharp)), (_aruco, lambda: _deblurred(crop, scale)), (_plain, lambda: _deblurred(crop, scale))]
    for det, image in attempts:
        found, _ = _run_single(det(), image())
        if found:
            return QrMarker(found[0].payload, _corners(np.array(found[0].corners_px) / scale + (c0, r0)))
    return None


# -- the two paths ---------------------------------------------------------------------------------
@dataclass(frozen=True)
class _Prepared:
    """An image made from the grey frame; a point (x, y) in it is (x / factor − pad_px, ...) in the frame."""

    image: np.ndarray
    factor: float = 1.0
    pad_px: float = 0.0

    def to_frame(self, quad: np.ndarray) -> np.ndarray:
        return quad / self.factor - self.pad_px


def _same(g: np.ndarray) -> _Prepared:
    return _Prepared(g)


def _up2(g: np.ndarray) -> _Prepared | None:
    return _Prepared(_resize(g, 2.0, cv2.INTER_CUBIC), 2.0) if max(g.shape) < UPSCALE_BELOW_PX else None


def _down2(g: np.ndarray) -> _Prepared | None:
    return _Prepared(_resize(g, 0.5, cv2.INTER_AREA), 0.5) if max(g.shape) > DOWNSCALE_ABOVE_PX else None


def _tiny(g: np.ndarray) -> _Prepared | None:
    """A small image may be a bare code printed edge to edge: give it a quiet zone and sharp 3× modules."""
    if max(g.shape) >= TINY_BELOW_PX:
        return None
    pad = max(4, max(g.shape) // 20)
    padded = cv2.copyMakeBorder(g, pad, pad, pad, pad, cv2.BORDER_CONSTANT, value=255)
    return _Prepared(_resize(padded, 3.0, cv2.INTER_NEAREST), 3.0, float(pad))


def _aruco_multi(img: np.ndarray) -> _Found:
    return _run_multi(_aruco(), img)


def _plain_single(img: np.ndarray) -> _Found:
    return _run_single(_plain(), img)


# the thorough cascade in the order measured to decode most per cost (docs/qr.md); it stops at the first step that decodes
THOROUGH_STEPS: tuple[tuple[str, Callable[[np.ndarray], _Prepared | None], Callable[[np.ndarray], _Found]], ...] = (
    ("aruco", _same, _aruco_multi),
    ("plain", _same, _plain_single),  # the baseline detectAndDecode: the cascade never decodes less than it
    ("aruco_down2", _down2, _aruco_multi),
    ("aruco_up2", _up2, _aruco_multi),
    ("plain_up2", _up2, _plain_single),
    ("aruco_tiny", _tiny, _aruco_multi),
    ("aruco_adaptive", lambda g: _Prepared(_adaptive(g)), _aruco_multi),
    ("aruco_otsu", lambda g: _Prepared(_otsu(g)), _aruco_multi),
)


def _decoded(grey: np.ndarray, prepared: _Prepared, found: _Found, refined: list[np.ndarray]) -> list[QrMarker]:
    """Markers decoded in ``prepared`` mapped to frame pixels, plus undecoded candidates refined from ``grey``.

    ``refined``: candidates already tried by earlier steps, so a code that several steps find is refined once.
    """
    markers = [QrMarker(m.payload, _corners(prepared.to_frame(np.array(m.corners_px)))) for m in found[0]]
    candidates = sorted((prepared.to_frame(q) for q in found[1]), key=_area, reverse=True)
    for quad in candidates[:CANDIDATE_MAX]:
        if any(_same_place(quad, old) for old in refined):
            continue
        refined.append(quad)
        m = _refine(grey, quad, thorough=True)
        if m is not None:
            markers.append(m)
    return markers


def _area(quad: np.ndarray) -> float:
    return float(cv2.contourArea(quad.astype(np.float32)))


def _same_place(a: np.ndarray, b: np.ndarray) -> bool:
    """Two candidates are the same code when their centres are closer than a quarter of the smaller one's size."""
    size = min(np.ptp(a, axis=0).max(), np.ptp(b, axis=0).max())
    return bool(np.hypot(*(a.mean(axis=0) - b.mean(axis=0))) < SAME_PLACE_SHARE * size)


def _corners(quad: np.ndarray) -> tuple[tuple[float, float], ...]:
    return tuple((float(x), float(y)) for x, y in quad)


def _cheap(grey: np.ndarray) -> tuple[list[QrMarker], str]:
    """Quadrilaterals from one fast pass at 640 px; each (largest first) decoded in a crop of the frame, refined if it fails."""
    factor = CHEAP_WORK_SIDE_PX / max(grey.shape)
    if abs(factor - 1.0) < CHEAP_RESIZE_MIN:
        prepared = _Prepared(grey)
    else:
        prepared = _Prepared(_resize(grey, factor, cv2.INTER_AREA if factor < 1.0 else cv2.INTER_LINEAR), factor)
    try:
        ok, points = _aruco_fast().detectMulti(prepared.image)
    except cv2.error:
        return [], ""
    if not ok:
        return [], ""  # the common case: nothing QR-like in view, one detector pass spent
    quads = sorted((prepared.to_frame(q) for q in _quads(points)), key=_area, reverse=True)[:CHEAP_DECODE_MAX]
    markers, undecoded = [], []
    for quad in quads:
        text = _decode_in_crop(grey, quad)
        if text:
            markers.append(QrMarker(text, _corners(quad)))
        else:
            undecoded.append(quad)
    step = "cheap" if markers else ""
    for quad in undecoded[:CHEAP_CANDIDATE_MAX]:
        m = _refine(grey, quad, thorough=False)
        if m is not None:
            markers.append(m)
            step = step or "cheap_refine"
    return markers, step


def _decode_in_crop(grey: np.ndarray, quad: np.ndarray) -> str:
    """Decode a found quadrilateral in a crop around it: OpenCV's decode costs ~3× more on the whole frame."""
    x0, y0 = np.maximum(quad.min(axis=0) - CROP_MARGIN_PX, 0).astype(int)
    x1, y1 = (quad.max(axis=0) + CROP_MARGIN_PX).astype(int)
    crop = np.ascontiguousarray(grey[y0:y1, x0:x1])
    if min(crop.shape) < MIN_SIDE_PX:
        return ""
    points = (quad - (x0, y0)).reshape(1, 4, 2).astype(np.float32)
    for det in (_aruco(), _plain()):
        try:
            text = det.decode(crop, points)[0]
        except cv2.error:
            continue
        if isinstance(text, str) and text:
            return text
    return ""


def _thorough(grey: np.ndarray) -> tuple[list[QrMarker], str]:
    refined: list[np.ndarray] = []
    for name, prepare, run in THOROUGH_STEPS:
        prepared = prepare(grey)
        if prepared is None:
            continue
        markers = _decoded(grey, prepared, run(prepared.image), refined)
        if markers:
            return markers, name
    return [], ""


def _grey(frame: object) -> np.ndarray | None:
    """The frame as a contiguous grey uint8 image, or None when it is not an image (BGR, BGRA or grey)."""
    if not isinstance(frame, np.ndarray) or frame.dtype != np.uint8:
        return None
    if frame.ndim == 3 and frame.shape[2] == 1:
        frame = frame[:, :, 0]
    if frame.ndim == 2:
        grey = frame
    elif frame.ndim == 3 and frame.shape[2] in (3, 4):
        grey = cv2.cvtColor(np.ascontiguousarray(frame), cv2.COLOR_BGR2GRAY if frame.shape[2] == 3 else cv2.COLOR_BGRA2GRAY)
    else:
        return None
    if min(grey.shape) < MIN_SIDE_PX:
        return None
    return np.ascontiguousarray(grey)


def _unique(markers: Iterable[QrMarker]) -> tuple[QrMarker, ...]:
    seen: dict[str, QrMarker] = {}
    for m in markers:
        seen.setdefault(m.payload, m)
    return tuple(seen.values())


def detect_qr_traced(frame_bgr: object, thorough: bool = False) -> tuple[tuple[QrMarker, ...], str]:
    """``detect_qr`` plus the name of the step that decoded ("" if none): for benchmarks and docs."""
    try:
        grey = _grey(frame_bgr)
        if grey is None:
            return (), ""
        markers, step = _thorough(grey) if thorough else _cheap(grey)
        return _unique(markers), step
    except Exception:  # per-frame contract: never raise; no marker read is the safe side (staleness grows)
        return (), ""


def detect_qr(frame_bgr: object, thorough: bool = False) -> tuple[QrMarker, ...]:
    """Decoded QR markers in a BGR (or grey/BGRA) uint8 frame; ``()`` for none or for anything that is not an image.

    ``thorough=False``: cheap per-frame path; ``thorough=True``: the whole fallback cascade (for stills, offline).
    """
    return detect_qr_traced(frame_bgr, thorough)[0]
