"""The vehicle ahead in the ego lane: found by its dark underside, tracked, turned into bearing and range.

Classic cues: whatever its colour, a vehicle casts a dark band on the road under its rear, and it shows
two red tail lights. Pixels much darker than the road reference inside the ego lane (widened a little)
form connected blobs; a blob as wide as a vehicle at that image row (``WIDTH_RANGE`` of the lane width
there) with non-road pixels and some tail-light red above it is a vehicle (a tree shadow has no lamps);
its box is the blob's width, ``ASPECT`` × width tall, standing on the blob's bottom row. Lamps are not
always seen (dark or unlit lamps, a far car's few pixels): such a box is a vehicle once its track is seen
*moving along the road as one rigid thing* — over ``MOTION_WINDOW_S`` its size holds and its ground range,
with the car's own speed added, advances at ``MOVING_SHARE`` of the car's speed or more, beyond the fit's
noise (``moving_over_ground``). A shadow, a patch of tar or a pothole stands still on the ground (its range
closes at exactly the car's speed); a standing lamp-less vehicle is left to the object search
(vision/obstacle.py), as before.
Boxes from an external detector enter as ``LeadBox`` too. Bearing comes from the camera model, range
from ground-plane geometry (needs the camera's mounting height) — or, when fused, from the ultrasonic.
"""

from __future__ import annotations

import math
from collections import deque
from dataclasses import dataclass
from typing import TYPE_CHECKING

import cv2
import numpy as np

from fearguard.camera import CameraModel
from fearguard.observation import Lead, LeadBox  # plain values (LeadBox re-exported here for existing imports)
from fearguard.sensors.kalman import kalman_filter
from fearguard.vision.lanes import LaneLine, RoadRegion

if TYPE_CHECKING:
    from filterpy.kalman import KalmanFilter

DARK_RATIO = 0.55  # [-] underside pixels are darker than this share of the road reference
WIDTH_RANGE = (0.3, 1.1)  # [-] blob width as a share of the lane width at its bottom row (a shadow across the road is wider)
LANE_WIDEN = 0.15  # [-] of the lane width: the search area reaches this far past each boundary
ASPECT = 0.8  # [-] box height / width of a vehicle's rear
MAX_ASPECT = 1.3  # [-] a blob taller than this × its width is not a vehicle's rear
MIN_FILL = 0.35  # [-] blob area / bounding-box area
ABOVE_FOREIGN_MIN = 0.35  # [-] share of non-road pixels in the box above the underside
RED_HUE_MAX = 8  # [OpenCV hue 0..180] tail-light red is within this of hue 0
RED_SAT_MIN = 120  # [0..255] and this saturated
TAIL_LIGHT_SHARE = 0.004  # [-] share of the box that must be tail-light red (two small lamps)
CONFIRM_HITS = 2  # [frames] detections in a row before a new lead is reported
LOST_AFTER_S = 0.5  # [s] a track coasts this long without detections
GATE_CHI2 = 16.3  # [-] chi-square, 3 dof, p = 0.001
UNLIT_WIDTH_MAX = 0.85  # [-] of the lane width: a lamp-less box wider than this is no vehicle (a 2.55 m truck in a 3 m lane)
MOTION_WINDOW_S = 1.0  # [s] a lamp-less track's ground ranges fitted for its speed over the ground (its last this long)
MOTION_MIN_SAMPLES = 8  # [-] ranges in the window before a speed is judged
MOVING_SHARE = 0.6  # [-] a lamp-less track is a vehicle when it moves along the road at this share of the car's speed or more
#   (a dappled shadow's blob, its edges re-forming as the car passes, has read 0.4)
MOVING_MIN_MPS = 0.3  # [m/s] and at least this (a standing car's ranges still wander by the box's pixel steps)
RIGID_SPREAD = 0.1  # [-] range × box width may vary by this standard deviation over its mean (a box 20 px wide 30 m ahead:
#   ±1 px and ±1 row are 5 % and 4 %); a shadow's blob varies 0.14 and more
RANGE_NOISE_SHARE = 0.03  # [-] a box's ground range is no more precise than this share of it (a pixel row is ~3 % of
#   the range 12 m ahead from 1.5 m up at 320 px): the floor of the fit's residual spread


