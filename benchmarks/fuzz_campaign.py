"""Hostile-input fuzz campaign: seeded garbage through ``FearGuard.step`` and through every file reader.

    python benchmarks/fuzz_campaign.py [--observations 100000] [--files 5000] [--seed 12]

Observations (cue level and frame level, every field garbage of every type with some probability:
text, bytes, bools, numpy bools, Decimal, Fraction, 0-d and 1-D arrays, huge and non-finite floats,
integers of hundreds of digits, objects whose ``__float__``/``__repr__``/``__str__`` raise; steering
functions that raise, return garbage, or return numbers beyond the steering range (held at full lock, said); times that stall, jump or go
back) and file mutants (rule TOML, scenario TOML, sensor-log CSV and JSONL, Donkey tub manifest and
catalog JSON: lines deleted, duplicated, swapped, numbers replaced by huge/odd ones, deep nesting,
truncation, bytes flipped or not UTF-8, wide rules, typos in keys).

Counted (each must be 0):
- tracebacks: ``step`` raised an Exception, or a reader raised anything but its FearguardError;
- unsafe commands: limit outside [0, max speed], fear outside [0, 1], steering outside ±max or not
  finite, a fault (a ``fault:`` reason, or an injected one) not answered by EMERGENCY/STOP at 0 m/s,
  a non-number cue read as a number (the command's cue is not NaN);
- internal errors: a reason containing "internal error".
Exit status 1 when any count is not 0. ``tests/hostile/test_fuzz_corpus.py`` runs a small count in CI.
"""

from __future__ import annotations

import argparse
import json
import math
import random
import re
import sys
import tempfile
import time
import warnings
from collections import Counter
from collections.abc import Callable
from dataclasses import dataclass, field
from decimal import Decimal
from fractions import Fraction
from pathlib import Path
from typing import Any

import cv2
import numpy as np

import fearguard as fg
from fearguard.cues import CUE_NAMES
from fearguard.errors import FearguardError, SensorLogWarning
from fearguard.readings import reading
from fearguard.replay.sensor_log import load_sensor_log
from fearguard.replay.sources import open_source
from fearguard.sim.scenario import load_scenario

PACKAGE = Path(fg.__file__).resolve().parent
EPISODE_STEPS = (20, 120)  # [steps] per guard before a new one is built
FRAME_SHARE = 0.2  # [-] of observations that carry a frame instead of cues
GARBAGE_P = 0.15  # [-] chance that one field of an observation is garbage
FRAME_SHAPE = (60, 80, 3)  # [px] small frames keep the frame-level part fast


# -- garbage ---------------------------------------------------------------------------------------
class BrokenFloat:
    """A value whose conversion to float raises (a sensor driver's proxy object gone wrong)."""

    def __float__(self) -> float:
        raise RuntimeError("driver crashed")


class Unprintable(Exception):
    """An exception (and a value) that cannot even be printed."""

    def __str__(self) -> str:
        raise Unprintable()

    __repr__ = __str__

    def __float__(self) -> float:
        raise Unprintable()


NON_NUMBERS: tuple[Callable[[random.Random], object], ...] = (
    lambda r: r.choice(["inf", "-inf", "nan", "5", "0.5", "", " 1 ", "1e400", "abc"]),
    lambda r: r.choice([b"inf", b"0.5", b"\xff"]),
    lambda r: r.choice([True, False]),
    lambda r: np.bool_(r.random() < 0.5),
    lambda r: Decimal(r.choice(["0.5", "Infinity", "NaN", "-3"])),
    lambda r: np.array(r.uniform(0, 3)),
    lambda r: np.array([r.uniform(0, 3)] * r.randint(0, 3)),
    lambda r: r.choice([None, [], {}, [0.5], (1.0,), {"x": 1}, 1j, object()]),
    lambda r: BrokenFloat(),
    lambda r: Unprintable(),
    lambda r: 10 ** r.randint(310, 400) * r.choice([1, -1]),
)
ODD_NUMBERS: tuple[Callable[[random.Random], object], ...] = (
    lambda r: r.choice([math.nan, math.inf, -math.inf, -0.0, 5e-324, 1e200, -1e200, 1e308, -1.0]),
    lambda r: Fraction(r.randint(-9, 9), r.randint(1, 9)),
    lambda r: np.float32(r.uniform(-10, 300)),
    lambda r: np.int64(r.randint(-5, 300)),
    lambda r: r.uniform(-1e6, 1e6),
    lambda r: r.randint(-(2**70), 2**70),
)


