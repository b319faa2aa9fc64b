"""ROS bags in (issue 37): real bags written by rosbags' writers of both generations, read back through fearguard.

Frames equal the images written, byte for byte, wherever the encoding is lossless; sensors are aligned like a sensor
log; a Donkey tub written as a ROS 1 bag and as a ROS 2 MCAP bag, with its own stamps, replays row for row like the tub
up to the tub's first recording pause (a fresh start in a tub, a stall in a bag), the same pictures at the same times
after it.
"""

from __future__ import annotations

import json
import shutil
import subprocess
import sys
from pathlib import Path

import cv2
import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st
from tests.replay.bag_writer import GENERATIONS, Msg, bag_path, bayer_rggb, compressed, frames_as_messages, raw_image, write_bag

from fearguard.cli import main
from fearguard.errors import SourceError
from fearguard.replay.bags import BagTopics, decode_image
from fearguard.replay.recordings import open_recording as open_source
from fearguard.replay.sources import TubSource

T0_NS = 1_700_000_000 * 10**9  # a real epoch stamp: receive time and header stamp agree
STEP_NS = 50_000_000  # 20 Hz
TUB = "modelcar/donkey-carpet-dark"
CUE_AND_COMMAND = ("t_s", "lane_confidence", "brightness", "occlusion", "obstacle_range_m", "qr_staleness_s", "fear", "fear_level",
                   "mode", "strategy", "speed_limit_mps", "steering_deg", "reasons", "cause")


def _images(n: int = 6, shape: tuple[int, int] = (24, 32)) -> list[np.ndarray]:
    rng = np.random.default_rng(7)
    return [rng.integers(0, 256, (*shape, 3), dtype=np.uint8) for _ in range(n)]


def _stamps(n: int) -> list[int]:
    return [T0_NS + i * STEP_NS for i in range(n)]


@pytest.mark.parametrize("generation", GENERATIONS)
@pytest.mark.parametrize("encoding", ["bgr8", "rgb8", "bgra8", "mono8"])
def test_raw_frames_equal_the_images_written_byte_for_byte(tmp_path: Path, generation: str, encoding: str) -> None:
    images = _images()
    bag = write_bag(bag_path(tmp_path, generation), generation,
                    frames_as_messages(_stamps(6), [raw_image(im, encoding) for im in images], compressed_images=False))
    source = open_source(bag)
    frames = list(source.iter_frames())
    assert (source.kind, source.expected_frames, source.frame_size, source.fps) == ("bag", 6, (32, 24), pytest.approx(20.0))
    expected = [cv2.cvtColor(cv2.cvtColor(im, cv2.COLOR_BGR2GRAY), cv2.COLOR_GRAY2BGR) if encoding == "mono8" else im for im in images]
    assert [f.index for f in frames] == list(range(6))
    for frame, image in zip(frames, expected, strict=True):
        assert frame.image_bgr.dtype == np.uint8 and frame.image_bgr.tobytes() == image.tobytes()
    assert [f.t_s for f in frames] == pytest.approx([0.05 * i for i in range(6)])
    assert [f.source_frame for f in frames] == [f.stamp_ns for f in frames] == _stamps(6)


@pytest.mark.parametrize("generation", GENERATIONS)
@pytest.mark.parametrize("fmt", ["jpeg", "png"])
def test_compressed_frames_decode_exactly_as_the_file_they_hold(tmp_path: Path, generation: str, fmt: str) -> None:
    images = _images(4)
    files = [cv2.imencode(".jpg" if fmt == "jpeg" else ".png", im)[1].tobytes() for im in images]
    bag = write_bag(bag_path(tmp_path, generation), generation,
                    frames_as_messages(_stamps(4), [compressed(f, fmt) for f in files], compressed_images=True))
    frames = list(open_source(bag).iter_frames())
    for frame, data, image in zip(frames, files, images, strict=True):
        assert frame.image_bgr.tobytes() == cv2.imdecode(np.frombuffer(data, np.uint8), cv2.IMREAD_COLOR).tobytes()
        if fmt == "png":
            assert frame.image_bgr.tobytes() == image.tobytes()