def lead_from_box(box: LeadBox, camera: CameraModel) -> Lead:
    """Bearing of the box centre and ground-plane range of its bottom edge from the car's front (None without mounting
    height)."""
    x, y, w, h = (float(v) for v in (box.x_px, box.y_px, box.w_px, box.h_px))  # numpy scalars of any width: no cast overflow
    return Lead(camera.bearing_deg(x + 0.5 * w), camera.range_ahead_m(y + h))


@dataclass(frozen=True)
class Sighting:
    """A vehicle-like box seen in one frame; ``lit``: with tail lights (else a vehicle only once seen moving)."""

    box: LeadBox
    lit: bool


def detect_lead(
    gray: np.ndarray, hls: np.ndarray, region: RoadRegion, left: LaneLine, right: LaneLine, reference: float,
    frame: np.ndarray | None = None,
) -> Sighting | None:
    """The nearest vehicle-like box with tail lights in the ego lane of a working image; without one, the nearest
    lamp-less one; or None.
    ``frame``: the BGR picture the working image was reduced from (any whole or fractional multiple of its size); a
    box's tail lights above the road rows are looked for there (a car 22 m ahead seen from 1.5 m up has its lamps
    above the road region's top row)."""
    if not math.isfinite(reference) or reference < 20:
        return None  # too dark to tell an underside from the road
    w = gray.shape[1]
    top, bottom = region.top_v_px, region.bottom_v_px
    rows = np.arange(top, bottom + 1, dtype=float)
    lu, ru = left.u_at(rows), right.u_at(rows)
    width = ru - lu
    if not (width > 0).all():
        return None
    # only the road rows (the lane polygon lies in them; the rows above cannot hold an underside), row 0 = top
    lane = np.zeros((bottom + 1 - top, w), np.uint8)
    band_rows = rows - top
    poly = np.concatenate([np.array([lu - LANE_WIDEN * width, band_rows]).T, np.array([ru + LANE_WIDEN * width, band_rows]).T[::-1]])
    cv2.fillPoly(lane, [np.rint(poly).astype(np.int32)], 255)
    band = cv2.bitwise_and(cv2.inRange(gray[top : bottom + 1], 0, int(DARK_RATIO * reference)), lane)
    if cv2.countNonZero(band) == 0:
        return None  # nothing dark in the lane: the common case, and the cheap one
    # 16-bit labels cost about half of 32-bit ones; an 8-connected h×w mask holds at most ⌈h/2⌉·⌈w/2⌉ components
    ltype = cv2.CV_16U if (band.shape[0] + 1) * (band.shape[1] + 1) // 4 < 65535 else cv2.CV_32S
    _n, _labels, stats, _ = cv2.connectedComponentsWithStats(band, connectivity=8, ltype=ltype)
    stats = stats[1:].astype(np.int64)
    stats[:, 1] += top
    # the shape tests, vectorised over all blobs (a noisy night frame has thousands of dark specks)
    x, y, bw, bh, area = stats.T
    v_bottom = y + bh - 1
    lu, ru = lu[v_bottom - top], ru[v_bottom - top]
    lane_w = ru - lu
    centre = x + 0.5 * bw
    keep = (v_bottom < bottom - 1) & (bh <= MAX_ASPECT * bw)  # not touching the image bottom, not too tall
    keep &= (lane_w > 0) & (bw >= WIDTH_RANGE[0] * lane_w) & (bw <= WIDTH_RANGE[1] * lane_w) & (area >= MIN_FILL * bw * bh)
    keep &= (centre >= lu) & (centre <= ru)  # the blob's centre is inside the ego lane (else: a vehicle beside)
    # a dark patch as wide as the lane is the road's own (darker pavement, a bridge's shadow): with tail lights it may
    # still be a wide vehicle, without them it is no vehicle
    lane_wide = bw > UNLIT_WIDTH_MAX * lane_w
    unlit: Sighting | None = None
    dev = max(45.0, 0.5 * reference)
    for i in np.flatnonzero(keep)[np.argsort(-v_bottom[keep])]:  # nearest first
        x, y, bw, bh, v_bottom_i = (int(a) for a in (stats[i, 0], stats[i, 1], stats[i, 2], stats[i, 3], v_bottom[i]))
        box_h = max(bh, int(ASPECT * bw))
        y0 = max(0, v_bottom_i - box_h + 1)
        y_road = max(y0, top)  # judge "not road" only on the road region (above it: sky and trees are foreign anyway)
        patch = gray[y_road : v_bottom_i + 1, x : x + bw].astype(np.float32)
        sat = hls[y_road : v_bottom_i + 1, x : x + bw, 2]
        foreign = (np.abs(patch - reference) > dev) | (sat >= 110)
        if foreign.mean() < ABOVE_FOREIGN_MIN:
            continue
        red = _red_pixels(hls[y_road : v_bottom_i + 1, x : x + bw])
        if y0 < top and frame is not None:  # the box reaches above the road rows (grey and HLS are 0 there): the frame's
            k = frame.shape[1] / gray.shape[1]  # pixels, in working pixels' worth
            above = frame[int(y0 * k) : int(top * k), int(x * k) : math.ceil((x + bw) * k)]
            red += _red_pixels(cv2.cvtColor(above, cv2.COLOR_BGR2HLS)) / (k * k) if above.size else 0.0
        box = LeadBox(float(x), float(y0), float(bw), float(v_bottom_i - y0 + 1))
        if red >= TAIL_LIGHT_SHARE * bw * (v_bottom_i - y0 + 1):
            return Sighting(box, lit=True)
        if unlit is None and not lane_wide[i]:
            unlit = Sighting(box, lit=False)  # no tail lights: a shadow, a dark patch — or a vehicle, if it moves
    return unlit


