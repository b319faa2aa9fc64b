"""Lane boundaries from image lines to the ground plane (metres), through the camera model.

A straight image line of a flat-ground marking is a straight ground line: two of its rows (the road
region's nearest and farthest) projected to the ground give the line. Needs a camera model with its
mount height (ground ranges); without one there are no metres, and the lane check is skipped.
"""

from __future__ import annotations

import math

from fearguard.camera import CameraModel
from fearguard.lane import GroundLine, LaneGeometry
from fearguard.vision.lanes import LaneLine, RoadRegion


def ground_point(camera: CameraModel, u_px: float, v_px: float) -> tuple[float, float] | None:
    """(forward m, left m) of the ground point seen at frame pixel (u, v); None at/above the horizon."""
    x = camera.ground_range_m(v_px)
    if x is None or camera.mount_height_m is None:
        return None
    p = math.radians(camera.pitch_deg)
    depth = x * math.cos(p) + camera.mount_height_m * math.sin(p)
    return x, -(u_px - camera.cx_px) * depth / camera.fx_px


def ground_line(line: LaneLine, camera: CameraModel, near_v: float, far_v: float, scale: float) -> tuple[GroundLine, float, float] | None:
    """The boundary as a ground line, with the near and far distances it was seen over (None if not projectable)."""
    near = ground_point(camera, line.u_at(near_v) * scale, near_v * scale)
    far = ground_point(camera, line.u_at(far_v) * scale, far_v * scale)
    if near is None or far is None or not far[0] > near[0] > 0.0:
        return None
    slope = (far[1] - near[1]) / (far[0] - near[0])
    return GroundLine(near[1] - slope * near[0], slope), near[0], far[0]


def lane_geometry(
    left: LaneLine | None, right: LaneLine | None, region: RoadRegion | None, scale: float,
    camera: CameraModel | None, steering_deg: float | None,
) -> LaneGeometry | None:
    """The ego lane in metres from the boundaries in working pixels (``scale`` frame px per working px)."""
    if camera is None or camera.mount_height_m is None or region is None or (left is None and right is None):
        return None
    cam = camera.scaled_to(max(1, round(region.width_px * scale)), max(1, round(region.height_px * scale)))
    near_v, far_v = float(region.bottom_v_px), float(region.top_v_px)
    lines = {side: ground_line(b, cam, near_v, far_v, scale) if b is not None else None
             for side, b in (("left", left), ("right", right))}
    seen = [g for g in lines.values() if g is not None]
    if not seen:
        return None
    near_m, far_m = max(g[1] for g in seen), min(g[2] for g in seen)
    pick = {side: (g[0] if g is not None else None) for side, g in lines.items()}
    if pick["left"] is not None and pick["right"] is not None and pick["left"].y_at(near_m) <= pick["right"].y_at(near_m):
        return None  # boundaries in the wrong order: not a lane
    return LaneGeometry(pick["left"], pick["right"], near_m, far_m, steering_deg)