@pytest.mark.parametrize("encoding", ["yuv422", "yuv422_yuy2"])
def test_yuv422_frames_are_opencvs_conversion_of_the_bytes(tmp_path: Path, encoding: str) -> None:
    images = _images(2)
    payloads = [raw_image(im, encoding) for im in images]
    bag = write_bag(bag_path(tmp_path, "ros2-mcap"), "ros2-mcap", frames_as_messages(_stamps(2), payloads, compressed_images=False))
    code = cv2.COLOR_YUV2BGR_UYVY if encoding == "yuv422" else cv2.COLOR_YUV2BGR_YUY2
    for frame, payload in zip(open_source(bag).iter_frames(), payloads, strict=True):
        assert frame.image_bgr.tobytes() == cv2.cvtColor(payload["data"].reshape(24, 32, 2), code).tobytes()


def test_a_bayer_rggb_picture_of_a_flat_colour_comes_back_that_colour(tmp_path: Path) -> None:
    flat = np.empty((24, 32, 3), np.uint8)
    flat[:] = (30, 100, 200)  # BGR: mostly red
    bag = write_bag(bag_path(tmp_path, "ros1"), "ros1", frames_as_messages(_stamps(1), [raw_image(flat, "bayer_rggb8")],
                                                                            compressed_images=False))
    frame = next(open_source(bag).iter_frames())
    assert frame.image_bgr[12, 16].tolist() == [30, 100, 200]
    assert bayer_rggb(flat)[0, 0] == 200  # the mosaic's top-left is red: the pattern is RGGB


def test_padded_rows_and_16_bit_grey_are_read_and_odd_encodings_explained() -> None:
    class Image:  # the fields of sensor_msgs/Image, as rosbags deserialises them
        def __init__(self, encoding: str, data: np.ndarray, step: int, width: int = 3, height: int = 2, is_bigendian: int = 0):
            self.encoding, self.data, self.step = encoding, data, step
            self.width, self.height, self.is_bigendian = width, height, is_bigendian

    padded = np.arange(2 * 12, dtype=np.uint8)  # 3 px × 3 bytes + 3 bytes of padding per row
    image, _ = decode_image(Image("bgr8", padded, 12))
    assert image.tolist() == [[[0, 1, 2], [3, 4, 5], [6, 7, 8]], [[12, 13, 14], [15, 16, 17], [18, 19, 20]]]
    wide = np.array([0x1234, 0xFF00, 0x0001, 0x8000, 0x0100, 0x7FFF], "<u2").view(np.uint8)
    image, _ = decode_image(Image("mono16", wide, 6))
    assert image[..., 0].tolist() == [[0x12, 0xFF, 0x00], [0x80, 0x01, 0x7F]]
    assert "32FC1" in decode_image(Image("32FC1", padded, 12))[1]
    assert "does not fit" in decode_image(Image("bgr8", padded[:10], 12))[1]


def test_sensors_are_aligned_by_time_like_a_sensor_log(tmp_path: Path) -> None:
    t = _stamps(6)
    messages = frames_as_messages(t, [raw_image(im) for im in _images()], compressed_images=False)
    messages += [Msg("/sonar", "sensor_msgs/msg/Range", t[0] + 10_000_000, {"range": 1.5}),
                 Msg("/sonar", "sensor_msgs/msg/Range", t[2] + 10_000_000, {"range": float("-inf")}),  # REP 117: too close
                 Msg("/sonar", "sensor_msgs/msg/Range", t[4] + 10_000_000, {"range": float("nan")}),  # no reading
                 Msg("/odom", "nav_msgs/msg/Odometry", t[1], {"vx": 0.8, "x": 0.0}),
                 Msg("/odom", "nav_msgs/msg/Odometry", t[3], {"vx": -0.6, "x": 0.5}),  # reversing: the speed is a magnitude
                 Msg("/qr", "std_msgs/msg/String", t[3] + 1, {"data": "FG1;route=a;sector=1;pos_m=2.0"})]
    bag = write_bag(bag_path(tmp_path, "ros2-db3"), "ros2-db3", sorted(messages, key=lambda m: m.log_ns))
    source = open_source(bag)
    sensors = source.sensors
    assert set(sensors.columns) == {"ultrasonic_range_m", "speed_mps", "odometer_m", "qr_payload"}
    at = [sensors.at(f.t_s) for f in source.iter_frames()]
    assert [s.ultrasonic_range_m for s in at] == [None, 1.5, 1.5, 0.0, 0.0, 0.0]  # latest at or before; NaN is no reading
    assert [s.speed_mps for s in at] == [None, 0.8, 0.8, 0.6, 0.6, 0.6]
    assert [s.odometer_m for s in at][3:] == [0.5, 0.5, 0.5]
    assert [s.qr_payload for s in at] == [None, None, None, None, "FG1;route=a;sector=1;pos_m=2.0", "FG1;route=a;sector=1;pos_m=2.0"]
    assert sensors.at(10.0).speed_mps is None  # older than MAX_AGE_S: no reading