def non_number(r: random.Random) -> object:
    return r.choice(NON_NUMBERS)(r)


def garbage(r: random.Random) -> object:
    return non_number(r) if r.random() < 0.6 else r.choice(ODD_NUMBERS)(r)


# -- observations ----------------------------------------------------------------------------------
VEHICLES = (
    fg.VehicleLimits(),
    fg.VehicleLimits(has_ultrasonic=True, has_qr_localisation=True),
    fg.VehicleLimits(has_ultrasonic=True),
    fg.VehicleLimits(has_qr_localisation=True, max_speed_mps=1.0, max_steering_deg=20.0),
    # a road car that declares no radar but is given ranges (issue 31: they must count)
    fg.VehicleLimits(max_speed_mps=30.0, max_decel_mps2=6.0, reaction_time_s=0.5, stop_margin_m=1.0, ultrasonic_min_range_m=0.3,
                     ultrasonic_max_range_m=80.0, lead_max_decel_mps2=8.0, max_closing_speed_mps=45.0),
)
CUE_RANGES = ((0.0, 1.0), (0.0, 255.0), (0.0, 1.0), (0.0, 5.0), (0.0, 40.0))


@dataclass
class Tally:
    """What the campaign counts."""

    observations: int = 0
    frames: int = 0
    files: int = 0
    expected_faults: int = 0
    tracebacks: Counter[str] = field(default_factory=Counter)
    unsafe: Counter[str] = field(default_factory=Counter)
    internal_errors: Counter[str] = field(default_factory=Counter)
    file_outcomes: Counter[str] = field(default_factory=Counter)
    examples: list[str] = field(default_factory=list)

    def bad(self, kind: Counter[str], what: str, example: str) -> None:
        kind[what] += 1
        if len(self.examples) < 20:
            self.examples.append(f"{what}: {example}")

    @property
    def clean(self) -> bool:
        return not (self.tracebacks or self.unsafe or self.internal_errors)

    def summary(self) -> dict[str, Any]:
        return {
            "observations": self.observations, "frame_observations": self.frames, "file_mutants": self.files,
            "expected_faults": self.expected_faults, "tracebacks": sum(self.tracebacks.values()),
            "unsafe_commands": sum(self.unsafe.values()), "internal_errors": sum(self.internal_errors.values()),
            "by_kind": {"tracebacks": dict(self.tracebacks), "unsafe": dict(self.unsafe),
                        "internal_errors": dict(self.internal_errors)},
            "file_outcomes": dict(sorted(self.file_outcomes.items())), "examples": self.examples,
        }


BEYOND_LOCK = "beyond lock"  # _steering's answer for a finite angle beyond the range: no fault, a reason


@dataclass
class Injected:
    """What the generator did to one observation, for the oracle."""

    fault: str = ""  # a fault the supervisor must answer with EMERGENCY/STOP
    non_number_cues: tuple[int, ...] = ()  # cue fields given as non-numbers
    beyond_lock: bool = False  # the steering function answered a finite angle beyond the range: held at full lock, said