def _red_pixels(hls: np.ndarray) -> float:
    """How many pixels of an HLS patch are tail-light red."""
    hue = hls[..., 0]
    return float(np.count_nonzero(((hue <= RED_HUE_MAX) | (hue >= 180 - RED_HUE_MAX)) & (hls[..., 2] >= RED_SAT_MIN)))


class LeadTracker:
    """Kalman track of the lead box (centre u, bottom v, width; constant velocity). A track is reported once confirmed:
    CONFIRM_HITS detections with tail lights, or seen moving along the road (``moving_over_ground``). A lamp-less
    detection joins only a track that has shown no tail lights: a track that has is kept, moved and dropped by lit
    detections alone (coasting over frames without), exactly as when the search boxed only lit vehicles."""

    def __init__(self) -> None:
        self.kf: KalmanFilter | None = None
        self.hits = 0  # detections with tail lights
        self.moving = False  # seen moving along the road (stays so while tracked)
        self.samples: deque[tuple[float, float, float, float]] = deque()  # (t s, ground range m, the car's speed m/s, box width px)
        self.last_seen_s = -math.inf
        self.last_t_s: float | None = None

    def reset(self) -> None:
        self.__init__()  # type: ignore[misc]

    @property
    def confirmed(self) -> bool:
        return self.kf is not None and (self.hits >= CONFIRM_HITS or self.moving)

    def update(self, t_s: float, box: LeadBox | None, *, lit: bool = True, range_m: float | None = None,
               speed_mps: float | None = None) -> LeadBox | None:
        """Fold in this frame's box (or None) — ``lit``: seen with tail lights; ``range_m``: its ground range; ``speed_mps``:
        the car's own speed (None: unknown, and a lamp-less track is then never confirmed); the confirmed, smoothed box,
        or None."""
        dt = 0.05 if self.last_t_s is None or not t_s > self.last_t_s else min(1.0, t_s - self.last_t_s)
        self.last_t_s = t_s if self.last_t_s is None else max(self.last_t_s, t_s)
        if self.kf is not None:
            self.kf.F = np.eye(6)
            self.kf.F[0, 3] = self.kf.F[1, 4] = self.kf.F[2, 5] = dt
            self.kf.predict()
        if not (box is not None and box.usable and self._fold(box, lit, range_m, speed_mps)):
            if self.kf is not None and self.last_t_s - self.last_seen_s > LOST_AFTER_S:
                self.kf, self.hits, self.moving = None, 0, False
                self.samples.clear()
        if not self.confirmed:
            return None
        u, vb, wd = (float(a) for a in self.kf.x[:3])
        hd = ASPECT * wd
        return LeadBox(u - 0.5 * wd, vb - hd, wd, hd)

    def _fold(self, box: LeadBox, lit: bool, range_m: float | None, speed_mps: float | None) -> bool:
        """Join the box to the track, or start a track with it; False when it is left out. A lamp-less box never touches
        a track that has shown tail lights, nor replaces one seen moving; a lit box joins only a track that has shown
        tail lights or been seen moving (a lamp-less track not yet a vehicle is replaced, as if it had not been)."""
        if not lit and self.hits > 0:
            return False
        z = np.array([box.x_px + 0.5 * box.w_px, box.y_px + box.h_px, box.w_px])
        joinable = not lit or self.hits > 0 or self.moving
        if self.kf is not None and joinable and not self._outlier(z):
            self.kf.update(z)
            self.hits += int(lit)
        elif lit or not self.moving:
            self.kf, self.hits, self.moving = self._new(z), int(lit), False
            self.samples.clear()
        else:
            return False
        self._seen(range_m, speed_mps, box.w_px)
        return True

    def _seen(self, range_m: float | None, speed_mps: float | None, width_px: float) -> None:
        """A detection joined the track: remember its range and judge, once, whether the track moves along the road (a
        track that has shown tail lights, or already moves, needs no judging)."""
        t = self.last_t_s
        self.last_seen_s = t
        if self.hits > 0 or self.moving or range_m is None or speed_mps is None:
            return
        if not (math.isfinite(range_m) and math.isfinite(speed_mps) and range_m > 0):
            return
        self.samples.append((t, range_m, speed_mps, width_px))
        while self.samples and t - self.samples[0][0] > MOTION_WINDOW_S:
            self.samples.popleft()
        if len(self.samples) >= MOTION_MIN_SAMPLES and t - self.samples[0][0] >= 0.8 * MOTION_WINDOW_S:  # most of it
            self.moving = moving_over_ground(np.array(self.samples))

    def _outlier(self, z: np.ndarray) -> bool:
        kf = self.kf
        y = z - kf.H @ kf.x
        s = kf.H @ kf.P @ kf.H.T + kf.R
        return float(y @ np.linalg.solve(s, y)) > GATE_CHI2

    @staticmethod
    def _new(z: np.ndarray) -> KalmanFilter:
        kf = kalman_filter(dim_x=6, dim_z=3)
        kf.x = np.array([z[0], z[1], z[2], 0.0, 0.0, 0.0])
        kf.H = np.hstack([np.eye(3), np.zeros((3, 3))])
        scale = max(4.0, 0.1 * z[2])
        kf.R = np.eye(3) * scale**2
        kf.P = np.diag([scale**2] * 3 + [(4 * z[2]) ** 2] * 3)
        kf.Q = np.diag([1.0, 1.0, 1.0, 25.0, 25.0, 25.0]) * (0.2 * z[2]) ** 2 * 0.05
        return kf


