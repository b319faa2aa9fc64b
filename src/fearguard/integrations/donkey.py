"""Donkey Car part: fearguard between the pilot (or ``DriveMode``) and the drive train.

    part = FearGuardPart.from_cfg(cfg)
    V.add(part, inputs=part.inputs, outputs=part.outputs)

Conversions at the boundary, both ways, explicit (docs/donkey.md):
- angle ``a`` ∈ [−1, 1] with −1 = full left (Donkey) ↔ ``steering_deg = −a · max_steering_deg`` (+ = left, ISO 8855);
- throttle ``u`` ∈ [−1, 1] ↔ commanded speed ``u · max_speed_mps`` (the speed at full throttle, measured);
  out ``u' = min(u, limit / max_speed_mps)`` for u ≥ 0; u < 0 (brake / reverse) passes unchanged;
- frames: Donkey cameras give RGB (or grey), fearguard's vision wants BGR: converted into a new array
  every loop (so a camera that refills one buffer is analysed afresh);
- TFMini ``lidar/dist`` in cm, 0 before its first echo; ``enc/speed`` in m/s (HAVE_ODOM);
- without odometry the speed is estimated from the throttle actually sent, first order:
  ``v̂ ← v̂ + (1 − e^(−dt/τ)) · (max(u', 0) · max_speed_mps − v̂)``, falling no faster than ``max_decel_mps2``
  (an estimate that errs high while braking: the stopping envelope stays conservative).

Parts get no timestamp, so the part reads a monotonic clock (wall time can step back on a Pi without a
real-time clock). Every output is a finite float or a string, so ``TubWriter`` can record it (it
rejects NaN and inf). Until every wired sensor has delivered its first reading (a frame; a TFMini echo)
the part holds the car still with ``fear/mode = "STARTING"`` rather than entering an emergency. A car without
``FEARGUARD_TRACK`` whose camera hardly sees the lane over its first ``EYES_LOOPS`` loops (and so stands) logs once
what would help (``replay/eyes.py``).
"""

from __future__ import annotations

import logging
import math
import time
from collections.abc import Callable, Sequence
from dataclasses import replace
from pathlib import Path
from typing import Any

import cv2
import numpy as np

from fearguard.camera import CameraModel, camera_preset, load_camera
from fearguard.readings import finite_reading
from fearguard.replay.eyes import DONKEY, EyesCheck
from fearguard.supervisor import Command, FearGuard, Observation
from fearguard.vehicle import PRESETS, VehicleLimits

logger = logging.getLogger(__name__)

TFMINI_MIN_RANGE_M = 0.3  # [m] TFMini datasheet range 0.3–12 m (TFMini Plus 0.1–12 m): closer readings are not trusted
TFMINI_MAX_RANGE_M = 12.0  # [m] beyond it the sensor sees nothing in range
SPEED_LAG_S = 0.5  # [s] time to 63 % of a throttle step's speed on a 1:10 car (brushed ESC); measure yours (docs/donkey.md)
STARTING = "STARTING"  # fear/mode while a wired sensor has not delivered its first reading
FAULT = "FAULT"  # fear/mode if the part itself failed (never expected; the car is held still)
FEAR_OUTPUTS = ("fear/value", "fear/mode", "fear/limit_mps")
FEAR_TYPES = ("float", "str", "float")  # TubWriter types of FEAR_OUTPUTS
TFMINI_CHANNEL = "lidar/dist"  # donkeycar's TFMini part (cm)
ODOM_CHANNEL = "enc/speed"  # donkeycar's odometry (m/s)
EYES_LOOPS = 400  # [loops] supervised loops (20 s at Donkey's 20 Hz) after which the part says, once, if the lane was hardly seen


