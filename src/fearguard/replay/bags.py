"""ROS bags as recordings, no ROS needed: ROS 1 ``.bag``, ROS 2 bag folders (``.db3`` or ``.mcap``) and bare ``.mcap`` /
``.db3`` files, read through rosbags (pure Python; ``pip install "fearguard[ros]"``).

Frames come from one image topic (``sensor_msgs/Image``: bgr8, rgb8, bgra8, rgba8, mono8, mono16, 8UC1/3/4, the four
8-bit Bayer patterns, yuv422 (UYVY) and yuv422_yuy2 (YUYV), converted by OpenCV; ``sensor_msgs/CompressedImage``:
JPEG, PNG, anything ``cv2.imdecode`` reads). The frame index is the message's position in that topic.

Sensors are read once, when the bag is opened, one ``SensorLog`` per topic, and a frame sees each topic's latest
message at or before its time, at most ``MAX_AGE_S`` old (``BagSensors.at``: the sensor log's rule, per topic):
``sensor_msgs/Range`` → ``ultrasonic_range_m`` (−inf, REP 117's "too close to measure", is 0 m; NaN no reading);
``nav_msgs/Odometry``, ``geometry_msgs/TwistStamped`` or ``Twist`` → ``speed_mps`` = |(linear.x, linear.y)| (Odometry's
pose also gives ``odometer_m``, the path length driven); ``std_msgs/String`` → ``qr_payload``.

Clocks: a message's time is its header stamp when that stamp lies within ``CLOCK_AGREEMENT_S`` of the time the bag
received it (checked on each topic's first message), else the receive time (a simulator's clock, a sensor that stamps
0 or its own boot time), with a note; unstamped messages (String, Twist) use the receive time. ``t_s`` = time − the
first frame's time; ``Frame.stamp_ns`` and ``source_frame`` are the frame message's receive time in nanoseconds, the
time ``run.mcap`` stamps its messages with, so both files open side by side in Foxglove.

Damage: a bag whose end is cut off or corrupt is read up to the damage (``stopped_early`` says where and why). A
truncated MCAP file has no summary for rosbags to open, so it is read record by record by the ``mcap`` package's stream
reader, messages decoded with the type definitions stored in it. A ROS 1 bag without its index (a recording that was
killed) cannot be read by rosbags: a ``SourceError`` says so. Anything else unusable is a ``SourceError`` naming the
file and the problem, never a traceback.
"""

from __future__ import annotations

import math
from collections.abc import Callable, Generator, Iterator, Mapping, Sequence
from dataclasses import dataclass
from pathlib import Path
from types import MappingProxyType
from typing import Any

import cv2
import numpy as np

from fearguard.errors import SourceError, describe_exception
from fearguard.replay.sensor_log import MAX_AGE_S, NO_READING, SensorLog, SensorSample
from fearguard.replay.sources import FPS_ESTIMATE_RECORDS, Frame, FrameSource, _sampled, estimate_fps

