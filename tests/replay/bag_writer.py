"""Real ROS bags for the tests, written by rosbags' own writers (ROS 1 .bag; ROS 2 .db3 and .mcap folders)."""

from __future__ import annotations

from collections.abc import Iterable, Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import cv2
import numpy as np
from rosbags.rosbag1 import Writer as Writer1
from rosbags.rosbag2 import StoragePlugin
from rosbags.rosbag2 import Writer as Writer2
from rosbags.typesys import Stores, get_typestore

GENERATIONS = ("ros1", "ros2-db3", "ros2-mcap")
STORES = {"ros1": Stores.ROS1_NOETIC, "ros2-db3": Stores.ROS2_HUMBLE, "ros2-mcap": Stores.ROS2_HUMBLE}


@dataclass
class Msg:
    """One message to write: topic, type (``sensor_msgs/msg/Image``), receive time, header stamp (None: = receive), fields."""

    topic: str
    msgtype: str
    log_ns: int
    fields: dict[str, Any] = field(default_factory=dict)
    stamp_ns: int | None = None


def bag_path(folder: Path, generation: str, name: str = "drive") -> Path:
    return folder / (f"{name}.bag" if generation == "ros1" else f"{name}_{generation.split('-')[1]}")


def write_bag(path: Path, generation: str, messages: Iterable[Msg]) -> Path:
    """Write ``messages`` (in receive-time order) with rosbags' writer of that generation; returns the bag's path."""
    store = get_typestore(STORES[generation])
    if generation == "ros1":
        writer: Any = Writer1(path)
    else:
        plugin = StoragePlugin.MCAP if generation.endswith("mcap") else StoragePlugin.SQLITE3
        writer = Writer2(path, version=9, storage_plugin=plugin)
    connections: dict[str, Any] = {}
    with writer:
        for m in messages:
            if m.topic not in connections:
                connections[m.topic] = writer.add_connection(m.topic, m.msgtype, typestore=store)
            msg = build(store, m.msgtype, m.stamp_ns if m.stamp_ns is not None else m.log_ns, m.fields)
            raw = store.serialize_ros1(msg, m.msgtype) if generation == "ros1" else store.serialize_cdr(msg, m.msgtype)
            writer.write(connections[m.topic], m.log_ns, raw)
    return path


def build(store: Any, msgtype: str, stamp_ns: int, fields: dict[str, Any]) -> Any:
    """A message of ``msgtype`` with a header stamped ``stamp_ns`` (if it has one) and the given fields, zeros elsewhere."""
    types = store.types
    time = types["builtin_interfaces/msg/Time"](sec=stamp_ns // 1_000_000_000, nanosec=stamp_ns % 1_000_000_000)
    header_type = types["std_msgs/msg/Header"]
    header = header_type(seq=0, stamp=time, frame_id="base") if "seq" in header_type.__dataclass_fields__ else \
        header_type(stamp=time, frame_id="base")
    vector = types["geometry_msgs/msg/Vector3"]
    if msgtype == "sensor_msgs/msg/Image":
        return types[msgtype](header=header, **fields)
    if msgtype == "sensor_msgs/msg/CompressedImage":
        return types[msgtype](header=header, **fields)
    if msgtype == "sensor_msgs/msg/Range":
        return types[msgtype](header=header, radiation_type=0, field_of_view=0.26, min_range=0.02, max_range=4.0, **fields)
    if msgtype == "std_msgs/msg/String":
        return types[msgtype](**fields)
    twist = types["geometry_msgs/msg/Twist"](linear=vector(x=fields.get("vx", 0.0), y=0.0, z=0.0), angular=vector(x=0.0, y=0.0, z=0.0))
    if msgtype == "geometry_msgs/msg/Twist":
        return twist
    if msgtype == "geometry_msgs/msg/TwistStamped":
        return types[msgtype](header=header, twist=twist)
    point = types["geometry_msgs/msg/Point"](x=fields.get("x", 0.0), y=fields.get("y", 0.0), z=0.0)
    pose = types["geometry_msgs/msg/Pose"](position=point, orientation=types["geometry_msgs/msg/Quaternion"](x=0.0, y=0.0, z=0.0, w=1.0))
    return types[msgtype](
        header=header, child_frame_id="base_link",
        pose=types["geometry_msgs/msg/PoseWithCovariance"](pose=pose, covariance=np.zeros(36)),
        twist=types["geometry_msgs/msg/TwistWithCovariance"](twist=twist, covariance=np.zeros(36)),
    )


def raw_image(image_bgr: np.ndarray, encoding: str = "bgr8") -> dict[str, Any]:
    """``sensor_msgs/Image`` fields holding ``image_bgr`` in ``encoding`` (bgr8, rgb8, mono8, bgra8, yuv422, bayer_rggb8)."""
    h, w = image_bgr.shape[:2]
    if encoding == "rgb8":
        pixels = cv2.cvtColor(image_bgr, cv2.COLOR_BGR2RGB)
    elif encoding == "bgra8":
        pixels = cv2.cvtColor(image_bgr, cv2.COLOR_BGR2BGRA)
    elif encoding == "mono8":
        pixels = cv2.cvtColor(image_bgr, cv2.COLOR_BGR2GRAY)
    elif encoding in ("yuv422", "uyvy"):
        pixels = cv2.cvtColor(image_bgr, cv2.COLOR_BGR2YUV_UYVY)
    elif encoding == "yuv422_yuy2":
        pixels = cv2.cvtColor(image_bgr, cv2.COLOR_BGR2YUV_YUY2)
    elif encoding == "bayer_rggb8":
        pixels = bayer_rggb(image_bgr)
    else:
        pixels = image_bgr
    data = np.ascontiguousarray(pixels).reshape(-1)
    return {"height": h, "width": w, "encoding": encoding, "is_bigendian": 0, "step": data.size // h, "data": data}


def bayer_rggb(image_bgr: np.ndarray) -> np.ndarray:
    """The RGGB mosaic a Bayer sensor would record of ``image_bgr``: R at (0, 0), G at (0, 1) and (1, 0), B at (1, 1)."""
    mosaic = np.empty(image_bgr.shape[:2], np.uint8)
    mosaic[0::2, 0::2] = image_bgr[0::2, 0::2, 2]
    mosaic[0::2, 1::2] = image_bgr[0::2, 1::2, 1]
    mosaic[1::2, 0::2] = image_bgr[1::2, 0::2, 1]
    mosaic[1::2, 1::2] = image_bgr[1::2, 1::2, 0]
    return mosaic


def compressed(data: bytes, fmt: str = "jpeg") -> dict[str, Any]:
    return {"format": fmt, "data": np.frombuffer(data, np.uint8)}


def frames_as_messages(stamps_ns: Sequence[int], payloads: Sequence[dict[str, Any]], *, compressed_images: bool,
                       topic: str = "/camera/image") -> list[Msg]:
    msgtype = "sensor_msgs/msg/CompressedImage" if compressed_images else "sensor_msgs/msg/Image"
    return [Msg(topic, msgtype, t, p) for t, p in zip(stamps_ns, payloads, strict=True)]