def _steering(r: random.Random, max_deg: float) -> tuple[Callable[[object], object], str]:
    """A steering function and what it does: "" (a fine angle), "beyond lock" (a finite angle beyond the range, held at
    full lock: no fault) or the fault the supervisor must report."""
    roll = r.random()
    if roll < 0.8:
        value = r.uniform(-max_deg, max_deg)
        return (lambda frame: value), ""
    if roll < 0.87:
        value = garbage(r)
        v = reading(value)  # a reading of exactly 0 is a fine angle (not falsy garbage)
        if v is None or not math.isfinite(v):
            return (lambda frame: value), "steering garbage"
        return (lambda frame: value), BEYOND_LOCK if abs(v) > max_deg else ""
    if roll < 0.93:
        exc = r.choice([ValueError("bad"), ZeroDivisionError(), Unprintable(), MemoryError(), RecursionError()])

        def raising(frame: object) -> float:
            raise exc

        return raising, "steering raised"
    value = r.choice([1.0, -1.0]) * r.uniform(max_deg * 1.01, max_deg * 10)
    return (lambda frame: value), BEYOND_LOCK


def _frame(r: random.Random, rng: np.random.Generator) -> object:
    roll = r.random()
    if roll < 0.75:
        kind = r.randrange(4)
        if kind == 0:
            return rng.integers(0, 256, FRAME_SHAPE, dtype=np.uint8)
        if kind == 1:
            return np.full(FRAME_SHAPE, r.randrange(256), np.uint8)
        if kind == 2:
            img = np.full(FRAME_SHAPE, 70, np.uint8)
            cv2.line(img, (10, 59), (35, 25), (255, 255, 255), 2)
            cv2.line(img, (70, 59), (45, 25), (255, 255, 255), 2)
            return img
        return rng.integers(0, 256, FRAME_SHAPE[:2], dtype=np.uint8)
    return r.choice([
        lambda: np.zeros(64, np.uint8), lambda: np.array(3, np.uint8), lambda: np.zeros((0, 0, 3), np.uint8),
        lambda: rng.random(FRAME_SHAPE), lambda: np.zeros((*FRAME_SHAPE[:2], 2), np.uint8),
        lambda: np.zeros((4, 4, 3, 2), np.uint8), lambda: np.full(FRAME_SHAPE, np.nan), lambda: np.zeros(FRAME_SHAPE, bool),
        lambda: [[0, 1], [2, 3]], lambda: "frame.png", lambda: b"\x89PNG", lambda: BrokenFloat(),
        lambda: np.zeros((1, 1, 3), np.uint8), lambda: np.zeros((2000, 1, 3), np.uint8),
    ])()


def _cues(r: random.Random) -> tuple[fg.Cues, tuple[int, ...]]:
    values: list[object] = [r.uniform(lo, hi) for lo, hi in CUE_RANGES]
    bad: list[int] = []
    for i in range(len(values)):
        if r.random() < GARBAGE_P:
            values[i] = garbage(r)
            if reading(values[i]) is None:
                bad.append(i)
        elif r.random() < 0.05:
            values[i] = math.inf if i >= 3 else r.choice([math.nan, -1.0, 1e9])
    return fg.Cues(*values), tuple(bad)  # type: ignore[arg-type]


def _field(r: random.Random, good: Callable[[], object]) -> object:
    return garbage(r) if r.random() < GARBAGE_P else good()


def _lead(r: random.Random) -> object:
    roll = r.random()
    if roll < 0.6:
        return None
    if roll < 0.8:
        return fg.Lead(bearing_deg=_field(r, lambda: r.uniform(-20, 20)), range_m=_field(r, lambda: r.uniform(0, 5)))  # type: ignore[arg-type]
    if roll < 0.95:
        return fg.LeadBox(*(_field(r, lambda: float(r.randint(-5, 90))) for _ in range(4)))  # type: ignore[arg-type]
    return garbage(r)


def _payload(r: random.Random) -> object:
    roll = r.random()
    if roll < 0.7:
        return None
    if roll < 0.9:
        return f"FG1;route={r.choice(['campus', 'A', 'x' * 40])};sector={r.randint(-1, 3)};pos_m={r.uniform(-5, 100):.{r.randint(0, 3)}f}"
    return garbage(r)