def estimated_speed_mps(
    previous_mps: float, throttle: float, dt_s: float, *, full_throttle_mps: float, lag_s: float, decel_mps2: float
) -> float:
    """Speed after ``dt_s`` at ``throttle``: first-order lag toward ``max(throttle, 0) · full_throttle_mps``.

    ``v + (1 − e^(−dt/τ)) · (target − v)``, but never falling faster than ``decel_mps2 · dt`` (a car
    coasts or brakes no harder than that, so the estimate errs high while slowing down).
    """
    target = max(0.0, min(1.0, throttle)) * full_throttle_mps
    gain = 1.0 - math.exp(-max(0.0, dt_s) / lag_s) if lag_s > 0 else 1.0
    v = previous_mps + gain * (target - previous_mps)
    return max(v, previous_mps - decel_mps2 * max(0.0, dt_s), 0.0)


def donkey_to_deg(angle: float, max_steering_deg: float) -> float:
    """Donkey angle (−1 = full left … +1 = full right) → fearguard degrees (+ = left)."""
    return -angle * max_steering_deg


def deg_to_donkey(steering_deg: float, max_steering_deg: float) -> float:
    """fearguard degrees (+ = left) → Donkey angle in [−1, 1] (−1 = full left)."""
    return max(-1.0, min(1.0, -steering_deg / max_steering_deg))


def _bgr(image: object) -> np.ndarray | None:
    """A Donkey camera image (RGB, or grey with IMAGE_DEPTH = 1) as a new BGR array; None if not an image."""
    if not isinstance(image, np.ndarray) or image.dtype != np.uint8 or image.size == 0:
        return None
    if image.ndim == 3 and image.shape[2] == 3:
        return cv2.cvtColor(image, cv2.COLOR_RGB2BGR)
    if image.ndim == 2 or (image.ndim == 3 and image.shape[2] == 1):
        return cv2.cvtColor(image, cv2.COLOR_GRAY2BGR)
    return None


