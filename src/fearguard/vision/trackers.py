"""What the stateful frame analysis remembers between frames, and the pass-through stand-ins of the stateless form.

``FramePipeline`` holds ``Trackers.tracking()``: the lane boundaries' Kalman tracks, the lead box's
track, the steering's lane memory, the median of the last confidences and the road's appearance. ``analyze_frame`` runs the
very same stages with ``Trackers.pass_through()``: each stand-in hands this frame's measurement back
unchanged and remembers nothing. So the two forms differ only in what they remember, and a pipeline
built with pass-through trackers must agree with ``analyze_frame`` on every frame (tested, as
filterpy tests its procedural form against ``KalmanFilter``).
"""

from __future__ import annotations

from collections import deque
from dataclasses import dataclass
from typing import Protocol

import numpy as np

from fearguard.observation import LeadBox
from fearguard.vision.ground_lanes import GroundLanes, GroundLaneSpec, GroundMemory
from fearguard.vision.lane_tracker import LaneTracker, TrackedLanes
from fearguard.vision.lanes import LaneLine, RoadRegion
from fearguard.vision.lead import LeadTracker
from fearguard.vision.medians import median
from fearguard.vision.obstacle import Obstacle, ObstacleTrack
from fearguard.vision.occlusion import RoadAppearance, RoadModel
from fearguard.vision.steering import DEFAULT_LANE_WIDTH, LaneMemory

CONFIDENCE_MEDIAN_FRAMES = 3  # [frames] lane_confidence over time is the median of this many frames (50 ms lag at 20 Hz)


class LaneTracking(Protocol):
    def current(self, region: RoadRegion) -> tuple[LaneLine | None, LaneLine | None]: ...

    def update(self, t_s: float, region: RoadRegion, left: LaneLine | None, right: LaneLine | None) -> TrackedLanes: ...


class LeadTracking(Protocol):
    def update(self, t_s: float, box: LeadBox | None, *, lit: bool = True, range_m: float | None = None,
               speed_mps: float | None = None) -> LeadBox | None: ...


class SteeringMemory(Protocol):
    def remember_width(self, left: LaneLine | None, right: LaneLine | None, v_px: float, width_px: int) -> float: ...

    def hold(self, steering_deg: float | None) -> float | None: ...

    far_centre_u_px: float | None  # [px] where last frame's lane centre crossed the road region's top row (None: no lane)

    def remember_far_centre(self, u_px: float | None) -> None: ...


class ObstacleTracking(Protocol):
    def update(self, seen: Obstacle | None) -> Obstacle | None: ...


class PassThroughObstacle:
    """No confirmation over time: this frame's object (or None) as it is."""

    def update(self, seen: Obstacle | None) -> Obstacle | None:
        return seen


class GroundTracking(Protocol):
    def priors(self, t_s: float) -> GroundLanes | None: ...

    def remember(self, t_s: float, lanes: GroundLanes) -> None: ...

    def spec_now(self, spec: GroundLaneSpec) -> GroundLaneSpec: ...


class ConfidenceSmoothing(Protocol):
    def update(self, confidence: float) -> float: ...


class RoadMemory(Protocol):
    def reference(self, measured: RoadAppearance) -> RoadAppearance: ...

    def learn(self, measured: RoadAppearance, occlusion: float) -> None: ...


class ConfidenceMedian:
    """Median of the last CONFIDENCE_MEDIAN_FRAMES confidences: one odd frame neither alarms nor reassures."""

    def __init__(self) -> None:
        self._recent: deque[float] = deque(maxlen=CONFIDENCE_MEDIAN_FRAMES)

    def update(self, confidence: float) -> float:
        self._recent.append(confidence)
        return float(median(np.array(self._recent)))


class PassThroughLanes:
    """No lane tracks: no prior for the line choice, this frame's detections accepted as they are."""

    def current(self, region: RoadRegion) -> tuple[LaneLine | None, LaneLine | None]:
        return None, None

    def update(self, t_s: float, region: RoadRegion, left: LaneLine | None, right: LaneLine | None) -> TrackedLanes:
        return TrackedLanes(left=left, right=right, left_accepted=True, right_accepted=True, predicted_left=None, predicted_right=None,
                            left_support=left.support if left is not None else 0.0,
                            right_support=right.support if right is not None else 0.0)


class PassThroughLead:
    """No lead track: this frame's box with tail lights (or None) as it is; a lamp-less one needs a track to be seen moving."""

    def update(self, t_s: float, box: LeadBox | None, *, lit: bool = True, range_m: float | None = None,
               speed_mps: float | None = None) -> LeadBox | None:
        return box if lit else None


class PassThroughMemory:
    """No lane memory: the lane width is this frame's (or the default), and no previous angle is held."""

    def remember_width(self, left: LaneLine | None, right: LaneLine | None, v_px: float, width_px: int) -> float:
        measured = right.u_at(v_px) - left.u_at(v_px) if left is not None and right is not None else 0.0
        return measured if measured > 0 else DEFAULT_LANE_WIDTH * width_px

    def hold(self, steering_deg: float | None) -> float | None:
        return steering_deg

    far_centre_u_px = None

    def remember_far_centre(self, u_px: float | None) -> None:
        pass


class PassThroughConfidence:
    """No smoothing over time: this frame's confidence."""

    def update(self, confidence: float) -> float:
        return confidence


class PassThroughGround:
    """No ground-model memory: every frame is fitted without priors."""

    def priors(self, t_s: float) -> GroundLanes | None:
        return None

    def remember(self, t_s: float, lanes: GroundLanes) -> None:
        return None

    def spec_now(self, spec: GroundLaneSpec) -> GroundLaneSpec:
        return spec


class PassThroughRoad:
    """No road appearance model: this frame's lane interior is the road."""

    def reference(self, measured: RoadAppearance) -> RoadAppearance:
        return measured

    def learn(self, measured: RoadAppearance, occlusion: float) -> None:
        return None


@dataclass(frozen=True)
class Trackers:
    """The memories of the frame analysis (each replaced, never reset in place, on a pipeline reset)."""

    lanes: LaneTracking
    leads: LeadTracking
    memory: SteeringMemory
    confidence: ConfidenceSmoothing
    road: RoadMemory  # the road's appearance over recent frames (occlusion's reference)
    ground: GroundTracking  # the bending lane's last boundaries (the ground model's priors)
    obstacles: ObstacleTracking  # an object in the lane, confirmed over consecutive frames

    @classmethod
    def tracking(cls) -> Trackers:
        """The stateful form's: Kalman tracks, lane memory, confidence median."""
        return cls(lanes=LaneTracker(), leads=LeadTracker(), memory=LaneMemory(), confidence=ConfidenceMedian(), road=RoadModel(),
                   ground=GroundMemory(), obstacles=ObstacleTrack())

    @classmethod
    def pass_through(cls) -> Trackers:
        """The stateless form's: every stand-in hands this frame's measurement back and remembers nothing."""
        return cls(
            lanes=PassThroughLanes(), leads=PassThroughLead(), memory=PassThroughMemory(), confidence=PassThroughConfidence(),
            road=PassThroughRoad(), ground=PassThroughGround(), obstacles=PassThroughObstacle(),
        )