BAG_SUFFIXES = (".bag", ".db3", ".mcap")
INSTALL_HINT = 'reading ROS bags needs rosbags: pip install "fearguard[ros]"'
CLOCK_AGREEMENT_S = 5.0  # [s] a header stamp this close to the receive time is on the bag's clock (transport and queues take ms)
NO_TOPIC = "none"  # --range-topic none: ignore a topic the bag has
IMAGE_TYPES = ("sensor_msgs/msg/Image", "sensor_msgs/msg/CompressedImage")
RANGE_TYPES = ("sensor_msgs/msg/Range",)
SPEED_TYPES = ("nav_msgs/msg/Odometry", "geometry_msgs/msg/TwistStamped", "geometry_msgs/msg/Twist")  # preferred first
QR_TYPES = ("std_msgs/msg/String",)
_GREY = {"mono8", "8UC1"}
# encoding → (channels, OpenCV conversion to BGR or None); Bayer names follow cv_bridge: OpenCV names a pattern by
# its second row, so ROS's rggb is OpenCV's BG (checked on a synthetic mosaic in the tests)
RAW_ENCODINGS: Mapping[str, tuple[int, int | None]] = MappingProxyType({
    "bgr8": (3, None), "8UC3": (3, None), "rgb8": (3, cv2.COLOR_RGB2BGR), "bgra8": (4, cv2.COLOR_BGRA2BGR), "8UC4": (4, cv2.COLOR_BGRA2BGR),
    "rgba8": (4, cv2.COLOR_RGBA2BGR), "mono8": (1, cv2.COLOR_GRAY2BGR), "8UC1": (1, cv2.COLOR_GRAY2BGR),
    "bayer_rggb8": (1, cv2.COLOR_BayerBG2BGR), "bayer_bggr8": (1, cv2.COLOR_BayerRG2BGR),
    "bayer_gbrg8": (1, cv2.COLOR_BayerGR2BGR), "bayer_grbg8": (1, cv2.COLOR_BayerGB2BGR),
    "yuv422": (2, cv2.COLOR_YUV2BGR_UYVY), "uyvy": (2, cv2.COLOR_YUV2BGR_UYVY),
    "yuv422_yuy2": (2, cv2.COLOR_YUV2BGR_YUY2), "yuyv": (2, cv2.COLOR_YUV2BGR_YUY2),
})
WIDE_ENCODINGS = ("mono16", "16UC1")  # 16-bit grey: the high byte is shown


@dataclass(frozen=True)
class BagTopics:
    """The topics to read; None picks the only topic of the right type, ``"none"`` ignores that sensor."""

    image: str | None = None
    range: str | None = None
    speed: str | None = None
    qr: str | None = None


def is_bag(path: Path) -> bool:
    """A ROS 1 bag, a ROS 2 bag folder (it has metadata.yaml) or a bare .db3 / .mcap file."""
    if path.is_dir():
        return (path / "metadata.yaml").is_file()
    return path.suffix.lower() in BAG_SUFFIXES


# ------------------------------------------------------------------------------------------- readers


@dataclass(frozen=True)
class _Topic:
    name: str
    msgtype: str
    count: int | None  # messages in the bag (None: a damaged file read record by record does not know)


class _Reader:
    """rosbags' AnyReader: one .bag, a ROS 2 bag folder, or a bare .mcap / .db3 file."""

    def __init__(self, path: Path) -> None:
        from rosbags.highlevel import AnyReader
        from rosbags.typesys import Stores, get_typestore

        # a ROS 2 bag folder (metadata.yaml) or one file; the default types serve bags that store no definitions (Foxy)
        self._reader = AnyReader([path], default_typestore=get_typestore(Stores.ROS2_HUMBLE))
        self._reader.open()
        self.topics: dict[str, _Topic] = {}
        for c in self._reader.connections:
            known = self.topics.get(c.topic)
            self.topics[c.topic] = _Topic(c.topic, c.msgtype, c.msgcount + (known.count or 0 if known else 0))

    def messages(self, topics: Sequence[str]) -> Iterator[tuple[str, int, Callable[[], Any]]]:
        """(topic, receive time ns, a function that decodes the message) in receive-time order."""
        wanted = [c for c in self._reader.connections if c.topic in topics]
        reader = self._reader
        for connection, log_ns, raw in reader.messages(connections=wanted):
            yield connection.topic, log_ns, _decoder(reader.deserialize, raw, connection.msgtype)

    def close(self) -> None:
        self._reader.close()


def _decoder(deserialize: Callable[[bytes, str], Any], raw: bytes, msgtype: str) -> Callable[[], Any]:
    return lambda: deserialize(raw, msgtype)