@pytest.mark.parametrize("msgtype", ["geometry_msgs/msg/Twist", "geometry_msgs/msg/TwistStamped"])
def test_a_twist_topic_gives_the_speed(tmp_path: Path, msgtype: str) -> None:
    t = _stamps(3)
    messages = frames_as_messages(t, [raw_image(im) for im in _images(3)], compressed_images=False)
    messages.append(Msg("/vel", msgtype, t[0], {"vx": 1.25}))
    source = open_source(write_bag(bag_path(tmp_path, "ros1"), "ros1", messages))
    assert [source.sensors.at(f.t_s).speed_mps for f in source.iter_frames()] == [1.25, 1.25, 1.25]
    assert source.topics_used == {"image": "/camera/image", "speed": "/vel"}


def test_topics_are_picked_when_there_is_one_and_asked_for_otherwise(tmp_path: Path) -> None:
    t = _stamps(2)
    images = [raw_image(im) for im in _images(2)]
    messages = [*frames_as_messages(t, images, compressed_images=False, topic="/front"),
                *frames_as_messages([x + 1 for x in t], images, compressed_images=False, topic="/rear"),
                Msg("/a", "sensor_msgs/msg/Range", t[0], {"range": 1.0}), Msg("/b", "sensor_msgs/msg/Range", t[0], {"range": 2.0})]
    bag = write_bag(bag_path(tmp_path, "ros2-mcap"), "ros2-mcap", sorted(messages, key=lambda m: m.log_ns))
    with pytest.raises(SourceError, match=r"several sensor_msgs/msg/Image topics: /front \(2 messages\), /rear .*--image-topic"):
        open_source(bag)
    with pytest.raises(SourceError, match=r"--range-topic.*several sensor_msgs/msg/Range topics"):
        open_source(bag, topics=BagTopics(image="/rear"))
    source = open_source(bag, topics=BagTopics(image="/rear", range="/b"))
    assert source.sensors.at(0.0).ultrasonic_range_m == 2.0
    assert open_source(bag, topics=BagTopics(image="/rear", range="none")).sensors is None
    with pytest.raises(SourceError, match=r"--image-topic.*/a is sensor_msgs/msg/Range, not"):
        open_source(bag, topics=BagTopics(image="/a"))
    listing = r"topics: /front \(sensor_msgs/msg/Image\), /a \(sensor_msgs/msg/Range\)"
    with pytest.raises(SourceError, match=r"/nope is not in the bag; " + listing):
        open_source(bag, topics=BagTopics(image="/nope"))


def test_header_stamps_on_another_clock_give_way_to_the_receive_time(tmp_path: Path) -> None:
    t = _stamps(3)
    messages = [Msg("/camera/image", "sensor_msgs/msg/Image", x, raw_image(im), stamp_ns=12 * 10**9 + i * 10**8)  # a simulator's clock
                for i, (x, im) in enumerate(zip(t, _images(3), strict=True))]
    source = open_source(write_bag(bag_path(tmp_path, "ros1"), "ros1", messages))
    assert [f.t_s for f in source.iter_frames()] == pytest.approx([0.0, 0.05, 0.1])  # receive time, not the 0.1 s steps
    assert any("another clock" in note and "aligned by receive time" in note for note in source.notes)


def test_a_bag_without_an_image_topic_or_without_rosbags_is_a_source_error(tmp_path: Path, monkeypatch) -> None:
    bag = write_bag(bag_path(tmp_path, "ros1"), "ros1", [Msg("/sonar", "sensor_msgs/msg/Range", T0_NS, {"range": 1.0})])
    with pytest.raises(SourceError, match=r"no sensor_msgs/Image or CompressedImage topic to replay; the bag has /sonar"):
        open_source(bag)
    monkeypatch.setitem(sys.modules, "rosbags", None)
    with pytest.raises(SourceError, match=r'pip install "fearguard\[ros\]"'):
        open_source(bag)


