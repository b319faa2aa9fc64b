"""FearGuardPart inside a real donkeycar ``Vehicle`` loop (donkeycar 5.3.0: Python 3.11, numpy < 2).

Run by ``.ci/donkey.sh`` in its own environment; skipped where donkeycar is not installed. Frames come
from a real video through a threaded camera part (donkeycar's ``BaseCamera``), the config is donkeycar's
own ``cfg_complete.py``, the part sits after ``DriveMode`` on ``steering``/``throttle`` (every drive mode
guarded) and donkeycar's ``TubWriter`` records every output (it raises on a non-finite float).

The loop rate (the issue's ≥ 18 Hz) is the machine's as much as the part's, so it is measured three ways and
printed: the Vehicle loop's rate (loops / seconds), the part's wall time per call (donkeycar's own part
profiler) and the part's CPU time per call (``time.thread_time`` around ``run``: what the part costs,
whatever else the machine runs). It fails only on a clear miss: the part's CPU time over its share of
the 18 Hz period, or the loop under 18 Hz on a machine that is not overloaded (load average per core < 1).
"""

from __future__ import annotations

import json
import math
import os
import statistics
import threading
import time
import warnings
from pathlib import Path

import cv2
import numpy as np
import pytest

donkeycar = pytest.importorskip("donkeycar", reason="donkeycar 5.3.0 is installed by .ci/donkey.sh (Python 3.11, numpy < 2)")

from donkeycar.config import Config  # noqa: E402
from donkeycar.parts.camera import BaseCamera  # noqa: E402
from donkeycar.parts.tub_v2 import Tub, TubWriter  # noqa: E402
from donkeycar.templates.complete import DriveMode  # noqa: E402
from donkeycar.vehicle import Vehicle  # noqa: E402

from fearguard.integrations.donkey import EYES_LOOPS, FearGuardPart  # noqa: E402
from fearguard.replay.run import ReplayOptions, replay  # noqa: E402

VIDEO = "road/video/solidWhiteRight.mp4"
PILOT_THROTTLE = 0.5  # [-] the easy drive's autopilot throttle
LOOP_CAP = 400  # [loops] safety cap; the drive ends when the video does (221 frames at 20 fps)
MIN_LOOP_HZ = 18.0  # [Hz] the criterion for a 20 Hz DRIVE_LOOP_HZ
PART_CPU_SHARE = 0.5  # [-] of the 18 Hz period the part's CPU time may take (the camera, pilot, tub share the rest)
USER_ANGLE, USER_THROTTLE = 0.05, 0.0  # [Donkey units] a joystick at rest, recorded beside the pilot's commands


def stock_config() -> Config:
    cfg = Config()
    cfg.from_pyfile(str(Path(donkeycar.__file__).parent / "templates" / "cfg_complete.py"))
    return cfg


class VideoCamera(BaseCamera):
    """A threaded camera part playing a video at the camera frame rate: RGB at IMAGE_W × IMAGE_H, like a Pi camera."""

    def __init__(self, path: Path, width: int, height: int, fps: float) -> None:
        self.path, self.size, self.period_s = path, (width, height), 1.0 / fps
        self.frame = None
        self.frames = 0
        self.finished = threading.Event()
        self.on = True

    def update(self) -> None:
        cap = cv2.VideoCapture(str(self.path))
        next_t = time.monotonic()
        while self.on:
            ok, bgr = cap.read()
            if not ok:
                break
            small = cv2.resize(bgr, self.size, interpolation=cv2.INTER_AREA)
            self.frame = cv2.cvtColor(small, cv2.COLOR_BGR2RGB)
            self.frames += 1
            next_t += self.period_s
            time.sleep(max(0.0, next_t - time.monotonic()))
        cap.release()
        self.finished.set()

    def shutdown(self) -> None:
        self.on = False


class Pilot:
    """An autopilot: a gentle weave and a steady throttle (Donkey units)."""

    def __init__(self, throttle: float) -> None:
        self.throttle, self.n = throttle, 0

    def run(self, image: object) -> tuple[float | None, float | None]:
        if image is None:
            return None, None
        self.n += 1
        return 0.1 * math.sin(self.n / 20.0), self.throttle


class EndOfVideo:
    """Stops the vehicle loop when the camera has played the whole video."""

    def __init__(self, vehicle: Vehicle, camera: VideoCamera) -> None:
        self.vehicle, self.camera = vehicle, camera

    def run(self) -> None:
        if self.camera.finished.is_set():
            self.vehicle.on = False


