"""HoughLaneSteering: the baseline lane-geometry steering function (frame → degrees, + = left).

The classic pipeline of the field (Hough lanes, Kalman-tracked boundaries, aim at the lane centre);
users wrap it with ``FearGuard`` like any other estimator. It is a ``perception.FrameSteering``: a
FearGuard that wraps it analyses each frame once with its pipeline and asks ``steer_from`` for the
angle of that same analysis, so the cues and the steering always describe the same frame.
"""

from __future__ import annotations

from fearguard.camera import CameraModel
from fearguard.vision.frame import FrameAnalysis, FramePipeline
from fearguard.vision.ground_lanes import GroundLaneSpec


class HoughLaneSteering:
    """Stateful steering function: frame (BGR uint8) → steering angle in degrees (+ = left).

    ``aim_m``: the angle is the bearing of the lane centre this far ahead of the camera (a camera with a mount height;
    default: ``steering.LOOKAHEAD`` of the road region) — pure pursuit's look-ahead: nearer follows a curve more
    closely (``worlds/metadrive/preset.AIM_M``). ``markings``: the track's markings (``lane.MARKINGS``): "light" paint or
    tape (the default), or "dark" tape on a paler floor (black electrical tape on a carpet or a mat). ``guidance``: what the
    track guides the car by (``lane.GUIDANCE``): "two_lines" (the default), or one line — "centre_line", "one_edge" —
    whose own support is the lane confidence (the steering still aims as for a lane).

    No lane in view: the previous angle is kept (0 before any lane was seen); the supervisor's
    lane_confidence will be low at the same time, so it slows or stops the car.
    """

    def __init__(self, camera: CameraModel | None = None, fps: float = 20.0, *, ground: GroundLaneSpec | None = None,
                 aim_m: float | None = None, markings: str = "light", guidance: str = "two_lines") -> None:
        self._pipeline = FramePipeline(camera, fps, ground=ground, aim_m=aim_m, markings=markings, guidance=guidance)

    @property
    def pipeline(self) -> FramePipeline:
        """The frame analysis this steering reads (its camera, trackers and lane memory)."""
        return self._pipeline

    def __call__(self, frame: object) -> float:
        return self.steer_from(self._pipeline.process(frame))

    def steer_from(self, analysis: FrameAnalysis) -> float:
        """The angle for a frame this steering's pipeline has analysed."""
        return analysis.steering_deg if analysis.steering_deg is not None else 0.0

    def reset(self) -> None:
        self._pipeline.reset()