class FearGuardPart:
    """A Donkey part: ``run(image, angle, throttle[, lidar/dist][, enc/speed])`` → guarded angle, throttle, fear.

    ``channels`` are the two channels it guards (read and rewritten): ``("pilot/angle", "pilot/throttle")``
    guards the autopilot only; ``("steering", "throttle")`` after ``DriveMode`` guards every drive mode.
    """

    def __init__(
        self,
        *,
        vehicle: VehicleLimits,
        rules: Any = None,
        camera: CameraModel | None = None,
        has_tfmini: bool = False,
        has_odom: bool = False,
        speed_lag_s: float = SPEED_LAG_S,
        channels: Sequence[str] = ("pilot/angle", "pilot/throttle"),
        image_channel: str = "cam/image_array",
        clock: Callable[[], float] = time.monotonic,
        track: Any = None,
    ) -> None:
        if len(channels) != 2:
            raise ValueError(f"channels must be (angle channel, throttle channel), got {channels!r}")
        self.vehicle = vehicle
        # the pilot's angle comes in each Observation; a track profile (path or TrackProfile) adds the familiarity cue
        self.guard = FearGuard(None, rules=rules, vehicle=vehicle, camera=camera, track=track)
        self.has_tfmini, self.has_odom = has_tfmini, has_odom
        self.speed_lag_s = speed_lag_s
        self.clock = clock
        self.inputs = [image_channel, *channels] + [TFMINI_CHANNEL] * has_tfmini + [ODOM_CHANNEL] * has_odom
        self.outputs = [*channels, *FEAR_OUTPUTS]
        self.types = ["float", "float", *FEAR_TYPES]  # for TubWriter: inputs += part.outputs; types += part.types
        self.last_command: Command | None = None
        self._eyes: EyesCheck | None = EyesCheck(self.guard.rules.policy.recovery_min_confidence, camera=camera is not None,
                                                 track=track is not None, remedies=DONKEY)
        self._reset_state()

    def _reset_state(self) -> None:
        self._started = False
        self._last_t_s: float | None = None
        self._speed_mps = 0.0

    # -- construction from a Donkey config ---------------------------------------------------
    @classmethod
    def from_cfg(
        cls, cfg: Any, *, channels: Sequence[str] = ("pilot/angle", "pilot/throttle"), clock: Callable[[], float] = time.monotonic
    ) -> FearGuardPart:
        """Build the part from a Donkey config (``myconfig.py`` / ``cfg_complete.py`` keys, FEARGUARD_* for its own).

        ``FEARGUARD_PRESET`` (a name in ``fearguard.vehicle.PRESETS``, default the camera-only 1:10 car) gives every
        vehicle number; the other FEARGUARD_* keys override it, and the sensors are what the config wires
        (HAVE_TFMINI, HAVE_ODOM), whatever the preset carries. ``FEARGUARD_TRACK``: a profile from ``fearguard learn``
        on this car's tubs (docs/learning.md): the familiarity cue, and the light and lane as this track has them.
        """
        base = _cfg_preset(getattr(cfg, "FEARGUARD_PRESET", None))
        has_tfmini, has_odom = bool(getattr(cfg, "HAVE_TFMINI", False)), bool(getattr(cfg, "HAVE_ODOM", False))
        if getattr(cfg, "USE_LIDAR", False):
            logger.warning("fearguard: USE_LIDAR is not read (the RPLidar part's output is not a range ahead); wire a TFMini")
        ranges = {"ultrasonic_min_range_m": TFMINI_MIN_RANGE_M, "ultrasonic_max_range_m": TFMINI_MAX_RANGE_M} if has_tfmini else {}
        vehicle = replace(
            base,
            max_speed_mps=_cfg_number(cfg, "FEARGUARD_MAX_SPEED_MPS", base.max_speed_mps, "the speed at full throttle, m/s"),
            max_steering_deg=_cfg_number(cfg, "FEARGUARD_MAX_STEERING_DEG", base.max_steering_deg, "the wheel angle at angle ±1, deg"),
            max_decel_mps2=_cfg_number(cfg, "FEARGUARD_DECEL_MPS2", base.max_decel_mps2, "the braking at throttle 0 or below, m/s²"),
            has_ultrasonic=has_tfmini,
            has_qr_localisation=False,  # Donkey Car has no QR localisation part
            **ranges,
        )
        if not hasattr(cfg, "FEARGUARD_MAX_SPEED_MPS"):
            logger.warning(
                "fearguard: FEARGUARD_MAX_SPEED_MPS not set, assuming %.1f m/s at full throttle (%s); measure it (docs/donkey.md)",
                vehicle.max_speed_mps, f"preset {cfg.FEARGUARD_PRESET}" if getattr(cfg, "FEARGUARD_PRESET", None) else "default",
            )
        width = int(_cfg_number(cfg, "IMAGE_W", 160, "pixels"))
        height = int(_cfg_number(cfg, "IMAGE_H", 120, "pixels"))
        return cls(
            vehicle=vehicle,
            rules=getattr(cfg, "FEARGUARD_RULES", None),
            camera=_cfg_camera(getattr(cfg, "FEARGUARD_CAMERA", None), width, height),
            has_tfmini=has_tfmini,
            has_odom=has_odom,
            speed_lag_s=_cfg_number(cfg, "FEARGUARD_SPEED_LAG_S", SPEED_LAG_S, "the throttle-to-speed time constant, s"),
            channels=channels,
            clock=clock,
            track=getattr(cfg, "FEARGUARD_TRACK", None),
        )

    # -- the Donkey part protocol --------------------------------------------------------------
    def run(self, image: object, angle: object, throttle: object, *sensors: object) -> tuple[float, float, float, str, float]:
        """One loop: guarded (angle, throttle) in Donkey units, then fear/value, fear/mode, fear/limit_mps."""
        try:
            return self._run(image, angle, throttle, sensors)
        except Exception as exc:  # a Donkey loop ends on an exception in a part: hold the car still instead
            logger.error("fearguard part failed: %s: %s", type(exc).__name__, exc)
            return 0.0, 0.0, 1.0, FAULT, 0.0

    def shutdown(self) -> None:
        """Nothing to release (Donkey calls it when the vehicle stops)."""

    def reset(self) -> None:
        """Forget all history (a new drive): the guard, the speed estimate, the start-up wait."""
        self.guard.reset()
        self._reset_state()

    def _run(self, image: object, angle: object, throttle: object, sensors: tuple[object, ...]) -> tuple[float, float, float, str, float]:
        t = float(self.clock())
        if self._last_t_s is not None and t <= self._last_t_s:
            t = self._last_t_s + 1e-6  # a coarse clock may repeat a reading; time must increase for the guard
        dt = 0.0 if self._last_t_s is None else t - self._last_t_s
        self._last_t_s = t
        frame = _bgr(image)
        a, u = finite_reading(angle), finite_reading(throttle)
        range_cm = finite_reading(sensors[0]) if self.has_tfmini and sensors else None
        limits = self.vehicle
        if not self._started:
            self._started = frame is not None and (not self.has_tfmini or (range_cm is not None and range_cm > 0))
            if not self._started:
                held = 0.0 if a is None else max(-1.0, min(1.0, a))
                return held, 0.0, 1.0, STARTING, 0.0
        pilot_deg = donkey_to_deg(a, limits.max_steering_deg) if a is not None else math.nan
        range_m = range_cm / 100.0 if range_cm is not None and range_cm > 0 else None  # 0: no echo (unknown)
        if self.has_odom:
            speed = finite_reading(sensors[-1]) if sensors else None
            speed_mps = speed if speed is not None else math.nan  # unknown: the guard assumes the worst
        else:
            speed_mps = self._speed_mps
        cmd = self.guard.step(Observation(t_s=t, speed_mps=speed_mps, frame=frame, ultrasonic_range_m=range_m, steering_deg=pilot_deg))
        self.last_command = cmd
        self._watch_eyes(cmd)
        limit = finite_reading(cmd.speed_limit_mps)
        limit = 0.0 if limit is None else max(0.0, limit)
        if u is None:
            out_throttle = 0.0
        else:
            out_throttle = u if u < 0 else min(u, limit / limits.max_speed_mps)
        self._speed_mps = estimated_speed_mps(
            self._speed_mps, out_throttle, dt, full_throttle_mps=limits.max_speed_mps, lag_s=self.speed_lag_s,
            decel_mps2=limits.max_decel_mps2,
        )
        steering = finite_reading(cmd.steering_deg)
        out_angle = deg_to_donkey(steering, limits.max_steering_deg) if steering is not None else 0.0
        fear = finite_reading(cmd.fear)
        return out_angle, out_throttle, 1.0 if fear is None else fear, cmd.mode.name, limit

    def _watch_eyes(self, cmd: Command) -> None:
        """Over the first EYES_LOOPS supervised loops, count how much of the lane the camera saw; then, once, a warning
        naming what would help if it hardly saw it (replay/eyes.py: a car that stands because its camera finds no lane
        on a track it cannot read says so, and how to teach it the track)."""
        if self._eyes is None:
            return
        self._eyes.add(cmd)
        if self._eyes.supervised >= EYES_LOOPS:
            advice = self._eyes.finish().advice
            if advice:
                logger.warning("fearguard: %s", advice)
            self._eyes = None


