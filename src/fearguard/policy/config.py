"""The policy's vocabulary and numbers: the modes, the emergency strategies, and a rule file's ``[policy]`` table.

``PolicyConfig`` holds plain values; the rule-file loader (``fuzzy/loader.py``) reads and validates the table.
"""

from __future__ import annotations

from dataclasses import dataclass
from enum import Enum

TIME_EPS_S = 1e-9  # [s] slack in time comparisons, so that 10 steps of 0.1 s count as 1.0 s


class Mode(Enum):
    """The supervisor's modes, declared from least to most cautious (expectations such as ``mode_by`` rely on the order)."""

    NORMAL = "NORMAL"
    CAUTION = "CAUTION"
    EMERGENCY = "EMERGENCY"


class Strategy(Enum):
    PASS_THROUGH = "PASS_THROUGH"
    FOLLOW_LEAD = "FOLLOW_LEAD"
    STOP = "STOP"
    CRAWL = "CRAWL"


@dataclass(frozen=True)
class PolicyConfig:
    """The policy numbers of a rule file's ``[policy]`` table (defaults: a 1:10 model car)."""

    speed_fraction: tuple[float, ...] = (1.0, 0.8, 0.6, 0.4, 0.3)  # of max speed, per fear level
    caution_fear: float = 0.375  # [-] fear at or above which the mode is CAUTION
    emergency_enter_fear: float = 0.7  # [-] fear that counts toward entering EMERGENCY
    emergency_exit_fear: float = 0.5  # [-] fear below which the hold timer runs
    enter_frames: int = 3  # [frames] consecutive frames over the enter threshold
    hold_s: float = 2.0  # [s] time below the exit threshold before EMERGENCY is left
    comfort_accel_mps2: float = 0.5  # [m/s²] fastest rise of the speed limit
    crawl_fraction: float = 0.15  # [-] of max speed, CRAWL cap (and FOLLOW_LEAD without a range)
    follow_time_gap_s: float = 1.5  # [s] a moving object ahead is followed with this time gap (and FOLLOW_LEAD's range / gap)
    follow_decel_mps2: float = 0.5  # [m/s²] braking planned to fall back to a slower moving object's speed at the time gap
    follow_gain: float = 1.0  # [deg/deg] steering per degree of lead bearing
    watchdog_frames: int = 10  # [frames] a frame later than this many typical periods after the last is a stall
    watchdog_age_s: float = 1.0  # [s] ... and later than this (openpilot: a message older than max(10 periods, …))
    recovery_dwell_s: float = 1.0  # [s] at standstill after a road-picture stop before a re-acquisition creep
    recovery_creep_m: float = 0.6  # [m] longest single creep
    recovery_creep_s: float = 4.0  # [s] longest single creep in time
    recovery_max_creeps: int = 4  # [-] creeps per EMERGENCY; then the car stays stopped and says why
    recovery_max_total_m: float = 2.0  # [m] total creep distance per EMERGENCY
    standstill_mps: float = 0.05  # [m/s] at or below this the car counts as standing still
    moving_object_min_mps: float = 0.15  # [m/s] an object ahead slower than this (ego speed − closing speed) stands
    recovery_min_confidence: float = 0.25  # [-] lane_confidence from which a creep steers by the lane seen now
    recovery_min_guide: float = 0.15  # [-] a boundary's guide (LaneEvidence.guide) from which a frame found the lane
    recovery_blind_m: float = 0.3  # [m] creep distance with nothing of the lane in sight, per EMERGENCY
    recovery_creep_max_deg: float = 6.0  # [deg] a creep steered by the wrapped estimator stays within ± this
    road_enter_s: float = 0.5  # [s] a road-picture-only emergency with the path known clear waits this long, in CAUTION
    road_doubt_fraction: float = 0.4  # [-] of max speed while it waits (a flickering picture: slow down, do not stop)
    route_blind_m: float = 0.0  # [m] followed by the caller's route steering per loss of the road picture, the path known
    #   clear, before an emergency (policy.route; 0: a route is not followed)
    stop_line_wait_s: float = 0.0  # [s] standing before a stop line before crossing (0: stop lines are not stopped for)
    stop_line_cross_m: float = 1.0  # [m] after a served stop, lines are not stopped for again within this distance
    oscillation_deg: float = 10.0  # [deg] a steering sign flip between two frames, both beyond this, is large
    oscillation_flips: int = 3  # [-] this many large sign flips in a row: the estimator oscillates (a fault)
    lane_check_lookahead_s: float = 1.0  # [s] the lane check looks this far ahead (time to line crossing)
    lane_check_min_deg: float = 5.0  # [deg] the estimator must steer this much more toward the boundary than the lane
    lane_check_fraction: float = 0.6  # [-] of max speed while the lane check overrides the estimator


MODE_ORDER: tuple[str, ...] = tuple(m.name for m in Mode)  # least to most cautious: tables and plots use this order
STRATEGY_ORDER: tuple[str, ...] = tuple(s.name for s in Strategy)
