"""FearGuardPart without donkeycar: units and signs, config keys, start-up, outputs safe to record.

The part in the real donkeycar loop: test_donkey_loop.py (run by .ci/donkey.sh).
"""

from __future__ import annotations

import math
from types import SimpleNamespace

import numpy as np
import pytest
from hypothesis import given
from hypothesis import strategies as st

from fearguard.integrations.donkey import (
    EYES_LOOPS,
    FEAR_OUTPUTS,
    STARTING,
    FearGuardPart,
    _bgr,
    deg_to_donkey,
    donkey_to_deg,
    estimated_speed_mps,
)


class Clock:
    def __init__(self, period_s: float = 0.05) -> None:
        self.t, self.period_s = 100.0, period_s

    def __call__(self) -> float:
        self.t += self.period_s
        return self.t


def part(clock=None, **cfg) -> FearGuardPart:
    return FearGuardPart.from_cfg(SimpleNamespace(IMAGE_W=160, IMAGE_H=120, **cfg), clock=clock or Clock())


def grey_frame(value: int = 110) -> np.ndarray:
    return np.full((120, 160, 3), value, np.uint8)


def test_donkey_minus_one_is_full_left_which_is_positive_degrees():
    assert donkey_to_deg(-1.0, 30.0) == 30.0
    assert donkey_to_deg(0.5, 30.0) == -15.0
    assert deg_to_donkey(30.0, 30.0) == -1.0
    assert deg_to_donkey(-45.0, 30.0) == 1.0  # clipped to Donkey's range
    for a in (-1.0, -0.3, 0.0, 0.7, 1.0):
        assert deg_to_donkey(donkey_to_deg(a, 25.0), 25.0) == pytest.approx(a)


def test_rgb_frames_reach_fearguard_as_bgr_in_a_new_array():
    rgb = np.zeros((120, 160, 3), np.uint8)
    rgb[..., 0] = 200  # red in RGB
    bgr = _bgr(rgb)
    assert bgr is not None and bgr is not rgb
    assert (bgr[..., 2] == 200).all() and (bgr[..., 0] == 0).all()
    assert _bgr(np.zeros((120, 160), np.uint8)).shape == (120, 160, 3)  # IMAGE_DEPTH = 1
    assert _bgr(None) is None and _bgr(np.zeros((120, 160, 3))) is None  # float images are not camera frames


def test_config_keys_wire_the_sensors_and_the_limits():
    p = part(HAVE_TFMINI=True, HAVE_ODOM=True, FEARGUARD_MAX_SPEED_MPS=3.5, FEARGUARD_MAX_STEERING_DEG=25,
             FEARGUARD_DECEL_MPS2=1.5)
    assert p.inputs == ["cam/image_array", "pilot/angle", "pilot/throttle", "lidar/dist", "enc/speed"]
    assert p.outputs == ["pilot/angle", "pilot/throttle", *FEAR_OUTPUTS]
    assert len(p.types) == len(p.outputs)
    v = p.vehicle
    assert (v.max_speed_mps, v.max_steering_deg, v.max_decel_mps2) == (3.5, 25.0, 1.5)
    assert v.has_ultrasonic and not v.has_qr_localisation
    stock = part()
    assert stock.inputs == ["cam/image_array", "pilot/angle", "pilot/throttle"]
    assert not stock.vehicle.has_ultrasonic, "a stock car has no range sensor: the range cue must not stop it"


def test_a_preset_gives_the_vehicle_numbers_and_the_other_keys_override_it():
    from fearguard.vehicle import PRESETS

    p = part(FEARGUARD_PRESET="hc_sr04_pi", FEARGUARD_MAX_SPEED_MPS=1.4)
    preset = PRESETS["hc_sr04_pi"]
    v = p.vehicle
    assert v.max_speed_mps == 1.4  # the key overrides the preset
    assert (v.max_decel_mps2, v.reaction_time_s, v.stop_margin_m) == (preset.max_decel_mps2, preset.reaction_time_s,
                                                                      preset.stop_margin_m)
    assert not v.has_ultrasonic, "the sensors are what the config wires (no HAVE_TFMINI), not what the preset carries"
    assert part(FEARGUARD_PRESET="duckiebot", HAVE_TFMINI=True).vehicle.ultrasonic_max_range_m == 12.0  # the TFMini's
    with pytest.raises(ValueError, match=r"FEARGUARD_PRESET.*road_car"):
        part(FEARGUARD_PRESET="roadcar")