def _cfg_number(cfg: Any, key: str, default: float, meaning: str) -> float:
    """A positive finite number from the config, or the default; anything else names the key."""
    value = getattr(cfg, key, default)
    number = finite_reading(value)
    if number is None or number <= 0:
        raise ValueError(f"Donkey config {key} = {value!r}: expected a number > 0 ({meaning})")
    return number


def _cfg_preset(value: object) -> VehicleLimits:
    """FEARGUARD_PRESET: None (the camera-only default) or a preset name from fearguard.vehicle.PRESETS."""
    if value is None:
        return VehicleLimits()
    if not isinstance(value, str) or value not in PRESETS:
        raise ValueError(f"Donkey config FEARGUARD_PRESET = {value!r}: expected one of {', '.join(PRESETS)}")
    return PRESETS[value]


def _cfg_camera(value: object, width: int, height: int) -> CameraModel | None:
    """FEARGUARD_CAMERA: None (uncalibrated), a preset name (fearguard.camera.CAMERA_PRESETS) or a camera.toml path."""
    if value is None:
        return None
    if not isinstance(value, str | Path):
        raise ValueError(f"Donkey config FEARGUARD_CAMERA = {value!r}: expected a preset name or a camera.toml path")
    path = Path(value)
    camera = load_camera(path) if path.suffix == ".toml" else camera_preset(str(value))
    return camera.scaled_to(width, height)
