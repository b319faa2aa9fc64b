"""fearguard: a fuzzy, affective safety supervisor layered on any steering estimator.

cues → fear (fuzzy rules) → policy (speed limit, mode, emergency strategy) → command.
"""

from fearguard.cues import CUE_NAMES, Cues
from fearguard.errors import FearguardError, RuleError
from fearguard.fear import Cause, FearLevel, FearResult
from fearguard.fuzzy.loader import load_rules
from fearguard.fuzzy.rulebase import RuleBase
from fearguard.policy import Lead, Mode, PolicyConfig, Strategy
from fearguard.supervisor import Command, FearGuard, Observation
from fearguard.vehicle import VehicleLimits

__all__ = [
    "CUE_NAMES",
    "Cause",
    "Command",
    "Cues",
    "FearGuard",
    "FearLevel",
    "FearResult",
    "FearguardError",
    "Lead",
    "Mode",
    "Observation",
    "PolicyConfig",
    "RuleBase",
    "RuleError",
    "Strategy",
    "VehicleLimits",
    "load_rules",
]
