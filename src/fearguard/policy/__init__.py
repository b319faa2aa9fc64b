"""Policy: fear → speed limit ∧ stopping envelope, the mode machine, the emergency strategy, and the decision's steps.

Pure functions over plain values; the supervisor owns the state and the clock. Policy never looks at pixels and
reads no files: the rule-file loader reads the ``[policy]`` numbers, perception measures the lane geometry.

Speed limit = min(fear limit, stopping envelope, lane-check cap, emergency cap, lateral limit), then rate-limited
upward by the comfort acceleration. Each emergency cause that is active imposes its own cap and the smallest wins,
so a cue getting worse can only add caps: the limit never rises when a cue worsens.

    config.py     Mode, Strategy, PolicyConfig (the numbers of a rule file's [policy] table)
    speed.py      fear speed, stopping distance and envelope (RSS), imminent collision, lateral and rate limits
    modes.py      the mode machine (enter counter, hold, latched causes)
    emergency.py  the plan of each active cause, the re-acquisition creep
    lane_check.py will the wrapped steering cross a lane boundary soon?
    stop_line.py  stand before a stop line, wait, then cross
    route.py      follow the caller's route where the road picture is lost and the path is known clear
    decision.py   one frame's decision as named steps: speed caps, the steering choice, the explanation
"""

from fearguard.observation import Lead  # defined with the other plain values; fearguard.policy.Lead keeps working
from fearguard.policy.config import MODE_ORDER, STRATEGY_ORDER, TIME_EPS_S, Mode, PolicyConfig, Strategy
from fearguard.policy.emergency import (
    CAUSE_WORDS,
    EmergencyPlan,
    Recovery,
    active_causes,
    creep_clearance,
    creep_needs_m,
    emergency_plan,
    lane_in_sight,
    lane_reacquired,
    next_recovery,
    recovery_eligible,
    recovery_exhausted,
    recovery_status,
)
from fearguard.policy.modes import Latch, ModeState, next_mode
from fearguard.policy.speed import (
    CLOSING_WINDOW_S,
    ENVELOPE_SHRINK,
    closing_speed_from_ranges,
    envelope_speed_mps,
    fear_speed_mps,
    imminent_collision,
    lateral_speed_mps,
    lead_speed_mps,
    oscillating,
    rate_limited_mps,
    rate_limited_steering_deg,
    same_object_after_gap,
    stopping_distance_m,
    watchdog_s,
)

__all__ = [
    "CAUSE_WORDS", "CLOSING_WINDOW_S", "ENVELOPE_SHRINK", "MODE_ORDER", "STRATEGY_ORDER", "TIME_EPS_S", "EmergencyPlan",
    "Latch", "Lead", "Mode", "ModeState", "PolicyConfig", "Recovery", "Strategy", "active_causes",
    "closing_speed_from_ranges", "creep_clearance", "creep_needs_m", "emergency_plan", "envelope_speed_mps",
    "fear_speed_mps", "imminent_collision", "lane_in_sight", "lane_reacquired", "lateral_speed_mps", "lead_speed_mps",
    "next_mode", "next_recovery", "oscillating", "rate_limited_mps", "rate_limited_steering_deg", "recovery_eligible",
    "recovery_exhausted", "recovery_status", "same_object_after_gap", "stopping_distance_m", "watchdog_s",
]