def test_every_drive_mode_placement_rewrites_steering_and_throttle():
    p = FearGuardPart.from_cfg(SimpleNamespace(), channels=("steering", "throttle"))
    assert p.inputs[1:3] == ["steering", "throttle"] and p.outputs[:2] == ["steering", "throttle"]


@pytest.mark.parametrize(
    ("key", "value"), [("FEARGUARD_MAX_SPEED_MPS", "fast"), ("FEARGUARD_DECEL_MPS2", 0), ("FEARGUARD_MAX_STEERING_DEG", math.inf)]
)
def test_a_bad_config_value_names_its_key(key, value):
    with pytest.raises(ValueError, match=key):
        part(**{key: value})


def test_camera_presets_and_files_are_read_from_the_config(tmp_path):
    from fearguard.camera import save_camera

    p = part(FEARGUARD_CAMERA="picam-v2-320x240")
    assert (p.guard.camera.width_px, p.guard.camera.height_px) == (160, 120)  # scaled to IMAGE_W × IMAGE_H
    save_camera(p.guard.camera, tmp_path / "camera.toml")
    assert part(FEARGUARD_CAMERA=str(tmp_path / "camera.toml")).guard.camera == p.guard.camera
    with pytest.raises(ValueError, match="picam-v2-160x120"):
        part(FEARGUARD_CAMERA="picam-v9")


def test_the_car_is_held_still_until_the_camera_and_the_tfmini_have_delivered():
    p = part(HAVE_TFMINI=True)
    assert p.run(None, 0.2, 0.5, 0) == (0.2, 0.0, 1.0, STARTING, 0.0)
    assert p.run(grey_frame(), 0.2, 0.5, 0)[3] == STARTING  # a frame, but no echo yet
    assert p.run(grey_frame(), 0.2, 0.5, 250)[3] != STARTING
    assert p.last_command is not None


def test_after_start_a_lost_frame_or_echo_is_the_worst_case_not_a_wait():
    p = part(HAVE_TFMINI=True)
    p.run(grey_frame(), 0.0, 0.5, 300)
    for _ in range(5):
        out = p.run(None, 0.0, 0.5, 0)
    assert out[3] == "EMERGENCY" and out[1] == 0.0


def test_throttle_is_capped_by_the_limit_and_reverse_passes():
    p = part()
    p.run(grey_frame(), 0.0, 1.0)
    _, throttle, _, _, limit = p.run(grey_frame(), 0.0, 1.0)
    assert throttle == pytest.approx(limit / p.vehicle.max_speed_mps)
    assert p.run(grey_frame(), 0.0, -0.4)[1] == -0.4  # brake / reverse: never raised, never cut


def test_a_repeating_clock_does_not_fault_the_guard():
    p = part(clock=lambda: 5.0)
    p.run(grey_frame(), 0.0, 0.3)
    out = p.run(grey_frame(), 0.0, 0.3)
    assert not any("time did not increase" in r for r in p.last_command.reasons), out


garbage = st.one_of(
    st.none(), st.floats(allow_nan=True, allow_infinity=True), st.integers(-10, 10), st.text(max_size=3), st.booleans()
)


@given(angle=garbage, throttle=garbage, dist=garbage, speed=garbage, frame=st.sampled_from([None, "frame", "img", "bad"]))
def test_every_output_is_a_finite_float_or_a_string_whatever_comes_in(angle, throttle, dist, speed, frame):
    p = part(HAVE_TFMINI=True, HAVE_ODOM=True)
    image = {"frame": grey_frame(), "img": np.zeros((120, 160), np.uint8), "bad": np.zeros((2, 2, 7))}.get(frame)
    for _ in range(3):
        out = p.run(image, angle, throttle, dist, speed)
        assert len(out) == len(p.outputs)
        a, u, fear, mode, limit = out
        assert all(isinstance(x, float) and math.isfinite(x) for x in (a, u, fear, limit)), out
        assert isinstance(mode, str) and -1.0 <= a <= 1.0 and 0.0 <= fear <= 1.0 and limit >= 0.0
        pilot_u = throttle if isinstance(throttle, float | int) and not isinstance(throttle, bool) else None
        if pilot_u is not None and math.isfinite(pilot_u) and pilot_u >= 0:
            assert u <= pilot_u


@given(
    v=st.floats(0, 5), u=st.floats(-1, 1), dt=st.floats(0, 0.5), lag=st.floats(0.01, 2), decel=st.floats(0.1, 5)
)
def test_the_speed_estimate_moves_toward_the_throttle_speed_and_falls_no_faster_than_the_braking(v, u, dt, lag, decel):
    full = 2.0
    new = estimated_speed_mps(v, u, dt, full_throttle_mps=full, lag_s=lag, decel_mps2=decel)
    target = max(0.0, u) * full
    assert new >= v - decel * dt - 1e-9 and new >= 0.0
    assert new <= max(v, target) + 1e-9


