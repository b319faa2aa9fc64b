"""Exceptions a person can act on.

    FearguardError          base: the CLI catches it, prints ``Type: message`` and exits 2
    ├── RuleError           a rule-base file is wrong (names the file, the line or key, and the fix)
    ├── CameraError         camera.toml is wrong (camera.py)
    ├── CalibrationError    chessboard photos cannot calibrate (calibration.py)
    ├── ScenarioError       a scenario file is wrong (sim/schema.py)
    ├── SourceError         a recording cannot be read (replay/sources.py)
    └── SensorLogError      a sensor log line is malformed, with --strict (replay/sensor_log.py)

``FearGuard.step`` never raises any of these: faults at run time become safe commands.
"""

from __future__ import annotations

from pathlib import Path


class FearguardError(Exception):
    """Base of every error fearguard raises on purpose."""


class RuleError(FearguardError):
    """A rule-base file (TOML) is malformed or inconsistent."""

    def __init__(self, path: str | Path, where: str, problem: str) -> None:
        self.path = str(path)
        self.where = where
        self.problem = problem
        super().__init__(f"{self.path}, {where}: {problem}")
