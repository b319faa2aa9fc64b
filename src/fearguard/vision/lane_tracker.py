"""Temporal tracking of the two lane boundaries with filterpy Kalman filters.

Each boundary is tracked as its image column at the road region's top and bottom rows, with a constant-velocity model
(state: u_top, u_bottom and their rates, px and px/s). A detection far from the prediction (Mahalanobis gate) is
treated as a miss, unless it persists — ``REINIT_AFTER`` outliers in a row, each within ``REINIT_AGREE`` of the one
before and none much weaker than the track's recent best (``REINIT_SUPPORT_SHARE``) — which re-initialises the track
there (the lane really moved, e.g. a lane change). Outliers scattered over the image (a shadow edge one frame, a far
dash the next) are noise and never move a track. A track without detections is predicted for ``LOST_AFTER_S`` and then
dropped. A detection measures the boundary only where its marking ridges were found (``seen_span``): a straight line
through the dashes of a curved line in view is right at them and wrong where it is extrapolated to, so it is gated and
folded in at two rows within that span, not at the region's ends — while the track is fresh (a line with a direction
of its own on it within ``SUPPORT_HOLD_S``); a track that has coasted longer, its gate widened, is taken up again only
by a line that agrees with it at the region's ends.

A dashed line shows a dash or two at a time: its support (the share of rows with paint) rises and falls as the dashes
pass. An accepted detection's support is therefore the best its track had over the last ``SUPPORT_HOLD_S`` (one dash
period at driving speed): a dash between two others is no weaker evidence of the line than they were. A track also
remembers whether it was ever one side of a lane — accepted together with the other side in a pair seen well
(``paired``): a line alone that never was (a verge's edge, a seam in worn concrete) guides nothing.
"""

from __future__ import annotations

import math
from collections import deque
from dataclasses import dataclass
from typing import TYPE_CHECKING

import numpy as np

from fearguard.sensors.kalman import kalman_filter
from fearguard.vision.confidence import seen_rows
from fearguard.vision.lanes import LaneLine, RoadRegion, geometry_plausibility

if TYPE_CHECKING:
    from filterpy.kalman import KalmanFilter

MEASUREMENT_STD = 0.03  # [-] of the width: noise of a detected boundary's end point, frame to frame. Measured
#   (std of consecutive differences / √2, stateless detections): clean real footage 0.001-0.01, the simulator's tree
#   shadows 0.015 (top) and 0.029 (bottom), heavy-tailed; a true boundary under the worst shade must pass the gate
VELOCITY_STD = 0.15  # [-] of the width per s: a new track's rate is unknown but small (a first jump is noise, not motion)
ACCEL_STD = 0.6  # [-] of the width per s²: how fast a boundary may move in the image (curves, steering)
GATE_CHI2 = 13.8  # [-] chi-square, 2 dof, p = 0.001: detections beyond this are outliers
REINIT_AFTER = 3  # [frames] consecutive outliers that re-initialise the track ...
REINIT_AGREE = 0.04  # [-] of the width: ... each end point this close to the previous outlier's (they persist) ...
OWN_DIRECTION_SPAN = 0.1  # [-] of the region's rows: ... each with a direction of its own, seen over this span at least
#   (``seen_span``): a line through one short dash rests on a few rows, and a track begun on it disagrees with the whole
#   line at once (a far dash of a curved model-car line, seen for three frames, re-initialised the track 45 px off)
REINIT_SUPPORT_SHARE = 0.5  # [-] ... and each with at least this share of the best support the track held (SUPPORT_HOLD_S): a
#   weaker line (the grass edge beside a dashed line in a bend, support 0.15 against the dashes' 0.63) does not replace a
#   line seen well half a second ago
LOST_AFTER_S = 1.0  # [s] a track without any detection for this long is dropped
SUPPORT_HOLD_S = 0.6  # [s] an accepted detection's support is the best of the track's accepted detections this recent: one
#   period of a dashed line's pattern passing the camera (a model car's 0.15 m dashes, 0.6 m gaps at 1.3 m/s: 0.58 s; a
#   road's 3 m dashes, 9 m gaps at 25 m/s: 0.48 s), so a dash between two others is no weaker evidence than they were
PAIRED_MIN_EVIDENCE = 0.5  # [-] mean support × geometry of a pair that was a lane: both sides accepted and seen well together
#   (two weak lines in worn concrete or a verge's texture that happen to make a plausible pair are no lane)
DEFAULT_DT_S = 0.05  # [s] used on the first frame and when time does not advance
_IDENTITY = np.eye(2)  # the measurement weights of a line measured at the region's ends (read only)