class _McapStream:
    """A ROS 2 MCAP file read record by record (the ``mcap`` package's stream reader): for files cut short, which have
    no summary for rosbags to open. Messages are decoded with the definitions the file stores (ros2msg schemas)."""

    def __init__(self, path: Path) -> None:
        from rosbags.typesys import Stores, get_types_from_msg, get_typestore

        self.path = path
        self._store = get_typestore(Stores.ROS2_HUMBLE)
        self._get_types = get_types_from_msg
        self.topics: dict[str, _Topic] = {}
        self.damage: str | None = None
        for _ in self._records(None):  # the first pass learns every topic the readable part holds
            pass

    def _records(self, topics: Sequence[str] | None) -> Iterator[tuple[str, int, Callable[[], Any]]]:
        from mcap.records import Channel, Message, Schema
        from mcap.stream_reader import StreamReader

        schemas: dict[int, Any] = {}
        channels: dict[int, tuple[str, str]] = {}
        registered: set[str] = set()
        with self.path.open("rb") as fh:
            try:
                for record in StreamReader(fh, skip_magic=False).records:
                    if isinstance(record, Schema):
                        schemas[record.id] = record
                    elif isinstance(record, Channel):
                        schema = schemas.get(record.schema_id)
                        msgtype = _normal_type(schema.name) if schema is not None else ""
                        channels[record.id] = (record.topic, msgtype)
                        if topics is None:
                            self.topics[record.topic] = _Topic(record.topic, msgtype, None)
                        if schema is not None and msgtype not in registered and schema.encoding == "ros2msg":
                            self._store.register(self._get_types(schema.data.decode("utf-8", "replace"), msgtype))
                            registered.add(msgtype)
                    elif isinstance(record, Message) and topics is not None:
                        topic, msgtype = channels.get(record.channel_id, ("", ""))
                        if topic in topics:
                            yield topic, record.log_time, _decoder(self._store.deserialize_cdr, record.data, msgtype)
            except Exception as exc:  # the stream reader raises its own kinds at a cut or corrupt record: the damage
                self.damage = f"the file is cut short or corrupt after this point ({describe_exception(exc)})"

    def messages(self, topics: Sequence[str]) -> Iterator[tuple[str, int, Callable[[], Any]]]:
        yield from self._records(topics)

    def close(self) -> None:
        """Nothing stays open between passes."""


def _normal_type(name: str) -> str:
    """``sensor_msgs/Image`` (ROS 1 style) → ``sensor_msgs/msg/Image``, as rosbags names types."""
    parts = name.split("/")
    return f"{parts[0]}/msg/{parts[1]}" if len(parts) == 2 else name


def _open_reader(path: Path) -> _Reader | _McapStream:
    """rosbags' reader; for an .mcap file rosbags cannot open (cut short), the record-by-record stream."""
    try:
        import rosbags  # noqa: F401  (the optional extra: a clear message without it)
    except ModuleNotFoundError:
        raise SourceError(path, "", f"a ROS bag, but {INSTALL_HINT}") from None
    try:
        return _Reader(path)
    except Exception as exc:  # rosbags raises its own kinds, struct and sqlite errors for damaged files: all mean unreadable
        first = exc
    mcap_files = [path] if path.is_file() else sorted(path.glob("*.mcap")) if path.is_dir() else []
    if len(mcap_files) == 1 and mcap_files[0].suffix.lower() == ".mcap":
        try:
            stream = _McapStream(mcap_files[0])
        except Exception as exc:  # not even the start of an MCAP file
            raise SourceError(path, "", f"cannot read it as a ROS 2 MCAP file ({describe_exception(exc)})") from None
        if stream.topics:
            return stream
        raise SourceError(mcap_files[0], "", f"cut short or corrupt before its first complete chunk of messages ({stream.damage or first})")
    hint = ""
    if path.suffix.lower() == ".bag" and "index" in str(first).lower():
        hint = "; a ROS 1 bag whose recording was killed has no index: reindex it (`rosbag reindex`) or convert it with rosbags"
    raise SourceError(path, "", f"rosbags cannot read it ({describe_exception(first)}){hint}") from None


# -------------------------------------------------------------------------------------- the source


def _stamp_ns(msg: Any) -> int | None:
    """The header stamp in ns, None when the message has no header or stamps 0."""
    header = getattr(msg, "header", None)
    stamp = getattr(header, "stamp", None)
    if stamp is None:
        return None
    ns = int(stamp.sec) * 1_000_000_000 + int(getattr(stamp, "nanosec", getattr(stamp, "nsec", 0)))
    return ns or None