def _time(r: random.Random, last: float | None) -> tuple[object, float | None, str]:
    """The next time stamp (maybe garbage), the supervisor's clock after it, and the fault it must report.

    The supervisor's clock: a finite time not after the last one is a fault and restarts the clock there;
    a time that is not a finite number is a fault and leaves the clock alone.
    """
    base = r.uniform(-10, 10) if last is None else last
    roll = r.random()
    if roll < 0.93:
        value: object = base + r.choice([0.05, 0.05, 0.1, 0.033, 1.0, 5.0])
    elif roll < 0.96:
        value = base - r.choice([0.0, 0.0, 0.01, 3.0])
    else:
        value = garbage(r)
    f = reading(value)
    if f is None or not math.isfinite(f):
        return value, last, "time not a number"
    return value, f, "time did not increase" if last is not None and f <= last else ""


def observation(r: random.Random, rng: np.random.Generator, last: float | None, with_frame: bool
                ) -> tuple[object, float | None, Injected]:
    """One observation, the supervisor's clock after it, and what was injected into it."""
    if r.random() < 0.005:
        return garbage(r), last, Injected(fault="not an observation")
    t_s, clock, fault = _time(r, last)
    t = 0.0 if clock is None else clock
    cues, bad = (None, ()) if with_frame else _cues(r)
    obs = fg.Observation(
        t_s=t_s,  # type: ignore[arg-type]
        speed_mps=_field(r, lambda: r.uniform(0, 3)),  # type: ignore[arg-type]
        frame=_frame(r, rng) if with_frame else None,
        cues=cues,
        ultrasonic_range_m=_field(r, lambda: r.choice([None, r.uniform(0, 5)])),  # type: ignore[arg-type]
        odometer_m=_field(r, lambda: r.choice([None, t * 0.5])),  # type: ignore[arg-type]
        qr_payload=_payload(r),  # type: ignore[arg-type]
        lead=_lead(r),  # type: ignore[arg-type]
        ultrasonic_echo_s=_field(r, lambda: r.choice([None, r.uniform(0, 0.03)])),  # type: ignore[arg-type]
    )
    return obs, clock, Injected(fault=fault, non_number_cues=bad)


def judge(cmd: object, vehicle: fg.VehicleLimits, injected: Injected, tally: Tally) -> None:
    """The oracle: every invariant a command must keep, whatever went in."""
    if not isinstance(cmd, fg.Command):
        tally.bad(tally.unsafe, "not a Command", type(cmd).__name__)
        return
    reasons = [r for r in cmd.reasons if isinstance(r, str)]
    if len(reasons) != len(cmd.reasons):
        tally.bad(tally.unsafe, "reason not text", repr(cmd.reasons)[:80])
    internal = [r for r in reasons if "internal error" in r]
    if internal:
        tally.bad(tally.internal_errors, internal[0].split(":")[1].strip()[:60], internal[0][:160])
    limit, fear, steering = cmd.speed_limit_mps, cmd.fear, cmd.steering_deg
    if not (isinstance(limit, float) and 0.0 <= limit <= vehicle.max_speed_mps):
        tally.bad(tally.unsafe, "speed limit outside [0, max]", repr(limit))
    if not (isinstance(fear, float) and 0.0 <= fear <= 1.0):
        tally.bad(tally.unsafe, "fear outside [0, 1]", repr(fear))
    if not (isinstance(steering, float) and abs(steering) <= vehicle.max_steering_deg):
        tally.bad(tally.unsafe, "steering outside ±max", repr(steering))
    faulted = any(r.startswith("fault:") for r in reasons)
    if injected.fault:
        tally.expected_faults += 1
        if not faulted:
            tally.bad(tally.unsafe, f"injected fault not reported ({injected.fault})", "; ".join(reasons)[:160])
    if faulted and not (cmd.mode is fg.Mode.EMERGENCY and cmd.strategy is fg.Strategy.STOP and limit == 0.0):
        tally.bad(tally.unsafe, "fault not answered by EMERGENCY/STOP", f"{cmd.mode} {cmd.strategy} {limit}")
    if not faulted and injected.beyond_lock and not any("held at full lock" in r for r in reasons):
        tally.bad(tally.unsafe, "steering beyond the range held without a reason", "; ".join(reasons)[:160])
    if not faulted:
        values = cmd.cues.values()
        for i in injected.non_number_cues:
            applies = i != 4 or vehicle.has_qr_localisation  # a range is read on every car; QR only where it applies
            if applies and not math.isnan(values[i]):
                tally.bad(tally.unsafe, f"non-number read as a number ({CUE_NAMES[i]})", repr(values[i]))


    if not faulted:
        _judge_envelope(cmd, vehicle, tally)