class BoundaryTrack:
    """One boundary's Kalman filter over (u_top, u_bottom)."""

    def __init__(self, width_px: int) -> None:
        self.width_px = width_px
        self.kf: KalmanFilter | None = None
        self.last_seen_s = -math.inf
        self.outliers = 0
        self.pending: np.ndarray | None = None  # the last outlier, which the next must agree with to count
        self.recent: deque[tuple[float, float]] = deque()  # (t_s, support) of the accepted detections of the last SUPPORT_HOLD_S
        self.paired = False  # accepted, since the track began, together with the other side as a lane (PAIRED_MIN_EVIDENCE)
        self._model_dt_s = math.nan  # the period F and Q were built for
        self._F = self._Q = np.eye(4)

    def _new_filter(self, z: np.ndarray) -> KalmanFilter:
        kf = kalman_filter(dim_x=4, dim_z=2)
        kf.x = np.array([z[0], z[1], 0.0, 0.0])
        kf.H = np.array([[1.0, 0, 0, 0], [0, 1.0, 0, 0]])
        r = (MEASUREMENT_STD * self.width_px) ** 2
        kf.R = np.eye(2) * r
        kf.inv = _inverse_2x2  # filterpy's hook for the inverse: S is 2×2 here, np.linalg.inv costs ~10× the formula
        kf.P = np.diag([r, r, (VELOCITY_STD * self.width_px) ** 2, (VELOCITY_STD * self.width_px) ** 2])
        return kf

    def _begin(self, z: np.ndarray) -> None:
        """A new track at detection z: nothing held, no lane side yet."""
        self.kf = self._new_filter(z)
        self.recent.clear()
        self.paired = False

    def predict(self, dt_s: float) -> None:
        if self.kf is None:
            return
        if dt_s != self._model_dt_s:  # the frame period rarely changes: build F and Q once per period
            self._model_dt_s = dt_s
            self._F = np.array([[1.0, 0, dt_s, 0], [0, 1.0, 0, dt_s], [0, 0, 1.0, 0], [0, 0, 0, 1.0]])
            q = (ACCEL_STD * self.width_px) ** 2
            g = np.array([0.5 * dt_s**2, dt_s])
            block = np.outer(g, g) * q
            self._Q = np.array([[block[0, 0], 0, block[0, 1], 0], [0, block[0, 0], 0, block[0, 1]],
                                [block[1, 0], 0, block[1, 1], 0], [0, block[1, 0], 0, block[1, 1]]])
        self.kf.F, self.kf.Q = self._F, self._Q
        self.kf.predict()

    def update(self, t_s: float, z: np.ndarray | None, h: np.ndarray | None = None, span: float = 1.0, support: float = 1.0) -> bool:
        """Fold in a detection or a miss; True if the detection was accepted. ``z``: the detection's columns (u_top,
        u_bottom) at the region's ends, or — with ``h`` (2×2: each row the weights of u_top and u_bottom at one image
        row) — at two rows where it was seen (``seen_span``); ``span``: the share of the region's rows those two span.
        A detection with no direction of its own (``span`` below ``OWN_DIRECTION_SPAN``: one short dash, a speck) is
        evidence where it agrees, but it neither moves the track nor keeps it alive: a track fed only by such specks
        for ``LOST_AFTER_S`` is dropped. And past ``SUPPORT_HOLD_S`` without a line of its own direction, a detection is
        judged at the region's ends again. (On worn concrete after the markings end, specks and a partial line on the
        verge's edge, each accepted where it was seen by a track whose gate had widened for half a second, kept the
        last line's track — a side of the lane — alive and drifting onto the verge, and the creep steered by it.)"""
        if self.kf is not None and t_s - self.last_seen_s > LOST_AFTER_S:
            self.kf = None  # nothing with a direction of its own found on it for that long
        if z is None:
            return False
        own_direction = span >= OWN_DIRECTION_SPAN
        if self.kf is None:
            self._begin(_ends(z, h))
            self.last_seen_s, self.outliers, self.pending = t_s, 0, None
            return True
        if h is not None and t_s - self.last_seen_s > SUPPORT_HOLD_S + 1e-9:  # coasted past a dash period: only the whole
            z, h = _ends(z, h), None  # line, judged at its ends, takes the track up again
        # innovation and its covariance: H picks combinations of (u_top, u_bottom), so H·x and H·P·Hᵀ use the first two
        h2 = _IDENTITY if h is None else h
        y = z - h2 @ self.kf.x[:2]
        s = h2 @ self.kf.P[:2, :2] @ h2.T + self.kf.R
        if _mahalanobis2(y, s) > GATE_CHI2:
            weaker = support < REINIT_SUPPORT_SHARE * self.best_recent(t_s)
            ends = _ends(z, h) if own_direction and not weaker else None  # a speck, or a weaker line, cannot move the track
            persists = (ends is not None and self.pending is not None
                        and float(np.max(np.abs(ends - self.pending))) <= REINIT_AGREE * self.width_px)
            self.outliers, self.pending = (self.outliers + 1 if persists else 1), ends
            if self.outliers < REINIT_AFTER or ends is None:
                return False
            self._begin(ends)
            self.last_seen_s = t_s
        elif own_direction:
            # H given: z is already the right shape (filterpy skips reshaping it); the filter's own H for a whole-region line
            self.kf.update(z, H=self.kf.H if h is None else np.hstack([h, np.zeros((2, 2))]))
            self.last_seen_s = t_s
        self.outliers, self.pending = 0, None
        return True

    def best_recent(self, t_s: float) -> float:
        """The best support of the track's accepted detections within SUPPORT_HOLD_S before t_s (0: none); older ones are
        forgotten."""
        recent = self.recent
        while recent and recent[0][0] < t_s - SUPPORT_HOLD_S - 1e-9:  # a frame exactly SUPPORT_HOLD_S old still counts
            recent.popleft()
        return max((s for _, s in recent), default=0.0)

    def held_support(self, t_s: float, support: float) -> float:
        """The support of a detection accepted at t_s: the best of the track's accepted detections within SUPPORT_HOLD_S
        (this one included). A new track holds nothing from before it."""
        self.recent.append((t_s, support))
        return self.best_recent(t_s)

    def line(self, region: RoadRegion) -> LaneLine | None:
        """The tracked boundary as a line in the region (support 0: it is an estimate, not evidence)."""
        if self.kf is None:
            return None
        u_top, u_bottom = float(self.kf.x[0]), float(self.kf.x[1])
        slope = (u_bottom - u_top) / max(1, region.bottom_v_px - region.top_v_px)
        return LaneLine(slope, u_top - slope * region.top_v_px, 0.0, 0)