def decode_image(msg: Any) -> tuple[np.ndarray | None, str]:
    """A ``sensor_msgs/Image`` or ``CompressedImage`` as 8-bit BGR, or (None, why not)."""
    data = np.asarray(msg.data, dtype=np.uint8)
    if hasattr(msg, "format"):  # CompressedImage
        if "compresseddepth" in str(msg.format).lower():
            return None, f"compressed depth image ({msg.format!r}) is not a camera picture"
        image = cv2.imdecode(data, cv2.IMREAD_COLOR) if data.size else None
        return (image, "") if image is not None else (None, f"cannot be decoded as an image (format {msg.format!r})")
    encoding, width, height, step = str(msg.encoding), int(msg.width), int(msg.height), int(msg.step)
    if encoding in WIDE_ENCODINGS:
        channels, conversion, depth = 1, cv2.COLOR_GRAY2BGR, 2
    elif encoding in RAW_ENCODINGS:
        (channels, conversion), depth = RAW_ENCODINGS[encoding], 1
    else:
        return None, f"encoding {encoding!r} is not one fearguard converts ({', '.join(RAW_ENCODINGS)}, {', '.join(WIDE_ENCODINGS)})"
    row = width * channels * depth
    if width < 1 or height < 1 or step < row or data.size < step * (height - 1) + row:
        return None, f"{width}x{height} {encoding} with step {step} does not fit its {data.size} bytes of data"
    rows = np.lib.stride_tricks.as_strided(data, shape=(height, row), strides=(step, 1))
    if depth == 2:
        wide = rows.view(">u2" if msg.is_bigendian else "<u2")
        pixels = (wide >> 8).astype(np.uint8).reshape(height, width)
    else:
        pixels = rows.reshape(height, width, channels) if channels > 1 else rows.reshape(height, width)
    image = cv2.cvtColor(np.ascontiguousarray(pixels), conversion) if conversion is not None else np.ascontiguousarray(pixels)
    return image, ""


def _pick(topics: Mapping[str, _Topic], types: Sequence[str], wanted: str | None, what: str, option: str, path: Path) -> str | None:
    """The topic to read for one role: the one asked for, else the only one of the most preferred type present."""
    if wanted == NO_TOPIC:
        return None
    if wanted is not None:
        topic = topics.get(wanted)
        if topic is None or topic.msgtype not in types:
            listing = ", ".join(f"{t.name} ({t.msgtype})" for t in topics.values()) or "none"
            why = "is not in the bag" if topic is None else f"is {topic.msgtype}, not {' or '.join(types)}"
            raise SourceError(path, option, f"{wanted} {why}; topics: {listing}")
        return wanted
    for msgtype in types:
        found = [t for t in topics.values() if t.msgtype == msgtype]
        if len(found) == 1:
            return found[0].name
        if found:
            listing = ", ".join(f"{t.name} ({t.count if t.count is not None else '?'} messages)" for t in found)
            raise SourceError(path, option, f"several {msgtype} topics: {listing}; choose the {what} with {option} TOPIC "
                                            f"(or {option} none)" if option != "--image-topic" else
                                            f"several {msgtype} topics: {listing}; choose the camera with {option} TOPIC")
    return None


class BagSensors:
    """The bag's sensor topics, one SensorLog each, merged per frame (each topic's latest message, at most max_age_s old)."""

    def __init__(self, logs: Mapping[str, SensorLog]) -> None:
        self.logs = logs  # role ("range", "speed", "qr") → its log
        columns = {"range": ("ultrasonic_range_m",), "speed": ("speed_mps", "odometer_m"), "qr": ("qr_payload",)}
        self.columns = tuple(c for role in logs for c in columns[role])
        self.issues: tuple = ()

    def at(self, t_s: float, max_age_s: float = MAX_AGE_S) -> SensorSample:
        """Every topic's reading valid at t_s, merged into one sample (``t_s`` is the frame's)."""
        values: dict[str, Any] = {}
        for log in self.logs.values():
            sample = log.at(t_s, max_age_s)
            if sample is NO_READING:
                continue
            values.update({k: v for k, v in vars(sample).items() if v is not None and k != "t_s"})
        return SensorSample(t_s=t_s, **values) if values else NO_READING


