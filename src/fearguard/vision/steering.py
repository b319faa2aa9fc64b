"""Baseline steering from the lane geometry: the aim point, its bearing, and the lane memory between frames.

The lane centre at a look-ahead row (``LOOKAHEAD`` of the road region from its top, or — a mounted camera given an
aim distance — the row of the ground that far ahead: pure pursuit's look-ahead, which sets how closely a curve is
followed) is the aim point;
the steering angle is its bearing through the camera model (deg, + = left): the direction a
pure-pursuit driver would head for. Two boundaries: between them (not a lane width apart, the barely seen one weighing
less); one boundary: the centre is half the remembered lane width from it. No boundary: the previous angle is kept (the
review's rule); without history there is no angle.
"""

from __future__ import annotations

from dataclasses import dataclass

from fearguard.camera import CameraModel
from fearguard.vision.lanes import LaneLine, RoadRegion

LOOKAHEAD = 0.3  # [-] of the road region's height, from its top: the row the car aims at
DEFAULT_LANE_WIDTH = 0.45  # [-] of the image width: lane width at the look-ahead row before any was measured
WIDTH_MEMORY = 0.1  # [-] EMA weight of a new lane-width measurement (once the width rests on 1/this full pairs)
WIDTH_TOLERANCE = 0.25  # [-] of the remembered lane width: two boundaries this near it apart are both the lane's
WELL_SEEN_SUPPORT = 0.5  # [-] a boundary this well supported weighs fully in the lane centre (less: in proportion)
MIN_WEIGHT = 1e-3  # [-] a boundary's least weight in the lane centre (one of support 0 still places it, as the only one would)


def lookahead_row(region: RoadRegion, camera: CameraModel | None = None, aim_m: float | None = None) -> float:
    """The row (working pixels) the steering aims at: the ground ``aim_m`` ahead of a mounted ``camera`` (any size: it
    is scaled to the region's), held inside the road region; else ``LOOKAHEAD`` of the region from its top."""
    if camera is not None and aim_m is not None:
        row = camera.scaled_to(region.width_px, region.height_px).ground_row_px(aim_m)
        if row is not None:
            return min(max(row, float(region.top_v_px)), float(region.bottom_v_px))
    return region.top_v_px + LOOKAHEAD * (region.bottom_v_px - region.top_v_px)


def aim_point_u(left: LaneLine | None, right: LaneLine | None, v_px: float, lane_width_px: float) -> float | None:
    """Column of the lane centre at row v (``centre_between`` the boundaries' columns there)."""
    return centre_between(left.u_at(v_px) if left is not None else None, right.u_at(v_px) if right is not None else None,
                          (left.support if left is not None else 0.0, right.support if right is not None else 0.0), lane_width_px)


def centre_between(left_u: float | None, right_u: float | None, supports: tuple[float, float], lane_width_px: float) -> float | None:
    """The lane centre from the boundaries' columns at one row. Two a lane width apart (within WIDTH_TOLERANCE of the
    remembered one) are both this lane's: the midpoint, however faint (sparse dashes on both sides). Two that are not
    cannot both be: the centre is half a lane width from each, weighted by its support up to WELL_SEEN_SUPPORT — mostly
    from the solid line seen at 1.00 beside a "right line" of noise at 0.20 (a model car at night, whose midpoint steered
    it out of its lane). One: half a lane width from it."""
    if left_u is not None and right_u is not None:
        if abs(right_u - left_u - lane_width_px) <= WIDTH_TOLERANCE * lane_width_px:
            return 0.5 * (left_u + right_u)  # a lane width apart: both are this lane's
        weight_left, weight_right = (min(1.0, max(s / WELL_SEEN_SUPPORT, MIN_WEIGHT)) for s in supports)
        from_left, from_right = left_u + 0.5 * lane_width_px, right_u - 0.5 * lane_width_px
        return (weight_left * from_left + weight_right * from_right) / (weight_left + weight_right)
    if left_u is not None:
        return left_u + 0.5 * lane_width_px
    if right_u is not None:
        return right_u - 0.5 * lane_width_px
    return None


def steering_from_aim(u_work_px: float, scale: float, camera: CameraModel) -> float:
    """Bearing (deg, + = left) of the aim point, given in working pixels (× scale → frame pixels)."""
    return camera.bearing_deg(u_work_px * scale)


@dataclass
class LaneMemory:
    """What the steering keeps between frames: the lane width at the look-ahead row, the last angle, and where the lane
    centre crossed the road region's top row (where the next frame's region looks: ``lanes.region_toward``)."""

    lane_width_px: float | None = None
    last_steering_deg: float | None = None
    far_centre_u_px: float | None = None
    width_evidence: float = 0.0  # [-] the supports of the pairs the width rests on (each the weaker side's)

    def remember_width(self, left: LaneLine | None, right: LaneLine | None, v_px: float, width_px: int) -> float:
        """The lane width at row v: the mean of the widths measured between two boundaries, each weighted by the weaker
        one's support, until it rests on 1/WIDTH_MEMORY fully supported pairs; then an EMA (WIDTH_MEMORY per pair).
        A first pair of a solid line and a stray at support 0.20 (a model car at night) measured 0.4 of the lane: taken
        as the width, it put the lane centre beside the one line seen for seconds; a pair seen well next corrects it."""
        if left is not None and right is not None:
            measured = right.u_at(v_px) - left.u_at(v_px)
            weight = min(1.0, left.support, right.support)
            if measured > 0 and weight > 0:
                self.width_evidence += weight
                old = self.lane_width_px if self.lane_width_px is not None else measured
                self.lane_width_px = old + max(weight / self.width_evidence, WIDTH_MEMORY) * (measured - old)
        return self.lane_width_px if self.lane_width_px is not None else DEFAULT_LANE_WIDTH * width_px

    def hold(self, steering_deg: float | None) -> float | None:
        """This frame's angle, or the last one when no lane gave one (the review's rule); remembered."""
        steering = steering_deg if steering_deg is not None else self.last_steering_deg
        self.last_steering_deg = steering
        return steering

    def remember_far_centre(self, u_px: float | None) -> None:
        self.far_centre_u_px = u_px