def moving_over_ground(samples: np.ndarray) -> bool:
    """Whether a box's ground ranges show it moving along the road as one rigid thing. ``samples``: rows of (t s, range m,
    the car's speed m/s, box width px).

    A robust line first (Theil–Sen: the median of the pairwise slopes) picks the ranges that lie on it — one
    detection of something else joined to the track is left out; the kept ones must keep the box's size: range ×
    width in pixels is a rigid object's width × the focal length, steady within ``RIGID_SPREAD`` (a shadow's blob
    grows, splits and merges). Then the least-squares slope of the kept ranges: the speed over the ground is the car's
    mean speed plus that slope, and it must exceed, by two standard errors of the slope, ``MOVING_SHARE`` × the car's
    speed and ``MOVING_MIN_MPS``. The residual spread is floored at ``RANGE_NOISE_SHARE`` of the range (a box's range is
    no better). By hand: numpy and OpenCV fit no robust line with a floored error."""
    t, r, v, w = (samples[:, k] for k in range(4))
    i, j = np.triu_indices(len(t), 1)
    apart = t[j] > t[i]
    if np.count_nonzero(apart) < 3:
        return False
    robust = float(np.median((r[j] - r[i])[apart] / (t[j] - t[i])[apart]))
    off = r - robust * t
    off -= np.median(off)
    floor = RANGE_NOISE_SHARE * float(np.median(r))
    kept = np.abs(off) <= max(3.0 * 1.4826 * float(np.median(np.abs(off))), 2.0 * floor)
    t, r, v, size = t[kept], r[kept], v[kept], (r * w)[kept]
    if len(t) < MOTION_MIN_SAMPLES or not float(size.std()) <= RIGID_SPREAD * float(size.mean()):
        return False
    t = t - t.mean()
    stt = float(t @ t)
    if stt <= 0.0:
        return False
    slope = float(t @ (r - r.mean())) / stt
    residual = r - r.mean() - slope * t
    spread = max(math.sqrt(float(residual @ residual) / max(len(t) - 2, 1)), RANGE_NOISE_SHARE * float(r.mean()))
    own = float(v.mean())
    return own + slope - 2.0 * spread / math.sqrt(stt) >= max(MOVING_MIN_MPS, MOVING_SHARE * own)
