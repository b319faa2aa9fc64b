"""The supervisor under test: a rule base, a vehicle, a steering function; and running a history through it.

``Subject.of(rules=..., vehicle=..., steer=...)`` accepts what a user has at hand: a rule file path (or
a loaded ``RuleBase``; None = the bundled default), a ``VehicleLimits`` (or a preset name or a
``vehicle.toml`` path; None = the default car), a steering function frame → degrees (or
``"module:function"``; None = the history's scripted outputs). Every run starts from a fresh
``FearGuard`` (and ``steer.reset()`` when the steering function has one), so runs are independent.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass, fields
from pathlib import Path
from typing import Any

import fearguard as fg
from fearguard.errors import SetupError  # defined in errors.py, importable here
from fearguard.files.steer_import import resolve_steer
from fearguard.testing.frames import frame_pixels
from fearguard.testing.history import History, SteerRaises, Step
from fearguard.vehicle import resolve_vehicle as vehicle_by_name
from fearguard.vehicle import vehicle_from_table


@dataclass(frozen=True, eq=False)
class Subject:
    """What is verified: the rules, the vehicle, and the wrapped steering function (None: scripted)."""

    rules: fg.RuleBase
    vehicle: fg.VehicleLimits
    steer: Callable[[Any], Any] | None = None
    vehicle_name: str = "default"
    steer_name: str = "scripted"
    track: fg.TrackProfile | None = None  # a learnt track profile the supervisor reads frames with (None: none)
    track_path: str | None = None

    @classmethod
    def of(cls, rules: fg.RuleBase | str | Path | None = None, vehicle: fg.VehicleLimits | str | Path | None = None,
           steer: Callable[[Any], Any] | str | None = None, track: fg.TrackProfile | str | Path | None = None) -> Subject:
        rb = rules if isinstance(rules, fg.RuleBase) else fg.load_rules(rules)
        car, car_name = resolve_vehicle(vehicle)
        check_honourable(car, car_name)
        fn, fn_name = resolve_steer(steer)
        profile = fg.load_track(track) if isinstance(track, str | Path) else track
        return cls(rb, car, fn, car_name, fn_name, profile, str(track) if isinstance(track, str | Path) else None)

    def header(self) -> dict[str, Any]:
        """What a counterexample file records about the subject, to replay it."""
        return {
            "rules": self.rules.path, "rules_name": self.rules.name, "vehicle_name": self.vehicle_name,
            "vehicle": {f.name: _json_number(getattr(self.vehicle, f.name)) for f in fields(self.vehicle)},
            "steer": self.steer_name, **({"track": self.track_path} if self.track_path else {}),
        }


def _json_number(v: Any) -> Any:
    return ("inf" if v > 0 else "-inf") if isinstance(v, float) and math.isinf(v) else v


def presets() -> dict[str, fg.VehicleLimits]:
    """The named vehicle presets of ``fearguard.vehicle`` (PRESETS), plus "default" = ``VehicleLimits()``."""
    from fearguard.vehicle import PRESETS

    return {"default": fg.VehicleLimits(), **dict(PRESETS)}


def distinct_presets() -> dict[str, fg.VehicleLimits]:
    """The presets with different numbers (aliases of the same car dropped): the cars a matrix test covers."""
    out: dict[str, fg.VehicleLimits] = {}
    for name, car in presets().items():
        if all(car != other for other in out.values()):
            out[name] = car
    return out


def vehicle_from_mapping(data: dict[str, Any], where: str) -> fg.VehicleLimits:
    """A VehicleLimits from a table of its fields (a counterexample header: infinities as "inf"); errors name the key."""
    values = {k: (float(v) if v in ("inf", "-inf") else v) for k, v in data.items() if v is not None}  # None: the default
    return vehicle_from_table(values, where)


TYRE_GRIP_MPS2 = 9.81  # [m/s²] μ = 1 on dry asphalt: the hardest braking tyres deliver without aerodynamic downforce


def check_honourable(car: fg.VehicleLimits, where: str) -> None:
    """Reject a vehicle whose stated numbers the stopping envelope cannot honour: braking beyond tyre grip
    (the envelope would plan stops the car cannot make), a stop margin the range sensor cannot see past (it
    could never move), a range filter slower than the car itself (its own approach would read as noise)."""
    if car.max_decel_mps2 > TYRE_GRIP_MPS2:
        raise SetupError(f"vehicle {where}: max_decel_mps2 = {car.max_decel_mps2:g} m/s² is more than tyres deliver "
                         f"(≈ {TYRE_GRIP_MPS2:g} m/s², μ = 1): the envelope would plan stops this car cannot make; "
                         "state the braking measured on the car")
    if not car.has_ultrasonic:
        return
    if car.stop_margin_m >= car.ultrasonic_max_range_m:
        raise SetupError(f"vehicle {where}: stop_margin_m = {car.stop_margin_m:g} m is not inside the range sensor's "
                         f"{car.ultrasonic_max_range_m:g} m: the envelope could never let it move")
    if car.max_closing_speed_mps < car.max_speed_mps:
        raise SetupError(f"vehicle {where}: max_closing_speed_mps = {car.max_closing_speed_mps:g} m/s is below its own top "
                         f"speed {car.max_speed_mps:g} m/s: the range filter would reject its approach to a standing obstacle")


def resolve_vehicle(vehicle: fg.VehicleLimits | str | Path | None) -> tuple[fg.VehicleLimits, str]:
    """A VehicleLimits and its name from a value, "default", a preset name or a vehicle.toml path
    (``fearguard.vehicle.resolve_vehicle`` decides; this adds the name the kit's reports print)."""
    if vehicle is None or (isinstance(vehicle, str) and vehicle == "default"):
        return fg.VehicleLimits(), "default"
    if isinstance(vehicle, fg.VehicleLimits):
        return vehicle, "given"
    return vehicle_by_name(vehicle), str(vehicle)


class _NotCalled:
    def __repr__(self) -> str:
        return "not called"


NOT_CALLED = _NotCalled()  # the supervisor did not ask the steering function this frame


@dataclass(frozen=True)
class Run:
    """The commands a history produced, and what the wrapped steering function answered each frame."""

    commands: tuple[fg.Command, ...]
    steering_in: tuple[Any, ...]  # the wrapped function's raw answer per frame (NOT_CALLED; SteerRaises: it raised)
    raised: str | None = None  # step() raised: the supervisor broke its contract


def observation(step: Step, frame: Any, scripted: bool = False) -> fg.Observation:
    """The Observation a step describes; ``scripted``: the step's steering output comes with it (``steering_deg``), as a
    caller that holds the estimator's angle passes it (a scripted raise is a value that is no angle: a fault too)."""
    return fg.Observation(
        t_s=step.t_s, speed_mps=step.speed_mps, frame=frame, cues=step.cues, ultrasonic_range_m=step.ultrasonic_range_m,
        odometer_m=step.odometer_m, qr_payload=step.qr_payload, lead=step.lead, ultrasonic_echo_s=step.ultrasonic_echo_s,
        range_rate_mps=step.range_rate_mps, steering_deg=step.steer_output if scripted else None,
    )


class Driver:
    """One supervisor around the subject's steering function (or a script), fed history after history.

    The steering function is wrapped so that every frame's raw answer is recorded (the checkers compare
    it with the command); ``reset()`` resets the supervisor and, if it has one, the steering function.
    """

    def __init__(self, subject: Subject) -> None:
        self.subject = subject
        self._answers: list[Any] = []
        self.guard = fg.FearGuard(self._steer if subject.steer is not None else None, rules=subject.rules, vehicle=subject.vehicle,
                                  track=subject.track)
        self._reset_steer()

    def _reset_steer(self) -> None:
        reset = getattr(self.subject.steer, "reset", None)
        if callable(reset):
            reset()

    def reset(self) -> None:
        self.guard.reset()
        self._reset_steer()

    def _steer(self, frame: Any) -> Any:
        """The subject's own steering function, its answer (or that it raised) recorded for the checkers."""
        assert self.subject.steer is not None  # only wrapped when there is one (a scripted answer comes in the Observation)
        try:
            out = self.subject.steer(frame)
        except Exception as exc:  # recorded for the checkers, then handed on: the supervisor must catch it
            self._answers[-1] = SteerRaises(type(exc).__name__)
            raise
        self._answers[-1] = out
        return out

    def drive(self, history: History) -> Run:
        """Feed the history frame by frame; a step() that raises ends the run and is reported, never re-raised."""
        commands: list[fg.Command] = []
        self._answers = []
        previous: Any = None
        scripted = self.subject.steer is None
        for i, step in enumerate(history):
            self._answers.append(step.steer_output if scripted else NOT_CALLED)
            frame = frame_pixels(step.frame, previous)
            previous = frame
            try:
                commands.append(self.guard.step(observation(step, frame, scripted)))
            except Exception as exc:  # the contract says step never raises: report it as the violation
                return Run(tuple(commands), tuple(self._answers), f"step {i} raised {type(exc).__name__}: {exc}")
        return Run(tuple(commands), tuple(self._answers))


def run(subject: Subject, history: History) -> Run:
    """Feed a history to a fresh supervisor; never raises for what the supervisor does."""
    return Driver(subject).drive(history)