def _judge_envelope(cmd: fg.Command, vehicle: fg.VehicleLimits, tally: Tally) -> None:
    """Invariant 2 at the range the command used: v·t_r + v²/(2a) ≤ max(0, d − margin + v_f²/(2b)); a finite range
    counts whatever the car declares."""
    d = cmd.cues.obstacle_range_m
    if not (isinstance(d, float) and 0.0 <= d < math.inf):
        return
    closing = cmd.closing_speed_mps
    v, b = cmd.speed_limit_mps, vehicle.lead_max_decel_mps2
    v_f = 0.0 if not math.isfinite(closing) else max(0.0, -closing)  # unknown speed of the object ahead: standing (the
    # speed the supervisor credited it is at most its closing bound; the oracle credits only an opening gap)
    need = v * vehicle.reaction_time_s + v * v / (2.0 * vehicle.max_decel_mps2)
    room = max(0.0, d - vehicle.stop_margin_m + v_f * v_f / (2.0 * b))
    if need > room + 1e-6 and v > 0.0 and not math.isfinite(closing):
        tally.bad(tally.unsafe, "speed limit beyond the stopping envelope of a given range", f"d={d:.4g} m, limit {v:.4g} m/s")


def run_observations(n: int, seed: int, tally: Tally) -> None:
    """``n`` observations through fresh guards, episode by episode."""
    r, rng = random.Random(seed), np.random.default_rng(seed)
    rule_bases = (fg.load_rules(), fg.load_rules(PACKAGE / "rules" / "road_car.toml"))
    done = 0
    while done < n:
        vehicle = r.choice(VEHICLES)
        steer, steer_fault = _steering(r, vehicle.max_steering_deg)
        guard = fg.FearGuard(steer, rules=r.choice(rule_bases), vehicle=vehicle)
        with_frames = r.random() < FRAME_SHARE
        clock: float | None = None
        for _ in range(min(r.randint(*EPISODE_STEPS), n - done)):
            obs, clock, injected = observation(r, rng, clock, with_frames)
            if steer_fault == BEYOND_LOCK:
                injected.beyond_lock = True
            elif steer_fault and not injected.fault and isinstance(obs, fg.Observation):
                injected.fault = steer_fault
            try:
                cmd = guard.step(obs)  # type: ignore[arg-type]
            except Exception as exc:  # the very thing counted: step must never raise
                tally.bad(tally.tracebacks, f"step raised {type(exc).__name__}", "")
                continue
            finally:
                done += 1
                tally.observations += 1
                tally.frames += with_frames
            judge(cmd, vehicle, injected, tally)


# -- file mutants ---------------------------------------------------------------------------------
def _number_token(r: random.Random) -> str:
    return r.choice(["9" * r.randint(19, 400), "-" + "9" * 320, "1e400", "-1e400", "nan", "inf", "-0", "0", "1e-320",
                     "0x7fffffffffffffff", "3.", ".5", "1_000", str(r.uniform(-100, 100)), str(r.randint(-5, 5)), "true", '"7"'])


def _deep(r: random.Random, json_like: bool) -> str:
    depth = r.choice([10, 70, 300, 1000, 3000])
    if json_like or r.random() < 0.5:
        return "[" * depth + "]" * depth
    return "{a = " * depth + "1" + "}" * depth