class Recorder:
    """Keeps every loop's channels for the assertions."""

    def __init__(self) -> None:
        self.rows: list[tuple] = []

    def run(self, *values: object) -> None:
        self.rows.append(values)


class ToyCar:
    """The car's longitudinal motion from the throttle sent: a first-order lag of 0.3 s, braking at most 2.5 m/s²."""

    LAG_S, DECEL_MPS2 = 0.3, 2.5

    def __init__(self, full_throttle_mps: float) -> None:
        self.full, self.x_m, self.v_mps, self.last_t = full_throttle_mps, 0.0, 0.0, None
        self.lock = threading.Lock()

    def run(self, throttle: object) -> tuple[float, float]:
        now = time.monotonic()
        dt = 0.0 if self.last_t is None else now - self.last_t
        self.last_t = now
        u = float(throttle) if isinstance(throttle, float | int) else 0.0
        target = max(0.0, u) * self.full
        v = self.v_mps + (1 - math.exp(-dt / self.LAG_S)) * (target - self.v_mps)
        with self.lock:
            self.x_m += 0.5 * (self.v_mps + max(v, self.v_mps - self.DECEL_MPS2 * dt)) * dt
            self.v_mps = max(v, self.v_mps - self.DECEL_MPS2 * dt, 0.0)
        return self.x_m, self.v_mps


class FakeTFMini:
    """A threaded TFMini-like part: distance to a box in cm at 100 Hz, 0 before the first echo (as donkeycar's TFMini)."""

    def __init__(self, car: ToyCar, box_x_m: float, first_echo_s: float = 0.2) -> None:
        self.car, self.box_x_m, self.first_echo_s = car, box_x_m, first_echo_s
        self.dist, self.on = 0, True

    def update(self) -> None:
        start = time.monotonic()
        while self.on:
            if time.monotonic() - start >= self.first_echo_s:
                with self.car.lock:
                    self.dist = round(max(0.0, self.box_x_m - self.car.x_m) * 100)
            time.sleep(0.01)

    def run_threaded(self) -> int:
        return self.dist

    def shutdown(self) -> None:
        self.on = False


class Timed:
    """The part as it is, with its CPU time per call measured (thread CPU: not stretched by other processes)."""

    def __init__(self, part: FearGuardPart) -> None:
        self.part, self.cpu_s = part, []

    def run(self, *inputs: object) -> tuple:
        start = time.thread_time()
        out = self.part.run(*inputs)
        self.cpu_s.append(time.thread_time() - start)
        return out


def drive(data_dir: Path, tmp_path: Path, cfg: Config, tfmini: FakeTFMini | None = None, car: ToyCar | None = None) -> dict:
    """The stock wiring: camera → pilot → DriveMode → FearGuardPart on steering/throttle → tub; what it measured."""
    vehicle = Vehicle()
    camera = VideoCamera(data_dir / VIDEO, cfg.IMAGE_W, cfg.IMAGE_H, cfg.CAMERA_FRAMERATE)
    vehicle.add(camera, outputs=["cam/image_array"], threaded=True)
    vehicle.add(EndOfVideo(vehicle, camera))
    if tfmini is not None:
        vehicle.add(tfmini, outputs=["lidar/dist"], threaded=True)
    vehicle.add(Pilot(PILOT_THROTTLE), inputs=["cam/image_array"], outputs=["pilot/angle", "pilot/throttle"])
    vehicle.add(
        DriveMode(cfg.AI_THROTTLE_MULT),
        inputs=["user/mode", "user/angle", "user/throttle", "pilot/angle", "pilot/throttle"],
        outputs=["steering", "throttle"],
    )
    part = FearGuardPart.from_cfg(cfg, channels=("steering", "throttle"))
    timed = Timed(part)
    vehicle.add(timed, inputs=part.inputs, outputs=part.outputs)
    if car is not None:
        vehicle.add(car, inputs=["throttle"], outputs=["car/x_m", "car/v_mps"])
    channels = ["cam/image_array", "user/angle", "user/throttle", "user/mode", "pilot/angle", "pilot/throttle", *part.outputs]
    types = ["image_array", "float", "float", "str", "float", "float", *part.types]
    tub = TubWriter(str(tmp_path / "tub"), inputs=channels, types=types)
    vehicle.add(tub, inputs=channels, outputs=["tub/num_records"], run_condition="recording")
    recorder = Recorder()
    extra = ["car/x_m", "car/v_mps"] if car is not None else []
    vehicle.add(recorder, inputs=["pilot/angle", "pilot/throttle", *part.outputs, *extra])
    vehicle.mem.put(["user/mode", "recording", "user/angle", "user/throttle"], ["local", True, USER_ANGLE, USER_THROTTLE])
    result = vehicle.start(rate_hz=cfg.DRIVE_LOOP_HZ, max_loop_count=LOOP_CAP)
    assert result is not None, "the vehicle loop ended on an exception (see the traceback above)"
    loops, seconds = result
    wall_s = vehicle.profiler.records[timed]["times"][1:-1]
    return {
        "rows": recorder.rows, "loops": loops, "seconds": seconds, "hz": loops / seconds, "recorded": len(tub.tub),
        "wall_ms": 1e3 * float(np.mean(wall_s)), "wall_p95_ms": 1e3 * float(np.percentile(wall_s, 95)),
        "cpu_ms": 1e3 * statistics.median(timed.cpu_s[1:]), "tub": tmp_path / "tub",
    }


