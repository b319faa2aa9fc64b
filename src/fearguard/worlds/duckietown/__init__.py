"""fearguard in gym-duckietown: the Duckiebot preset, the simulator as a world, drives, metrics and a suite.

``preset`` and ``metrics`` are plain Python; ``world`` and ``drive`` import the simulator only when
a world is opened (``bash .ci/duckietown.sh`` builds the environment that has it).

    from fearguard.worlds.duckietown import DriveOptions, drive
    result = drive(DriveOptions("loop_empty", seconds=60, obstacle="duck"), "out/dt")
"""

from fearguard.worlds.duckietown.drive import CONTROLLERS, DriveOptions, DriveResult, drive
from fearguard.worlds.duckietown.preset import duckiebot_camera, duckiebot_limits, steering_action

__all__ = ["CONTROLLERS", "DriveOptions", "DriveResult", "drive", "duckiebot_camera", "duckiebot_limits", "steering_action"]