def _deep_keys(r: random.Random) -> str:
    """TOML nested without a bracket: dotted keys, or a dotted table header (issue 31: a RecursionError once)."""
    depth = r.choice([70, 1000, 3000])
    path = ".".join(["a"] * depth)
    return f"{path} = 1\n" if r.random() < 0.5 else f"[{path}]\nx = 1\n"


def mutate(text: str, r: random.Random, json_like: bool) -> str:
    """One to three random edits of a text file."""
    for _ in range(r.randint(1, 3)):
        lines = text.splitlines(keepends=True) or [""]
        i, j = r.randrange(len(lines)), r.randrange(len(lines))
        op = r.randrange(11)
        if op == 0:
            del lines[i]
        elif op == 1:
            lines.insert(i, lines[j])
        elif op == 2:
            lines[i], lines[j] = lines[j], lines[i]
        elif op in (3, 4):  # a number replaced by an odd one
            nums = list(re.finditer(r"-?\d+(\.\d+)?([eE][-+]?\d+)?", lines[i]))
            if nums:
                m = r.choice(nums)
                lines[i] = lines[i][: m.start()] + _number_token(r) + lines[i][m.end():]
        elif op == 5:
            value = _deep(r, json_like)
            lines.insert(i, (f'{{"x": {value}}}\n' if json_like else f"deep_{i} = {value}\n"))
        elif op == 10 and not json_like and r.random() < 0.5:
            lines.insert(i, _deep_keys(r))
        elif op == 6:
            cut = r.randrange(len(text) + 1)
            return text[:cut]
        elif op == 7 and lines[i]:
            k = r.randrange(len(lines[i]))
            glyph = r.choice(["[", "]", "{", "}", '"', "'", "=", ",", "#", "\x00", "é", "\\", ";", "\t"])
            lines[i] = lines[i][:k] + glyph + lines[i][k + 1:]
        elif op == 8 and "=" in lines[i]:
            key, _, rest = lines[i].partition("=")
            lines[i] = key.rstrip()[:-1] + r.choice(["x", "_", ""]) + " =" + rest  # a typo in a key
        elif op == 9:
            wide = " AND ".join(["lane_confidence IS low"] * r.choice([3, 201, 600]))
            nots = "NOT " * r.choice([1, 99, 201, 2000])
            lines.insert(i, f'"IF {r.choice([wide, nots + "occlusion IS heavy"])} THEN fear IS high",\n')
        else:
            lines[i] = lines[i].replace(r.choice(["trimf", "trapmf", "0.0", "1.0", "true", "road", "t_s"]),
                                        r.choice(["gauss2mf", "gaussmf", "pimf", "-1.0", "1e999", "false", "", "T_S"]), 1)
        text = "".join(lines)
    return text


def _write(path: Path, text: str, r: random.Random) -> None:
    data = text.encode("utf-8", "surrogatepass")
    if r.random() < 0.03:  # not UTF-8 at all
        k = r.randrange(len(data) + 1)
        data = data[:k] + b"\xff\xfe\xc3" + data[k:]
    path.write_bytes(data)


def _read_rules(path: Path) -> str:
    rb = fg.load_rules(path)
    x = np.array([[0.5, 120.0, 0.3, 2.0, 1.0], [math.nan] * 5, [1.0, 128.0, 0.0, math.inf, 0.0]])
    fears = rb.evaluate_batch(x)
    single = [rb.evaluate(row).fear for row in x]
    if not all(0.0 <= f <= 1.0 for f in [*fears.tolist(), *single]):
        raise AssertionError(f"fear outside [0, 1]: {fears}")
    return "loaded"


def _read_scenario(path: Path) -> str:
    load_scenario(path)
    return "loaded"