@pytest.fixture(scope="module")
def easy_drive(shared_data, tmp_path_factory) -> dict:
    return drive(shared_data, tmp_path_factory.mktemp("easy"), stock_config())


@pytest.fixture
def cfg() -> Config:
    return stock_config()


def test_easy_drive_runs_to_the_end_of_the_video_with_throttle_passed_through(easy_drive):
    d, cfg = easy_drive, stock_config()
    rows = d["rows"]
    modes = [r[5] for r in rows]
    emergency = modes.count("EMERGENCY") / len(rows)
    pilot_throttle = sum(r[1] for r in rows if r[1] is not None)
    guarded_throttle = sum(r[3] for r in rows)
    print(
        f"\ndonkey loop: {d['loops']} loops in {d['seconds']:.1f} s = {d['hz']:.1f} Hz (target {cfg.DRIVE_LOOP_HZ}); "
        f"FearGuardPart {d['wall_ms']:.1f} ms per call (wall, mean; p95 {d['wall_p95_ms']:.1f} ms), "
        f"{d['cpu_ms']:.1f} ms CPU (median); EMERGENCY {100 * emergency:.1f} % of loops; "
        f"throttle {100 * guarded_throttle / pilot_throttle:.1f} % of the pilot's; modes "
        f"{ {m: modes.count(m) for m in sorted(set(modes))} }; {d['recorded']} tub records; "
        f"load average {os.getloadavg()[0]:.1f} on {os.cpu_count()} cores"
    )
    assert d["loops"] < LOOP_CAP, "the drive ended by the loop cap, not at the end of the video"
    assert d["recorded"] == d["loops"], "TubWriter recorded every loop (no non-finite value ended it)"
    for row in rows:
        angle, throttle, fear, mode, limit = row[2:7]
        assert all(isinstance(v, float) and math.isfinite(v) for v in (angle, throttle, fear, limit)), row
        assert isinstance(mode, str)
    assert emergency <= 0.05
    assert guarded_throttle >= 0.85 * pilot_throttle


def test_the_loop_keeps_18_hz_unless_the_machine_is_overloaded(easy_drive):
    d = easy_drive
    period_ms = 1e3 / MIN_LOOP_HZ
    assert d["cpu_ms"] <= PART_CPU_SHARE * period_ms, (
        f"the part costs {d['cpu_ms']:.1f} ms CPU per call, over {PART_CPU_SHARE:.0%} of the {period_ms:.1f} ms period")
    if d["hz"] < MIN_LOOP_HZ:
        load_per_core = os.getloadavg()[0] / (os.cpu_count() or 1)
        assert load_per_core >= 1.0, f"{d['hz']:.1f} Hz < {MIN_LOOP_HZ} Hz on a machine with load {load_per_core:.2f} per core"
        warnings.warn(f"loop {d['hz']:.1f} Hz < {MIN_LOOP_HZ} Hz with load {load_per_core:.2f} per core: the machine's, "
                      f"not the part's ({d['cpu_ms']:.1f} ms CPU per call)", stacklevel=1)