def seen_span(line: LaneLine, region: RoadRegion) -> tuple[np.ndarray, np.ndarray | None, float]:
    """The detection as a measurement where it was seen: its columns at the region's top and bottom rows, each moved
    into the span of its ridge rows (``confidence.seen_rows``, where ``confidence.agreement`` compares),
    the matrix that gives those columns from the track's (u_top, u_bottom), and the share of the region's rows between
    the two. A line seen over the whole region — or whose rows are not known, or a region under two rows high — is
    measured at its ends, as before (matrix None: the identity)."""
    top, bottom = float(region.top_v_px), float(region.bottom_v_px)
    ends = np.array([line.u_at(top), line.u_at(bottom)])
    seen = seen_rows(line)
    if seen is None or bottom - top < 2.0:
        return ends, None, 1.0
    rows = [min(seen[1], max(seen[0], v)) for v in (top, bottom)]
    if not rows[1] - rows[0] >= 1.0:  # a span under a pixel: no direction to measure; one row and its neighbour
        v = min(max(rows[0], top), bottom - 1.0) if rows[0] == rows[0] else top
        rows = [v, v + 1.0]
    if rows == [top, bottom]:
        return ends, None, 1.0
    span = bottom - top
    h = np.array([[(bottom - v) / span, (v - top) / span] for v in rows])
    return np.array([line.u_at(v) for v in rows]), h, (rows[1] - rows[0]) / span