def test_without_rosbags_the_cli_says_how_to_install_it_and_exits_2(tmp_path: Path) -> None:
    bag = write_bag(bag_path(tmp_path, "ros1"), "ros1", frames_as_messages(_stamps(1), [raw_image(_images(1)[0])], compressed_images=False))
    code = (f"import sys\nsys.modules['rosbags'] = None\nfrom fearguard.cli import main\n"
            f"sys.exit(main(['replay', {str(bag)!r}, '--out', {str(tmp_path / 'o')!r}]))")
    done = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, timeout=120)
    assert done.returncode == 2 and 'SourceError: ' in done.stderr and 'pip install "fearguard[ros]"' in done.stderr


def _bag_copies_cut(bag: Path, tmp_path: Path, cut_share: float, flip: int | None) -> Path:
    """A copy of the bag with its storage file cut to ``cut_share`` of its bytes, or one byte flipped at ``flip``."""
    target = tmp_path / f"damaged-{cut_share:.3f}-{flip}"
    shutil.rmtree(target, ignore_errors=True)
    if bag.is_dir():
        shutil.copytree(bag, target)
        storage = next(p for p in target.iterdir() if p.suffix in (".db3", ".mcap"))
    else:
        target.mkdir()
        storage = target / bag.name
        shutil.copy(bag, storage)
    data = bytearray(storage.read_bytes())
    if flip is not None:
        data[flip % len(data)] ^= 0xFF
    else:
        data = data[: int(len(data) * cut_share)]
    storage.write_bytes(bytes(data))
    return target if bag.is_dir() else storage


@pytest.fixture(scope="module")
def bags_to_damage(tmp_path_factory) -> dict[str, Path]:
    folder = tmp_path_factory.mktemp("bags")
    t = _stamps(40)
    messages = frames_as_messages(t, [raw_image(im) for im in _images(40, (12, 16))], compressed_images=False)
    messages += [Msg("/sonar", "sensor_msgs/msg/Range", x + 1, {"range": 1.0}) for x in t]
    messages.sort(key=lambda m: m.log_ns)
    return {g: write_bag(bag_path(folder, g), g, messages) for g in GENERATIONS}


@settings(max_examples=30, suppress_health_check=[HealthCheck.function_scoped_fixture])
@given(generation=st.sampled_from(GENERATIONS), cut=st.floats(0.0, 1.0), flip=st.none() | st.integers(0, 10**6))
def test_a_cut_or_corrupted_bag_is_read_up_to_the_damage_or_refused_never_a_traceback(
    bags_to_damage: dict[str, Path], tmp_path: Path, generation: str, cut: float, flip: int | None,
) -> None:
    damaged = _bag_copies_cut(bags_to_damage[generation], tmp_path, cut, flip)
    try:
        source = open_source(damaged)
    except SourceError as exc:
        assert str(damaged) in str(exc) or damaged.name in str(exc)
        return
    frames = list(source.iter_frames())
    assert len(frames) + len(source.skipped) <= 40
    for frame in frames:
        assert frame.image_bgr.shape == (12, 16, 3) and frame.image_bgr.dtype == np.uint8


def test_a_cut_mcap_bag_is_read_up_to_the_cut_with_a_note(bags_to_damage: dict[str, Path], tmp_path: Path) -> None:
    damaged = _bag_copies_cut(bags_to_damage["ros2-mcap"], tmp_path, 0.999, None)
    source = open_source(damaged)
    frames = list(source.iter_frames())
    assert len(frames) == 40 and "cut short or corrupt" in source.stopped_early and "read up to the damage" in source.stopped_early


# ----------------------------------------------------------------------------- the Donkey tub as a bag