class BagSource(FrameSource):
    """A ROS bag: frames from its image topic, sensors from its Range / Odometry / Twist / String topics."""

    kind = "bag"

    def __init__(self, path: Path, fps: float | None, topics: BagTopics | None = None) -> None:
        topics = topics or BagTopics()
        self._bag = _open_reader(path)
        try:
            self._setup(path, fps, topics)
        except BaseException:
            self._bag.close()
            raise

    def _setup(self, path: Path, fps: float | None, topics: BagTopics) -> None:
        found = self._bag.topics
        image = _pick(found, IMAGE_TYPES, topics.image, "camera", "--image-topic", path)
        if image is None:
            listing = ", ".join(f"{t.name} ({t.msgtype})" for t in found.values()) or "no topics"
            raise SourceError(path, "", f"no sensor_msgs/Image or CompressedImage topic to replay; the bag has {listing}")
        self.image_topic = image
        self.sensor_topics = {role: name for role, name in (
            ("range", _pick(found, RANGE_TYPES, topics.range, "range sensor", "--range-topic", path)),
            ("speed", _pick(found, SPEED_TYPES, topics.speed, "speed", "--speed-topic", path)),
            ("qr", _pick(found, QR_TYPES, topics.qr, "QR payloads", "--qr-topic", path)),
        ) if name is not None}
        notes: list[str] = []
        self._header_clock: dict[str, bool] = {}
        first = self._first_frames(notes)
        if not first:
            raise SourceError(path, image, "the image topic holds no readable message")
        self.t0_ns = first[0][1]
        size = None
        for image_bgr, _, _ in first:
            if image_bgr is not None:
                size = (int(image_bgr.shape[1]), int(image_bgr.shape[0]))
                break
        if fps is None:
            fps = estimate_fps([t for _, t, _ in first], 1e9, "the image stamps", "one image message", notes)
        count = found[image].count
        super().__init__(path, fps, count, size, notes)
        self.notes = (*self.notes, *self._sensor_notes())
        self.sensors = self._read_sensors() if self.sensor_topics else None
        self.topics_used = MappingProxyType({"image": image, **self.sensor_topics})

    def _time_ns(self, topic: str, msg: Any, log_ns: int, notes: list[str]) -> int:
        """The message's time on the bag's clock: its header stamp when that agrees with the receive time, else the latter."""
        stamp = _stamp_ns(msg)
        if topic not in self._header_clock:
            agrees = stamp is not None and abs(stamp - log_ns) <= CLOCK_AGREEMENT_S * 1e9
            self._header_clock[topic] = agrees
            if stamp is not None and not agrees:
                notes.append(f"{topic}: header stamps are {(stamp - log_ns) / 1e9:+.3g} s from the receive times (another clock): "
                             "aligned by receive time")
        return stamp if self._header_clock[topic] and stamp is not None else log_ns

    def _first_frames(self, notes: list[str]) -> list[tuple[np.ndarray | None, int, int]]:
        """(image or None, time ns, receive ns) of the first FPS_ESTIMATE_RECORDS image messages."""
        out: list[tuple[np.ndarray | None, int, int]] = []
        messages = self._bag.messages([self.image_topic])
        try:
            for topic, log_ns, decode in messages:
                try:
                    msg = decode()
                except Exception:  # an undecodable message is skipped here; iter_frames reports it
                    continue
                image = decode_image(msg)[0] if not out or out[0][0] is None else None
                out.append((image, self._time_ns(topic, msg, log_ns, notes), log_ns))
                if len(out) >= FPS_ESTIMATE_RECORDS:
                    break
        except Exception:  # damage this early is reported by iter_frames; the messages before it still count
            pass
        finally:
            close = getattr(messages, "close", None)
            if close is not None:
                close()
        return out

    def _sensor_notes(self) -> list[str]:
        return [f"{role} from {topic} ({self._bag.topics[topic].msgtype})" for role, topic in self.sensor_topics.items()]

    def _read_sensors(self) -> BagSensors:
        """Every sensor message, read once, as one SensorLog per role (times relative to the first frame)."""
        rows: dict[str, list[SensorSample]] = {role: [] for role in self.sensor_topics}
        role_of = {topic: role for role, topic in self.sensor_topics.items()}
        odometer = {"m": 0.0, "xy": None}
        notes: list[str] = []
        damaged = None
        try:
            for topic, log_ns, decode in self._bag.messages(list(role_of)):
                try:
                    msg = decode()
                except Exception:  # a message that does not decode is no reading
                    continue
                t_s = (self._time_ns(topic, msg, log_ns, notes) - self.t0_ns) / 1e9
                sample = _sensor_sample(role_of[topic], msg, t_s, odometer)
                if sample is not None:
                    rows[role_of[topic]].append(sample)
        except Exception as exc:  # a damaged bag: the sensor readings before the damage are kept
            damaged = f"sensor topics read up to damage in the bag ({describe_exception(exc)})"
        self.notes = (*self.notes, *notes, *([damaged] if damaged else []))
        return BagSensors({role: SensorLog(self.path, tuple(samples)) for role, samples in rows.items()})

    def _frames(self, start: int, stop: int | None, every: int) -> Generator[Frame, None, None]:
        index = -1
        notes: list[str] = []
        messages = self._bag.messages([self.image_topic])
        try:
            for topic, log_ns, decode in messages:
                index += 1
                if stop is not None and index >= stop:
                    return
                if not _sampled(index, start, stop, every):
                    continue
                try:
                    msg = decode()
                except Exception as exc:  # one message that does not deserialize costs that frame only
                    self._skip(index, f"message at {log_ns} ns does not decode ({describe_exception(exc)})")
                    continue
                image, why = decode_image(msg)
                if image is None:
                    self._skip(index, f"message at {log_ns} ns: {why}")
                    continue
                t_s = (self._time_ns(topic, msg, log_ns, notes) - self.t0_ns) / 1e9
                yield Frame(index, t_s, image, MappingProxyType({"stamp_ns": log_ns}), source_frame=log_ns, stamp_ns=log_ns)
        except Exception as exc:  # rosbags' and the storage's own errors at a damaged spot: read up to it
            self.stopped_early = f"the bag is damaged after image message {index} ({describe_exception(exc)}): read up to the damage"
        finally:
            close = getattr(messages, "close", None)
            if close is not None:
                close()
        damage = getattr(self._bag, "damage", None)
        if damage and self.stopped_early is None:
            self.stopped_early = f"{damage}: read up to the damage, {index + 1} image messages"


def _sensor_sample(role: str, msg: Any, t_s: float, odometer: dict[str, Any]) -> SensorSample | None:
    """One sensor message as a SensorSample row (None when it carries no reading)."""
    if role == "range":
        value = float(msg.range)
        if math.isnan(value):
            return None
        return SensorSample(t_s=t_s, ultrasonic_range_m=0.0 if value == -math.inf else value)
    if role == "qr":
        return SensorSample(t_s=t_s, qr_payload=str(msg.data)) if str(msg.data) else None
    twist = msg.twist.twist if hasattr(msg, "pose") else getattr(msg, "twist", msg)  # Odometry, TwistStamped, Twist
    speed = math.hypot(float(twist.linear.x), float(twist.linear.y))
    odometer_m = None
    if hasattr(msg, "pose"):
        xy = (float(msg.pose.pose.position.x), float(msg.pose.pose.position.y))
        if odometer["xy"] is not None:
            odometer["m"] += math.dist(odometer["xy"], xy)
        odometer["xy"] = xy
        odometer_m = odometer["m"]
    return SensorSample(t_s=t_s, speed_mps=speed if math.isfinite(speed) else None, odometer_m=odometer_m)
