"""Baseline steering from the lane geometry: the aim point, its bearing, and the lane memory between frames.

The lane centre at a look-ahead row (``LOOKAHEAD`` of the road region from its top, or — a mounted camera given an
aim distance — the row of the ground that far ahead: pure pursuit's look-ahead, which sets how closely a curve is
followed) is the aim point;
the steering angle is its bearing through the camera model (deg, + = left): the direction a
pure-pursuit driver would head for. One boundary: the centre is half the remembered lane width from
it. No boundary: the previous angle is kept (the review's rule); without history there is no angle.
"""

from __future__ import annotations

from dataclasses import dataclass

from fearguard.camera import CameraModel
from fearguard.vision.lanes import LaneLine, RoadRegion

LOOKAHEAD = 0.3  # [-] of the road region's height, from its top: the row the car aims at
DEFAULT_LANE_WIDTH = 0.45  # [-] of the image width: lane width at the look-ahead row before any was measured
WIDTH_MEMORY = 0.1  # [-] EMA weight of a new lane-width measurement


def lookahead_row(region: RoadRegion, camera: CameraModel | None = None, aim_m: float | None = None) -> float:
    """The row (working pixels) the steering aims at: the ground ``aim_m`` ahead of a mounted ``camera`` (any size: it
    is scaled to the region's), held inside the road region; else ``LOOKAHEAD`` of the region from its top."""
    if camera is not None and aim_m is not None:
        row = camera.scaled_to(region.width_px, region.height_px).ground_row_px(aim_m)
        if row is not None:
            return min(max(row, float(region.top_v_px)), float(region.bottom_v_px))
    return region.top_v_px + LOOKAHEAD * (region.bottom_v_px - region.top_v_px)


def aim_point_u(left: LaneLine | None, right: LaneLine | None, v_px: float, lane_width_px: float) -> float | None:
    """Column of the lane centre at row v: between both boundaries, or half a lane width from one."""
    if left is not None and right is not None:
        return 0.5 * (left.u_at(v_px) + right.u_at(v_px))
    if left is not None:
        return left.u_at(v_px) + 0.5 * lane_width_px
    if right is not None:
        return right.u_at(v_px) - 0.5 * lane_width_px
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

    def remember_width(self, left: LaneLine | None, right: LaneLine | None, v_px: float, width_px: int) -> float:
        if left is not None and right is not None:
            measured = right.u_at(v_px) - left.u_at(v_px)
            if measured > 0:
                old = self.lane_width_px
                self.lane_width_px = measured if old is None else (1 - WIDTH_MEMORY) * old + WIDTH_MEMORY * measured
        return self.lane_width_px if self.lane_width_px is not None else DEFAULT_LANE_WIDTH * width_px

    def hold(self, steering_deg: float | None) -> float | None:
        """This frame's angle, or the last one when no lane gave one (the review's rule); remembered."""
        steering = steering_deg if steering_deg is not None else self.last_steering_deg
        self.last_steering_deg = steering
        return steering

    def remember_far_centre(self, u_px: float | None) -> None:
        self.far_centre_u_px = u_px
