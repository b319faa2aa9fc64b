"""The cars fearguard is compared with: same steering estimator, same car, a different speed rule.

    unguarded  cruise speed, no supervisor
    crisp      the classic model-car rule: stop when the ultrasonic range is below 15 inches, else cruise
    aeb        time-to-collision emergency braking only (as common AEB systems): brake when TTC < AEB_TTC_S

Each is a small stateful object: ``speed_target(t_s, ultrasonic_range_m, speed_mps) -> m/s``.
"""

from __future__ import annotations

import math

from fearguard.sensors.ultrasonic import UltrasonicFilter

CRISP_STOP_M = 15 * 0.0254  # [m] 15 inches, the Raspberry-Pi car paper's stop distance
AEB_TTC_S = 1.5  # [s] full braking below this time to collision (Euro NCAP AEB systems brake at about 0.8–1.6 s)
AEB_MIN_RANGE_M = 0.2  # [m] and always when the obstacle is this close
BASELINES = ("unguarded", "crisp", "aeb")


class Baseline:
    """A speed rule without fear: cruise unless the rule says stop."""

    def __init__(self, name: str, cruise_mps: float, min_range_m: float = 0.15, max_range_m: float = 3.96) -> None:
        if name not in BASELINES:
            raise ValueError(f"unknown baseline {name!r}; choose one of {', '.join(BASELINES)}")
        self.name, self.cruise_mps = name, cruise_mps
        self.filter = UltrasonicFilter(min_range_m, max_range_m)
        self.braking = False

    def speed_target(self, t_s: float, ultrasonic_range_m: float | None) -> float:
        if self.name == "unguarded":
            return self.cruise_mps
        if self.name == "crisp":
            r = ultrasonic_range_m
            stop = r is not None and math.isfinite(r) and 0.0 < r < CRISP_STOP_M
            return 0.0 if stop else self.cruise_mps
        est = self.filter.update(t_s, ultrasonic_range_m)
        close = math.isfinite(est.range_m) and est.range_m < AEB_MIN_RANGE_M
        self.braking = close or (math.isfinite(est.ttc_s) and est.ttc_s < AEB_TTC_S)
        return 0.0 if self.braking else self.cruise_mps