def _read_sensor_log(path: Path) -> str:
    log = load_sensor_log(path)
    for t in (-1.0, 0.0, 0.5, 1e308, math.nan):
        log.at(t)
    try:
        load_sensor_log(path, strict=True)
    except FearguardError:
        return "issues"
    return "loaded"


def _read_vehicle(path: Path) -> str:
    from fearguard.vehicle import load_vehicle

    load_vehicle(path)
    return "loaded"


def _read_camera(path: Path) -> str:
    from fearguard.camera import load_camera

    load_camera(path)
    return "loaded"


def _read_counterexample(path: Path) -> str:
    from fearguard.testing.history import load_case

    load_case(path)
    return "loaded"


def _read_tub(folder: Path) -> str:
    source = open_source(folder)
    frames = list(source.iter_frames())
    return f"tub {len(frames)} frames"


@dataclass(frozen=True)
class FileKind:
    """One input format: seed texts, how to write a mutant, how to read it."""

    name: str
    seeds: tuple[str, ...]
    suffix: str
    read: Callable[[Path], str]
    json_like: bool = False


def _sensor_seeds() -> tuple[str, ...]:
    csv = "t_s,ultrasonic_range_m,speed_mps,odometer_m,qr_payload,lead_x,lead_y,lead_w,lead_h\n" + "".join(
        f"{0.05 * i:.2f},{2.0 - 0.01 * i:.3f},0.8,{0.04 * i:.3f},{'FG1;route=A;sector=1;pos_m=5.0' if i == 3 else ''},,,,\n"
        for i in range(12))
    jsonl = "".join(json.dumps({"t_s": 0.05 * i, "ultrasonic_range_m": 2.0 - 0.01 * i, "speed_mps": 0.8, "echo_s": 0.01}) + "\n"
                    for i in range(12))
    return csv, jsonl


def _tub_texts() -> tuple[str, str]:
    manifest = "\n".join([json.dumps(["cam/image_array", "user/angle", "user/throttle"]), json.dumps(["image_array", "float", "float"]),
                          "{}", json.dumps({"created_at": 0}),
                          json.dumps({"paths": ["catalog_0.catalog"], "current_index": 3, "max_len": 1000, "deleted_indexes": []})])
    catalog = "\n".join(json.dumps({"_index": i, "_timestamp_ms": 1000 + 50 * i, "cam/image_array": f"{i}_cam_image_array_.jpg",
                                    "user/angle": 0.1 * i, "user/throttle": 0.3}) for i in range(3))
    return manifest + "\n", catalog + "\n"


def _camera_seed() -> str:
    """A camera.toml as ``fearguard calibrate`` writes it."""
    from fearguard.camera import CameraModel, save_camera

    with tempfile.TemporaryDirectory() as tmp:
        path = Path(tmp) / "camera.toml"
        save_camera(CameraModel(width_px=1280, height_px=720, fx_px=1156.9, fy_px=1152.9, cx_px=665.9, cy_px=388.8,
                                distortion=(-0.2376, -0.0854, -0.0008, -0.0001, 0.1058), mount_height_m=1.2, pitch_deg=1.5), path)
        return path.read_text()


def _counterexample_seed() -> str:
    """A counterexample history as ``fearguard verify`` writes it."""
    from fearguard.testing.history import Case, Step, save_case

    steps = [Step(t_s=0.1 * k, speed_mps=1.0, cues=fg.Cues(1.0 - 0.2 * k, 120.0, 0.1 * k, 3.0 - k, 0.0), steer_output=float(k))
             for k in range(3)]
    with tempfile.TemporaryDirectory() as tmp:
        path = Path(tmp) / "cx.jsonl"
        save_case(path, Case.drive(steps, note="seed"), {"invariant": "limits_in_range", "number": "1"})
        return path.read_text()