def test_the_speed_estimate_reaches_63_percent_after_one_time_constant():
    v = estimated_speed_mps(0.0, 1.0, 0.5, full_throttle_mps=2.0, lag_s=0.5, decel_mps2=3.0)
    assert v == pytest.approx(2.0 * (1 - math.exp(-1)))


def test_a_failing_part_holds_the_car_still_instead_of_ending_the_loop():
    p = part()
    p.guard = None  # type: ignore[assignment]  # any internal failure
    assert p.run(grey_frame(), 0.3, 0.8) == (0.0, 0.0, 1.0, "FAULT", 0.0)


TUB_IMAGES = "modelcar/donkey-carpet-dark/images"  # black tape on dark carpet, the tub's 160x120 RGB frames


def _tub_frames(shared_data, start: int, count: int) -> list[np.ndarray]:
    """The tub's camera frames from record ``start`` on, as a Donkey camera delivers them (RGB)."""
    import cv2

    folder = shared_data / TUB_IMAGES
    return [cv2.cvtColor(cv2.imread(str(folder / f"{i}_cam_image_array_.jpg")), cv2.COLOR_BGR2RGB)
            for i in range(start, start + count)]


def _drive(p: FearGuardPart, frames: list[np.ndarray]) -> None:
    for frame in frames:
        p.run(frame, 0.0, 0.4)


def test_a_car_whose_camera_hardly_sees_the_lane_says_once_what_would_help(shared_data, caplog):
    """replay/eyes.py in the part: the tub's own frames, no FEARGUARD_TRACK and no FEARGUARD_CAMERA — the car stands in
    EMERGENCY, and after EYES_LOOPS loops one warning names the Donkey config keys that would let it drive."""
    frames = _tub_frames(shared_data, 1300, EYES_LOOPS)
    p = part(FEARGUARD_PRESET="donkey", FEARGUARD_MAX_SPEED_MPS=2.0)
    with caplog.at_level("WARNING", logger="fearguard.integrations.donkey"):
        _drive(p, frames[:-1])
        assert not [r for r in caplog.records if "lane was seen" in r.getMessage()]  # not before the window has passed
        _drive(p, frames[-1:] + frames[:50])  # the window ends, then more loops
    said = [r.getMessage() for r in caplog.records if "lane was seen" in r.getMessage()]
    assert len(said) == 1, said
    assert "FEARGUARD_TRACK" in said[0] and "FEARGUARD_CAMERA" in said[0] and "fearguard learn" in said[0]
    assert "--track" not in said[0] and "--camera" not in said[0]  # the config's words, not the command line's


def test_with_a_learnt_track_or_a_readable_road_the_part_stays_quiet(shared_data, tmp_path, caplog):
    from fearguard.track.learn import LearnOptions, learn_track
    from fearguard.track.profile import save_track

    track = save_track(learn_track([shared_data / "modelcar/donkey-carpet-dark"], LearnOptions(stop="1200f", every=2)).profile,
                       tmp_path / "track.npz")
    with caplog.at_level("WARNING", logger="fearguard.integrations.donkey"):
        _drive(part(FEARGUARD_PRESET="donkey", FEARGUARD_MAX_SPEED_MPS=2.0, FEARGUARD_TRACK=str(track)),
               _tub_frames(shared_data, 1300, EYES_LOOPS + 10))
        _drive(part(FEARGUARD_MAX_SPEED_MPS=2.0), _video_frames(shared_data / "road/video/solidWhiteRight.mp4", EYES_LOOPS + 10))
    assert not [r for r in caplog.records if "lane was seen" in r.getMessage()]


def _video_frames(path, count: int) -> list[np.ndarray]:
    """A dash-cam video's frames at Donkey's 160x120, RGB (the lane model reads this road)."""
    import cv2

    cap, out = cv2.VideoCapture(str(path)), []
    while len(out) < count:
        ok, bgr = cap.read()
        if not ok:
            cap.set(cv2.CAP_PROP_POS_FRAMES, 0)  # loop the short clip
            continue
        out.append(cv2.cvtColor(cv2.resize(bgr, (160, 120), interpolation=cv2.INTER_AREA), cv2.COLOR_BGR2RGB))
    cap.release()
    return out
