"""While the road picture is not trusted and no EMERGENCY answers it yet (a flicker's grace, the frames the mode
machine counts), the steering of the last calm picture is held: the estimator reads the very picture in doubt.

Found in MetaDrive (development seed 1, a tight left bend at 10 m/s): the lane was lost for 0.3 s, the lane steering's
angle fell from 17 to 3 deg while the bend went on, and the car left its lane before the EMERGENCY (which holds the
calm angle) began."""

from __future__ import annotations

import math

from hypothesis import given
from hypothesis import strategies as st

import fearguard as fg
from fearguard.policy.config import PolicyConfig
from fearguard.policy.decision import doubt_step

CFG = PolicyConfig()
angles = st.floats(-30.0, 30.0)


@given(fear=st.floats(0.0, 1.0), wanted=angles, trusted=angles)
def test_a_picture_in_doubt_holds_the_calm_angle_and_says_so(fear: float, wanted: float, trusted: float) -> None:
    steering, why = doubt_step(fear, wanted, trusted, CFG)
    if fear >= CFG.emergency_enter_fear:
        assert steering == trusted
        assert (why == "") == (wanted == trusted)  # a held angle that differs from the estimator's is explained
        if why:
            assert f"{trusted:+.1f} deg" in why and f"{wanted:+.1f} deg" in why
    else:
        assert (steering, why) == (wanted, "")


def _step(guard: fg.FearGuard, t: float, confidence: float, steering: float) -> fg.Command:
    """Cue level, an obstacle range far beyond the stopping distance: the path is known clear, so a lost picture gets
    the flicker grace before an EMERGENCY."""
    cues = fg.Cues(confidence, 120.0, 0.0, 40.0, 0.0)
    return guard.step(fg.Observation(t_s=t, speed_mps=1.0, cues=cues, steering_deg=steering))


@given(calm=st.floats(-20.0, 20.0), doubtful=st.floats(-20.0, 20.0), lost=st.integers(1, 12))
def test_through_the_grace_and_the_emergency_the_car_never_takes_the_doubtful_angle(calm: float, doubtful: float,
                                                                                    lost: int) -> None:
    guard = fg.FearGuard(lambda frame: 0.0, vehicle=fg.VehicleLimits.preset("model_car"))
    t = 0.0
    for _ in range(30):  # a calm picture: its angle is the one trusted
        cmd = _step(guard, t, 0.95, calm)
        t += 0.1
    assert math.isclose(cmd.steering_deg, calm, abs_tol=1e-9)
    for _ in range(lost):  # the picture lost: the estimator's angle changes, the command's does not
        cmd = _step(guard, t, 0.0, doubtful)
        t += 0.1
        assert math.isclose(cmd.steering_deg, calm, abs_tol=1e-9), cmd.reasons
        if cmd.mode is not fg.Mode.EMERGENCY and not math.isclose(calm, doubtful):
            assert any("holding the steering of the last calm picture" in r for r in cmd.reasons), cmd.reasons


@given(calm=st.floats(-10.0, 10.0), odd=st.floats(-20.0, 20.0), seed_frames=st.integers(3, 10))
def test_one_odd_calm_frame_amid_a_flicker_is_not_what_the_grace_holds(calm: float, odd: float, seed_frames: int) -> None:
    """The held angle is the median of the last calm pictures' (``supervisor.CALM_MEMORY``): found on pale dashed paint
    (benchmarks/scenarios_open/pale_dashes, seed 9), where one calm frame between two doubtful ones steered -7.9 deg on a
    gentle arc and the grace held it until the car left the lane."""
    guard = fg.FearGuard(lambda frame: 0.0, vehicle=fg.VehicleLimits.preset("model_car"))
    t = 0.0
    for _ in range(seed_frames):
        _step(guard, t, 0.95, calm)
        t += 0.1
    _step(guard, t, 0.0, calm)  # a doubtful frame ...
    t += 0.1
    _step(guard, t, 0.95, odd)  # ... one calm frame with an odd angle (steered as it says: it is calm) ...
    t += 0.1
    cmd = _step(guard, t, 0.0, odd)  # ... doubt again: the calm pictures' median is held, not the odd frame's angle
    assert math.isclose(cmd.steering_deg, calm, abs_tol=1e-9), cmd.reasons