def file_kinds() -> list[FileKind]:
    scenarios = tuple((PACKAGE / "scenarios" / n).read_text() for n in ("clear_straight.toml", "slower_lead.toml", "night.toml"))
    rules = tuple((PACKAGE / "rules" / n).read_text() for n in ("default.toml", "road_car.toml"))
    csv, jsonl = _sensor_seeds()
    manifest, catalog = _tub_texts()
    vehicles = ("preset = \"road_car\"\nmax_speed_mps = 25.0\n", "max_speed_mps = 1.5\nhas_ultrasonic = true\nstop_margin_m = 0.2\n")
    cameras = (_camera_seed(),)
    counterexample = _counterexample_seed()
    return [
        FileKind("rules", rules, ".toml", _read_rules),
        FileKind("vehicle", vehicles, ".toml", _read_vehicle),
        FileKind("camera", cameras, ".toml", _read_camera),
        FileKind("counterexample", (counterexample,), ".jsonl", _read_counterexample, json_like=True),
        FileKind("scenario", scenarios, ".toml", _read_scenario),
        FileKind("sensor_csv", (csv,), ".csv", _read_sensor_log),
        FileKind("sensor_jsonl", (jsonl,), ".jsonl", _read_sensor_log, json_like=True),
        FileKind("tub_manifest", (manifest,), "manifest.json", _read_tub, json_like=True),
        FileKind("tub_catalog", (catalog,), "catalog_0.catalog", _read_tub, json_like=True),
    ]


def _tub_folder(root: Path) -> tuple[Path, str, str]:
    folder = root / "tub"
    (folder / "images").mkdir(parents=True)
    for i in range(3):
        cv2.imwrite(str(folder / "images" / f"{i}_cam_image_array_.jpg"), np.full((60, 80, 3), 80 + 20 * i, np.uint8))
    manifest, catalog = _tub_texts()
    return folder, manifest, catalog


def run_files(n: int, seed: int, tally: Tally) -> None:
    """``n`` mutants, the formats in turn; a reader may fail only with its FearguardError."""
    r = random.Random(seed + 1)
    kinds = file_kinds()
    with tempfile.TemporaryDirectory(prefix="fearguard-fuzz-") as tmp:
        root = Path(tmp)
        tub, manifest, catalog = _tub_folder(root)
        for k in range(n):
            kind = kinds[k % len(kinds)]
            text = mutate(r.choice(kind.seeds), r, kind.json_like)
            if kind.name.startswith("tub"):
                _write(tub / "manifest.json", text if kind.name == "tub_manifest" else manifest, r)
                _write(tub / "catalog_0.catalog", text if kind.name == "tub_catalog" else catalog, r)
                path = tub
            else:
                path = root / f"mutant{kind.suffix}"
                _write(path, text, r)
            tally.files += 1
            try:
                outcome = kind.read(path)
            except FearguardError as exc:
                outcome = type(exc).__name__
            except Exception as exc:  # the very thing counted: a reader must fail only with its FearguardError
                tally.bad(tally.tracebacks, f"{kind.name}: {type(exc).__name__}", str(exc)[:120])
                continue
            tally.file_outcomes[f"{kind.name}: {outcome if not outcome.startswith('tub ') else 'tub read'}"] += 1


def campaign(observations: int, files: int, seed: int) -> Tally:
    tally = Tally()
    run_observations(observations, seed, tally)
    run_files(files, seed, tally)
    return tally


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--observations", type=int, default=100_000)
    parser.add_argument("--files", type=int, default=5_000)
    parser.add_argument("--seed", type=int, default=12)
    parser.add_argument("--json", type=Path, help="also write the counts here")
    args = parser.parse_args(argv)
    warnings.simplefilter("ignore", SensorLogWarning)  # mutants with unknown columns: expected, and counted as outcomes
    start = time.perf_counter()
    tally = campaign(args.observations, args.files, args.seed)
    summary = {**tally.summary(), "seed": args.seed, "seconds": round(time.perf_counter() - start, 1)}
    print(json.dumps(summary, indent=2))
    if args.json:
        args.json.write_text(json.dumps(summary, indent=2) + "\n")
    return 0 if tally.clean else 1


if __name__ == "__main__":
    sys.exit(main())