def test_replay_of_the_tub_logs_the_pilot_and_user_commands_in_donkey_units(easy_drive, tmp_path):
    """The tub donkeycar's own TubWriter wrote, replayed by fearguard: every recorded command, labelled, in Donkey units."""
    tub = Tub(str(easy_drive["tub"]), read_only=True)
    records = list(tub)
    recorded = {int(r["_index"]): r for r in records if "cam/image_array" in r}  # the loops before the first frame have none
    result = replay(easy_drive["tub"], tmp_path / "out", ReplayOptions(plots=False))
    lines = [json.loads(line) for line in (tmp_path / "out" / "log.jsonl").read_text().splitlines()]
    assert len(records) == easy_drive["recorded"] and len(lines) == len(recorded) >= len(records) - 5
    for line in lines:
        record = recorded[line["frame"]]
        assert line["pilot_angle_donkey"] == pytest.approx(record["pilot/angle"])
        assert line["pilot_throttle_donkey"] == pytest.approx(record["pilot/throttle"])
        assert (line["user_angle_donkey"], line["user_throttle_donkey"]) == (USER_ANGLE, USER_THROTTLE)
        assert line["user_mode_donkey"] == "local"
        assert "recorded_angle" not in line and isinstance(line["steering_deg"], float)  # fearguard's degrees, apart
    units = result.summary["log_field_units"]
    assert set(units) == {"user_angle_donkey", "user_throttle_donkey", "pilot_angle_donkey", "pilot_throttle_donkey",
                          "user_mode_donkey"}
    assert "-1 = full left, + = right" in units["pilot_angle_donkey"] and "+ = left" in units["pilot_angle_donkey"]


def test_tfmini_box_ahead_the_car_stops_before_it(shared_data, tmp_path, cfg):
    cfg.HAVE_TFMINI = True
    cfg.FEARGUARD_MAX_SPEED_MPS = 2.0
    cfg.FEARGUARD_DECEL_MPS2 = 2.0  # configured below the car's real 2.5 m/s² (docs/donkey.md: measure, then round down)
    car = ToyCar(cfg.FEARGUARD_MAX_SPEED_MPS)
    box_x_m = 4.0
    d = drive(shared_data, tmp_path, cfg, FakeTFMini(car, box_x_m), car)
    rows = d["rows"]
    x_end, v_end = rows[-1][-2], rows[-1][-1]
    top = max(r[-1] for r in rows)
    print(
        f"\ntfmini box at {box_x_m} m: stopped at {x_end:.2f} m ({box_x_m - x_end:.2f} m before it), "
        f"top speed {top:.2f} m/s, {d['hz']:.1f} Hz, {d['wall_ms']:.1f} ms per call ({d['cpu_ms']:.1f} ms CPU)"
    )
    assert top > 0.5, "the car drove toward the box"
    assert x_end < box_x_m - 0.05, "the car stopped before the box"
    assert v_end < 0.05


TUB = "modelcar/donkey-carpet-dark"  # a real Donkey tub v2 (dark carpet, tape edges), 2526 records at 20 Hz


class TubCamera(BaseCamera):
    """A threaded camera part playing a tub's images from record ``start`` at 20 Hz (RGB, as a Pi camera gives), and
    the driver's recorded angle and throttle with each frame (what the pilot would have said)."""

    def __init__(self, tub_path: Path, start: int, fps: float = 20.0, count: int | None = None) -> None:
        tub = Tub(str(tub_path), read_only=True)
        self.records = [r for r in tub if int(r["_index"]) >= start and "cam/image_array" in r][:count]
        self.images = tub_path / "images"
        self.period_s = 1.0 / fps
        self.frame, self.commands = None, (None, None)
        self.finished = threading.Event()
        self.on = True

    def update(self) -> None:
        next_t = time.monotonic()
        for r in self.records:
            if not self.on:
                break
            bgr = cv2.imread(str(self.images / r["cam/image_array"]))
            if bgr is not None:
                self.frame = cv2.cvtColor(bgr, cv2.COLOR_BGR2RGB)
                self.commands = (float(r["user/angle"]), float(r["user/throttle"]))
            next_t += self.period_s
            time.sleep(max(0.0, next_t - time.monotonic()))
        self.finished.set()

    def run_threaded(self) -> tuple:
        return self.frame, *self.commands

    def shutdown(self) -> None:
        self.on = False