def _ends(z: np.ndarray, h: np.ndarray | None) -> np.ndarray:
    """A measurement at two rows extended to the region's ends (u_top, u_bottom): a new track starts from the line."""
    return z if h is None else np.linalg.solve(h, z)


def _inverse_2x2(s: np.ndarray) -> np.ndarray:
    """The inverse of a 2×2 matrix by the adjugate (filterpy's ``KalmanFilter.inv``)."""
    det = s[0, 0] * s[1, 1] - s[0, 1] * s[1, 0]
    return np.array([[s[1, 1], -s[0, 1]], [-s[1, 0], s[0, 0]]]) / det


def _mahalanobis2(y: np.ndarray, s: np.ndarray) -> float:
    """yᵀ·S⁻¹·y for a 2-vector and a 2×2 covariance, in closed form (np.linalg.solve costs ~10× more at this size)."""
    det = s[0, 0] * s[1, 1] - s[0, 1] * s[1, 0]
    if not det > 0.0:
        return math.inf  # a degenerate covariance: the detection cannot be judged consistent
    return float((s[1, 1] * y[0] * y[0] - (s[0, 1] + s[1, 0]) * y[0] * y[1] + s[0, 0] * y[1] * y[1]) / det)


@dataclass(frozen=True)
class TrackedLanes:
    """The tracked boundaries after this frame's update, and whether each detection agreed with its track."""

    left: LaneLine | None
    right: LaneLine | None
    left_accepted: bool
    right_accepted: bool
    predicted_left: LaneLine | None  # the tracks' prediction before this frame's detections
    predicted_right: LaneLine | None
    left_support: float = 0.0  # [0..1] an accepted detection's support as its track holds it (``held_support``); 0: not accepted
    right_support: float = 0.0
    paired: tuple[bool, bool] = (True, True)  # each track was once one side of a lane seen well (``BoundaryTrack.paired``)


class LaneTracker:
    """Left and right boundary tracks; time is passed in (``t_s``), never read from a clock."""

    def __init__(self) -> None:
        self._tracks: tuple[BoundaryTrack, BoundaryTrack] | None = None
        self._last_t_s: float | None = None

    def reset(self) -> None:
        self._tracks, self._last_t_s = None, None

    def current(self, region: RoadRegion) -> tuple[LaneLine | None, LaneLine | None]:
        """The tracked boundaries as of the last update (the prior for this frame's line choice)."""
        if self._tracks is None or self._tracks[0].width_px != region.width_px:
            return None, None
        return self._tracks[0].line(region), self._tracks[1].line(region)

    def update(self, t_s: float, region: RoadRegion, left: LaneLine | None, right: LaneLine | None) -> TrackedLanes:
        if self._tracks is None or self._tracks[0].width_px != region.width_px:
            self._tracks = (BoundaryTrack(region.width_px), BoundaryTrack(region.width_px))
        dt = DEFAULT_DT_S if self._last_t_s is None or not t_s > self._last_t_s else min(1.0, t_s - self._last_t_s)
        self._last_t_s = t_s if self._last_t_s is None else max(self._last_t_s, t_s)
        predicted, accepted, held = [], [], []
        for track, line in zip(self._tracks, (left, right), strict=True):
            track.predict(dt)
            predicted.append(track.line(region))
            z, h, span = (None, None, 0.0) if line is None else seen_span(line, region)
            ok = track.update(self._last_t_s, z, h, span, 0.0 if line is None else line.support)
            accepted.append(ok)
            held.append(track.held_support(self._last_t_s, line.support) if ok and line is not None else 0.0)
        if accepted[0] and accepted[1] and left is not None and right is not None:
            if 0.5 * (held[0] + held[1]) * geometry_plausibility(left, right, region) >= PAIRED_MIN_EVIDENCE:
                self._tracks[0].paired = self._tracks[1].paired = True
        lt, rt = (t.line(region) for t in self._tracks)
        return TrackedLanes(lt, rt, accepted[0], accepted[1], predicted[0], predicted[1], held[0], held[1],
                            (self._tracks[0].paired, self._tracks[1].paired))
