"""A camera driver that refills one buffer every frame (cap.read(buf), ring buffers, np.copyto) is seen afresh.

The regression: an identity cache (``frame is last_frame``) gave the first frame's cues forever, so a
camera that went black stayed NORMAL at cruise speed.
"""

from __future__ import annotations

import numpy as np

import fearguard as fg
from fearguard.sim.scenario import load_scenario
from fearguard.sim.suite import BUNDLED
from fearguard.sim.world import World
from fearguard.vision.trackers import CONFIDENCE_MEDIAN_FRAMES

GOOD_FRAMES = 40  # 2 s of a clear straight road at 20 Hz
BLACK_FRAMES = 20


def _drive(reuse_buffer: bool) -> list[fg.Command]:
    """Drive clear_straight on rendered frames, then the camera goes black (dark sensor noise, never frozen)."""
    scenario = load_scenario(BUNDLED / "clear_straight.toml")
    world = World(scenario, seed=1)
    guard = fg.FearGuard(fg.HoughLaneSteering(camera=world.camera, fps=scenario.camera.fps),
                         rules=fg.load_rules(scenario.rules_path), vehicle=scenario.vehicle.limits)
    noise = np.random.default_rng(7)
    buffer: np.ndarray | None = None
    commands = []
    for k in range(GOOD_FRAMES + BLACK_FRAMES):
        sensed = world.sense()
        pixels = sensed.frame_bgr if k < GOOD_FRAMES else noise.integers(0, 6, sensed.frame_bgr.shape, dtype=np.uint8)
        if reuse_buffer:
            buffer = np.empty_like(pixels) if buffer is None else buffer
            np.copyto(buffer, pixels)
            frame = buffer
        else:
            frame = pixels.copy()
        cmd = guard.step(fg.Observation(t_s=sensed.t_s, speed_mps=sensed.speed_mps, frame=frame,
                                        ultrasonic_range_m=sensed.ultrasonic_range_m, odometer_m=sensed.odometer_m))
        commands.append(cmd)
        world.advance(cmd.steering_deg, min(scenario.cruise_speed_mps, cmd.speed_limit_mps))
    return commands


def test_a_camera_going_black_in_a_reused_buffer_enters_emergency_in_time() -> None:
    commands = _drive(reuse_buffer=True)
    assert commands[GOOD_FRAMES - 1].mode is fg.Mode.NORMAL  # the clear road was seen as clear
    allowed = fg.load_rules().policy.enter_frames + CONFIDENCE_MEDIAN_FRAMES - 1  # hysteresis + the confidence median
    modes = [c.mode for c in commands[GOOD_FRAMES:]]
    assert fg.Mode.EMERGENCY in modes[:allowed], f"black camera, modes {[m.name for m in modes]}"
    assert commands[-1].speed_limit_mps == 0.0 and commands[-1].strategy is fg.Strategy.STOP


def test_a_reused_buffer_gives_the_same_commands_as_a_new_array_per_frame() -> None:
    assert _drive(reuse_buffer=True) == _drive(reuse_buffer=False)
