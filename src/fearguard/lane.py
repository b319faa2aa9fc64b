"""The ego lane on the ground, as perception measures it: plain values (vision builds them, policy reads them).

Each boundary is a straight ground line y = y0 + slope·x in vehicle axes (x forward from the camera, y left, metres)
over the stretch the camera sees; the lane geometry's own steering is the reference the lane check compares with.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

MARKINGS = ("light", "dark")  # a track's markings: lighter than the floor (paint, white or yellow tape) or darker (black tape)
GUIDANCE = ("two_lines", "centre_line", "one_edge")  # what a track guides the car by: the lane's two boundaries, or one line —
#   along the middle of the course (a centre line the car follows) or at one side (one edge)


@dataclass(frozen=True)
class GroundLine:
    """A lane boundary on the ground: lateral offset y = y0 + slope·x (m, + = left), x forward (m)."""

    y0_m: float
    slope: float

    def y_at(self, x_m: float) -> float:
        return self.y0_m + self.slope * x_m


@dataclass(frozen=True)
class LaneGeometry:
    """The ego lane in metres: the boundaries seen (None = not seen), the seen stretch, the lane's own steering."""

    left: GroundLine | None
    right: GroundLine | None
    near_m: float  # [m] closest ground distance the boundaries were measured at
    far_m: float  # [m] farthest
    steering_deg: float | None  # the lane geometry's steering (the baseline estimator), None if unknown

    @property
    def offset_m(self) -> float | None:
        """Lateral offset of the lane centre at the near distance (m, + = the centre is left of the camera)."""
        if self.left is None or self.right is None:
            return None
        return 0.5 * (self.left.y_at(self.near_m) + self.right.y_at(self.near_m))

    @property
    def heading_deg(self) -> float | None:
        """Heading of the lane relative to the car (deg, + = the lane turns away to the left)."""
        lines = [b for b in (self.left, self.right) if b is not None]
        if not lines:
            return None
        return math.degrees(math.atan(sum(b.slope for b in lines) / len(lines)))