def tub_drive(cfg: Config, tub: Path, start: int, count: int | None = None) -> dict:
    """The stock loop with the tub from record ``start`` (``count`` records, or to its end) as camera and pilot at 20 Hz,
    FearGuardPart after DriveMode: its rows (pilot angle, throttle, part outputs), loops, seconds, CPU per call."""
    vehicle = Vehicle()
    camera = TubCamera(tub, start, count=count)
    vehicle.add(camera, outputs=["cam/image_array", "pilot/angle", "pilot/throttle"], threaded=True)
    vehicle.add(EndOfVideo(vehicle, camera))
    vehicle.add(DriveMode(cfg.AI_THROTTLE_MULT), inputs=["user/mode", "user/angle", "user/throttle", "pilot/angle", "pilot/throttle"],
                outputs=["steering", "throttle"])
    part = FearGuardPart.from_cfg(cfg, channels=("steering", "throttle"))
    timed = Timed(part)
    vehicle.add(timed, inputs=part.inputs, outputs=part.outputs)
    recorder = Recorder()
    vehicle.add(recorder, inputs=["pilot/angle", "pilot/throttle", *part.outputs])
    vehicle.mem.put(["user/mode", "user/angle", "user/throttle"], ["local", 0.0, 0.0])
    result = vehicle.start(rate_hz=cfg.DRIVE_LOOP_HZ, max_loop_count=4 * len(camera.records))
    assert result is not None, "the vehicle loop ended on an exception (see the traceback above)"
    loops, seconds = result
    return {"rows": [r for r in recorder.rows if r[1] is not None], "loops": loops, "seconds": seconds,
            "cpu_ms": 1e3 * statistics.median(timed.cpu_s[1:])}


def test_a_learnt_track_lets_the_car_drive_its_own_tub_in_the_real_loop(shared_data, tmp_path, cfg, caplog):
    """Issue 34: `fearguard learn` on the first half of a real tub, FEARGUARD_TRACK in the stock loop replaying the second
    half at 20 Hz as camera and pilot: the loop keeps its rate, the car keeps (nearly) the pilot's throttle."""
    from fearguard.track.learn import LearnOptions, learn_track
    from fearguard.track.profile import save_track

    tub = shared_data / TUB
    half = len(Tub(str(tub), read_only=True)) // 2
    track = save_track(learn_track([tub], LearnOptions(stop=f"{half}f")).profile, tmp_path / "track.npz")
    cfg.FEARGUARD_TRACK = str(track)
    cfg.FEARGUARD_PRESET = "donkey"
    with caplog.at_level("WARNING", logger="fearguard.integrations.donkey"):
        run = tub_drive(cfg, tub, half)
    rows, loops, seconds, cpu_ms = run["rows"], run["loops"], run["seconds"], run["cpu_ms"]
    modes = [r[5] for r in rows]
    emergency = modes.count("EMERGENCY") / len(rows)
    pilot = sum(max(0.0, r[1]) for r in rows)
    guarded = sum(max(0.0, r[3]) for r in rows)
    print(f"\nlearnt track, 2nd half of {TUB}: {loops} loops in {seconds:.1f} s = {loops / seconds:.1f} Hz; EMERGENCY "
          f"{100 * emergency:.1f} % of loops; throttle {100 * guarded / pilot:.1f} % of the pilot's; part {cpu_ms:.1f} ms CPU "
          f"(median); modes { {m: modes.count(m) for m in sorted(set(modes))} }")
    assert emergency <= 0.10
    assert guarded >= 0.85 * pilot
    assert cpu_ms <= PART_CPU_SHARE * 1e3 / MIN_LOOP_HZ
    assert not [r for r in caplog.records if "lane was seen" in r.getMessage()]  # a car with its track needs no advice


def test_without_a_track_the_standing_car_says_once_how_to_teach_it_the_track(shared_data, cfg, caplog):
    """The same tub without FEARGUARD_TRACK: the camera finds no lane on black tape over dark carpet and the car stands;
    after EYES_LOOPS loops the part logs, once, what would help, in the Donkey config's words (replay/eyes.py)."""
    cfg.FEARGUARD_PRESET = "donkey"
    with caplog.at_level("WARNING", logger="fearguard.integrations.donkey"):
        run = tub_drive(cfg, shared_data / TUB, 1300, count=EYES_LOOPS + 40)
    modes = [r[5] for r in run["rows"]]
    said = [r.getMessage() for r in caplog.records if "lane was seen" in r.getMessage()]
    print(f"\nno track, {TUB} from record 1300: {run['loops']} loops, EMERGENCY {100 * modes.count('EMERGENCY') / len(modes):.0f} % "
          f"of loops; said: {said}")
    assert modes.count("EMERGENCY") >= 0.5 * len(modes)
    assert len(said) == 1 and "FEARGUARD_TRACK" in said[0] and "fearguard learn" in said[0]
