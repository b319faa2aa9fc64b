"""HoughLaneSteering: the baseline lane-geometry steering function (frame → degrees, + = left).

The classic pipeline of the field (Hough lanes, Kalman-tracked boundaries, aim at the lane centre);
users wrap it with ``FearGuard`` like any other estimator. A FearGuard that wraps it shares its frame
pipeline, so each frame is analysed once for both the cues and the steering.
"""

from __future__ import annotations

from fearguard.camera import CameraModel
from fearguard.vision.frame import FrameAnalysis, FramePipeline


class HoughLaneSteering:
    """Stateful steering function: frame (BGR uint8) → steering angle in degrees (+ = left).

    No lane in view: the previous angle is kept (0 before any lane was seen); the supervisor's
    lane_confidence will be low at the same time, so it slows or stops the car.
    """

    def __init__(self, camera: CameraModel | None = None, fps: float = 20.0) -> None:
        self.pipeline = FramePipeline(camera, fps)

    def __call__(self, frame: object) -> float:
        analysis = self.pipeline.process(frame)
        return self.steering_from(analysis)

    @staticmethod
    def steering_from(analysis: FrameAnalysis) -> float:
        return analysis.steering_deg if analysis.steering_deg is not None else 0.0

    def reset(self) -> None:
        self.pipeline.reset()
