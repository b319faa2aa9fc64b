"""fearguard: a fuzzy, affective safety supervisor layered on any steering estimator.

frame + sensors → perception (cues) → fear (fuzzy rules) → policy (speed limit, mode, emergency strategy) → command.
"""

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
from fearguard.vehicle import VehicleLimits
from fearguard.vision.frame import FrameAnalysis, analyze_frame
from fearguard.vision.lane_steering import HoughLaneSteering

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
    "HoughLaneSteering",
    "Lead",
    "LeadBox",
    "Mode",
    "Observation",
    "PolicyConfig",
    "RuleBase",
    "RuleError",
    "Strategy",
    "VehicleLimits",
    "analyze_frame",
    "load_camera",
    "load_rules",
    "save_camera",
]
