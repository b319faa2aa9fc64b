"""Every exception class fearguard defines, in one tree.

    Exception
    ├── FearguardError              base of errors raised on purpose: the CLI prints ``Type: message``, exits 2
    │   ├── CalibrationError        chessboard photos cannot calibrate (vision/calibration.py)
    │   ├── SteerImportError        a ``module:function`` that names no usable steering function (files/steer_import.py)
    │   ├── SetupError              a vehicle, preset or steering function the testing kit cannot use (testing/subject.py)
    │   ├── SimulatorMissing        gym-duckietown or MetaDrive is not installed (worlds/duckietown/world.py, metadrive/headless.py)
    │   ├── MapError                a map, start or placement a simulator cannot build (worlds/duckietown/world.py, metadrive/world.py)
    │   ├── ClusterError            Dask is not installed, or its scheduler cannot be reached (drive/cluster.py)
    │   ├── SweepError              a sweep's --set that names no number of the rules or the vehicle (sim/sweep.py)
    │   └── FileError               a file is wrong: ``FileError(path, where, problem)`` → "path, where: problem"
    │       ├── RuleError           a rule-base file and its [policy] table (fuzzy/loader.py)
    │       ├── CameraError         camera.toml (camera.py)
    │       ├── VehicleFileError    vehicle.toml, or a --vehicle that names neither a preset nor a file (vehicle.py)
    │       ├── ScenarioError       a scenario file (sim/scenario.py)
    │       ├── SourceError         a recording: video, image folder, Donkey Car tub (replay/sources.py)
    │       ├── SensorLogError      a sensor log, with --strict (replay/sensor_log.py); its place is a line number
    │       └── HistoryError        a counterexample history file (testing/history.py); its place is a line number
    ├── ValueError
    │   └── RuleSyntaxError         a rule's text does not parse (fuzzy/rule_text.py); the loader wraps it in RuleError
    └── RuntimeError
        └── EstimatorFault          a fault the simulator injects into a steering estimator (sim/loop.py)

    UserWarning
    ├── SensorLogWarning            something in a sensor log is ignored, the log is still used
    └── CameraPitchWarning          the lane lines meet away from the horizon the camera model assumes (replay/pitch.py)

Each module that raises one imports it from here (its old import path keeps working: ``fearguard.vehicle.VehicleFileError``).

Every file is read through ``files/reader.py`` (bounded size and nesting, strict tables), so a malformed file
is always one of the ``FileError`` kinds above, naming the file, the line and the key.
``FearGuard.step`` never raises any of these: faults at run time become safe commands.
"""

from __future__ import annotations

from pathlib import Path


class FearguardError(Exception):
    """Base of every error fearguard raises on purpose."""


class FileError(FearguardError):
    """A file (or an input naming one) cannot be used; ``where`` is e.g. ``line 12, key policy.hold_s``."""

    def __init__(self, path: str | Path | None, where: str, problem: str) -> None:
        self.path = None if path is None else str(path)
        self.where = where
        self.problem = problem
        prefix = ", ".join(p for p in (self.path, where) if p)
        super().__init__(f"{prefix}: {problem}" if prefix else problem)


class RuleError(FileError):
    """A rule-base file (TOML) is malformed or inconsistent."""


class CameraError(FileError):
    """A camera file (TOML) is missing, malformed or physically impossible."""


class ScenarioError(FileError):
    """A scenario file (TOML) is missing, malformed, or describes an impossible world."""


class SourceError(FileError):
    """A recording cannot be used at all: missing, in a format OpenCV cannot decode, empty, or a broken tub."""


class SensorLogError(FileError):
    """A sensor log cannot be used: missing, no header or no t_s column, or (strict) a malformed line."""

    def __init__(self, path: str | Path, line: int | None, problem: str) -> None:
        self.line = line  # a log's place is its line number (1-based), None for the whole file
        super().__init__(path, "" if line is None else f"line {line}", problem)


class CalibrationError(FearguardError):
    """Calibration cannot be done with these inputs (no images, bad pattern, too few boards, mixed sizes)."""


class RuleSyntaxError(ValueError):
    """The text is not a rule; the message says what was expected where."""


class EstimatorFault(RuntimeError):
    """Raised by the faulty steering estimator of a scenario (the supervisor must survive it)."""


class SensorLogWarning(UserWarning):
    """Something in a sensor log is ignored (unknown columns) but the log is still used."""


class CameraPitchWarning(UserWarning):
    """The lane lines' vanishing point lies more than a few degrees from the horizon the camera model assumes."""


# -- quoting foreign values in messages --------------------------------------------------------
DESCRIBE_CHARS = 80  # [characters] of a foreign value quoted in a message or a reason


def describe(value: object) -> str:
    """``repr`` of a foreign value for a message, shortened; never raises (a broken ``repr`` is named by type)."""
    try:
        text = repr(value)
    except Exception:  # foreign objects may fail even to print: the message must still be written
        return f"<{type(value).__name__} whose repr raises>"
    return text if len(text) <= DESCRIBE_CHARS else text[: DESCRIBE_CHARS - 1] + "…"


def describe_exception(exc: BaseException) -> str:
    """``Type: message`` of an exception; never raises (a broken ``__str__`` is reported as such)."""
    try:
        text = str(exc)
    except Exception:  # an exception whose __str__ raises must not escape the handler that reports it
        text = "<message unprintable>"
    return f"{type(exc).__name__}: {text}"


class VehicleFileError(FileError):
    """A vehicle.toml that cannot be used (or a --vehicle that names neither a preset nor a file): names the key."""


class HistoryError(FileError):
    """A history file (a counterexample) cannot be read: names the file, the line and the field."""

    def __init__(self, path: str | Path, line: int | None, problem: str) -> None:
        self.line = line
        super().__init__(path, f"line {line}" if line else "", problem)


class SteerImportError(FearguardError):
    """A ``module:function`` that does not name a usable steering function."""


class SetupError(FearguardError):
    """A vehicle file, preset or steering function given to the testing kit cannot be used."""


class SimulatorMissing(FearguardError):
    """A simulator (gym-duckietown, MetaDrive) is not installed in this Python environment."""


class MapError(FearguardError):
    """A map name, start, block string or placement the simulator does not know or cannot build."""


class ClusterError(FearguardError):
    """``--jobs N``/``--scheduler`` cannot run: Dask is not installed, or the scheduler does not answer."""


class SweepError(FearguardError):
    """A sweep's ``--set KEY=V1,V2`` names no number of the rule file or the vehicle, or gives no usable values."""