def _tub_as_bags(tub: Path, folder: Path, stop: int | None) -> tuple[dict[str, Path], list[int]]:
    """The tub's frames with its own _timestamp_ms: a ROS 1 bag of raw bgr8 images (the decoded JPEGs) and a ROS 2 MCAP bag
    of CompressedImage (the JPEG files' bytes); and the stamps."""
    raw, jpeg, stamps = [], [], []
    for frame in TubSource(tub, None).iter_frames(stop=stop):
        stamps.append(frame.stamp_ns)
        raw.append(raw_image(frame.image_bgr))
        jpeg.append(compressed((tub / "images" / f"{frame.index}_cam_image_array_.jpg").read_bytes()))
    return {
        "ros1": write_bag(folder / "tub.bag", "ros1", frames_as_messages(stamps, raw, compressed_images=False)),
        "ros2-mcap": write_bag(folder / "tub_mcap", "ros2-mcap", frames_as_messages(stamps, jpeg, compressed_images=True)),
    }, stamps


def _rows(out: Path) -> list[dict]:
    return [json.loads(line) for line in (out / "log.jsonl").read_text().splitlines()]


def _tub_and_bags_replay_alike(shared_data: Path, tmp_path: Path, stop: int | None) -> None:
    tub = shared_data / TUB
    bags, stamps = _tub_as_bags(tub, tmp_path, stop)
    to = [] if stop is None else ["--to", f"{stop}f"]
    assert main(["replay", str(tub), "--out", str(tmp_path / "tub"), "--no-plots", *to]) == 0
    tub_rows = _rows(tmp_path / "tub")
    assert len(tub_rows) == len(stamps) == (stop or 2526)
    assert [r["source_frame"] for r in tub_rows] == [r["frame"] for r in tub_rows]  # the tub's record index
    for generation, bag in bags.items():
        out = tmp_path / generation
        assert main(["replay", str(bag), "--out", str(out), "--no-plots"]) == 0
        rows = _rows(out)
        assert len(rows) == len(tub_rows), generation
        # a tub records only while the car drives, so its gaps are pauses (a fresh start); a bag's are stalls (faults):
        # row for row alike up to the first pause, and after it the same pictures at the same times, the pauses stalls
        pauses = [k for k, r in enumerate(tub_rows) if "resumed_after_s" in r]
        first = pauses[0] if pauses else len(rows)
        for tub_row, row in zip(tub_rows[:first], rows[:first], strict=True):
            assert {k: row[k] for k in CUE_AND_COMMAND} == {k: tub_row[k] for k in CUE_AND_COMMAND}, (generation, tub_row["frame"])
        assert [(r["t_s"], r["brightness"]) for r in rows] == [(r["t_s"], r["brightness"]) for r in tub_rows], generation
        assert [k for k, r in enumerate(rows) if "input stalled" in r["reasons"][0]] == pauses, generation
        assert not any("stalled" in reason for r in tub_rows for reason in r["reasons"])
        assert [r["source_frame"] for r in rows] == stamps  # the bag stamp of each picture, in ns


def test_the_shared_tub_as_ros1_and_ros2_mcap_bags_replays_like_the_tub_first_400_frames(shared_data: Path, tmp_path: Path) -> None:
    _tub_and_bags_replay_alike(shared_data, tmp_path, 400)


@pytest.mark.slow
def test_the_whole_shared_tub_as_ros1_and_ros2_mcap_bags_replays_like_the_tub(shared_data: Path, tmp_path: Path) -> None:
    _tub_and_bags_replay_alike(shared_data, tmp_path, None)


def test_a_track_is_learnt_from_bags_as_from_the_tub(shared_data: Path, tmp_path: Path) -> None:
    """`fearguard learn` reads bags as replay does: the tub's pictures as an MCAP bag teach what the tub teaches."""
    from fearguard.track.learn import LearnOptions, learn_track

    tub = shared_data / TUB
    bags, stamps = _tub_as_bags(tub, tmp_path, 300)
    from_bag = learn_track([bags["ros2-mcap"]]).profile
    from_tub = learn_track([tub], LearnOptions(stop="300f")).profile
    assert from_bag.frames_learnt == len(stamps)  # a bag has no throttle: no frame is known to be standing
    assert from_tub.frames_learnt < len(stamps)  # the tub says when the car stood
    later = [f.image_bgr for f in TubSource(tub, None).iter_frames(300, 500, 10)]
    fam = [from_bag.familiarity(f)[0] for f in later]
    assert np.median(fam) >= 0.5 and abs(np.median(fam) - np.median([from_tub.familiarity(f)[0] for f in later])) <= 0.3
