"""fearguard: a fuzzy, affective safety supervisor layered on any steering estimator.

frame + sensors → perception (cues) → fear (fuzzy rules) → policy (speed limit, mode, emergency strategy) → command.

The public names below are imported on first use (PEP 562), so ``import fearguard`` and the CLI start
without loading OpenCV, SciPy and scikit-fuzzy: a Ctrl-C while the command line starts is handled by
the CLI's signal policy instead of interrupting an import (see ``interrupt.py``).
"""

from __future__ import annotations

import importlib
from typing import TYPE_CHECKING, Any

if TYPE_CHECKING:
    from fearguard.camera import CameraModel, load_camera, save_camera
    from fearguard.cues import CUE_NAMES, Cues
    from fearguard.errors import FearguardError, RuleError
    from fearguard.fear import Cause, FearLevel, FearResult
    from fearguard.fuzzy.loader import load_rules
    from fearguard.fuzzy.rulebase import RuleBase
    from fearguard.observation import Lead, LeadBox, Observation
    from fearguard.perception import FrameSteering
    from fearguard.policy import Mode, PolicyConfig, Strategy
    from fearguard.supervisor import Command, FearGuard
    from fearguard.track.profile import TrackProfile, load_track
    from fearguard.vehicle import VehicleLimits
    from fearguard.vision.frame import FrameAnalysis, analyze_frame
    from fearguard.vision.lane_steering import HoughLaneSteering

_HOME = {  # public name → the module that defines it
    "CameraModel": "fearguard.camera",
    "load_camera": "fearguard.camera",
    "save_camera": "fearguard.camera",
    "CUE_NAMES": "fearguard.cues",
    "Cues": "fearguard.cues",
    "FearguardError": "fearguard.errors",
    "RuleError": "fearguard.errors",
    "Cause": "fearguard.fear",
    "FearLevel": "fearguard.fear",
    "FearResult": "fearguard.fear",
    "load_rules": "fearguard.fuzzy.loader",
    "RuleBase": "fearguard.fuzzy.rulebase",
    "Lead": "fearguard.observation",
    "LeadBox": "fearguard.observation",
    "Observation": "fearguard.observation",
    "FrameSteering": "fearguard.perception",
    "Mode": "fearguard.policy",
    "PolicyConfig": "fearguard.policy",
    "Strategy": "fearguard.policy",
    "Command": "fearguard.supervisor",
    "FearGuard": "fearguard.supervisor",
    "TrackProfile": "fearguard.track.profile",
    "load_track": "fearguard.track.profile",
    "VehicleLimits": "fearguard.vehicle",
    "FrameAnalysis": "fearguard.vision.frame",
    "GroundLaneSpec": "fearguard.vision.ground_lanes",
    "analyze_frame": "fearguard.vision.frame",
    "HoughLaneSteering": "fearguard.vision.lane_steering",
}


__all__ = [
    "CUE_NAMES",
    "CameraModel",
    "Cause",
    "Command",
    "Cues",
    "FearGuard",
    "FearLevel",
    "FearResult",
    "FearguardError",
    "FrameAnalysis",
    "FrameSteering",
    "GroundLaneSpec",
    "HoughLaneSteering",
    "Lead",
    "LeadBox",
    "Mode",
    "Observation",
    "PolicyConfig",
    "RuleBase",
    "RuleError",
    "Strategy",
    "TrackProfile",
    "VehicleLimits",
    "analyze_frame",
    "load_camera",
    "load_rules",
    "load_track",
    "save_camera",
]


def __getattr__(name: str) -> Any:
    """Import a public name's module on first use and keep the name here."""
    home = _HOME.get(name)
    if home is None:
        raise AttributeError(f"module 'fearguard' has no attribute {name!r}")
    value = getattr(importlib.import_module(home), name)
    globals()[name] = value
    return value


def __dir__() -> list[str]:
    return sorted({*globals(), *__all__})
