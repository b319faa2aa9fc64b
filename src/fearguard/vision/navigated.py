"""A steering function for a car with a route: the lane seen by the camera, and the route where it leaves it.

A lane follower alone cannot take a roundabout's exit or a turn whose lane is painted: the lane it sees goes round
(MetaDrive ``--map SOS --seed 4``: the car circled the roundabout, its progress stalled at 60 % of the expert's), and
at a junction it reads the crossing road's lane. MetaDrive's agents get its navigation (the route's lanes ahead), a
Duckiebot its intersection navigation; so does this stack: where the route's steering and the lane's disagree by more
than ``FORK_DEG`` — the route leaves the lane seen, or no lane is seen — it steers by the route, else by the lane. The
supervisor wraps it like any estimator (its lane check lets a departure the route asks for through:
``policy.lane_check``). Both worlds with a route use it (``worlds/metadrive``, ``worlds/duckietown``).
"""

from __future__ import annotations

from collections.abc import Callable

from fearguard.vision.frame import FrameAnalysis, FramePipeline
from fearguard.vision.lane_steering import HoughLaneSteering

FORK_DEG = 8.0  # [deg] the route's aim-point bearing this far from the lane's: the route leaves this lane (on MetaDrive's
#   lanes the two agree within ~1 deg, 2-3 deg on the tightest curves; a roundabout's exit parts by 20-50 deg)


class NavigatedSteering:
    """A ``FrameSteering``: ``HoughLaneSteering`` on the camera, the route (``route()``: its steering now, None: none)
    where it leaves the lane seen, clipped to ±``max_steering_deg``."""

    def __init__(self, lanes: HoughLaneSteering, route: Callable[[], float | None], max_steering_deg: float) -> None:
        self.lanes, self.route, self.max_steering_deg = lanes, route, max_steering_deg

    @property
    def pipeline(self) -> FramePipeline:
        return self.lanes.pipeline

    def __call__(self, frame: object) -> float:
        return self.steer_from(self.pipeline.process(frame))

    def steer_from(self, analysis: FrameAnalysis) -> float:
        lane = self.lanes.steer_from(analysis)
        route = self.route()
        if route is None or (analysis.steering_deg is not None and abs(route - lane) <= FORK_DEG):
            return lane
        return max(-self.max_steering_deg, min(self.max_steering_deg, route))

    def reset(self) -> None:
        self.lanes.reset()
