"""``run.mcap`` for Foxglove: what the supervisor saw and decided, as topics beside the recording's own.

One message per frame on each topic, all stamped with the recording's time (``log_time`` = ``publish_time`` = the
frame's stamp in ns; for a ROS bag the image message's receive time, so both files open side by side):

| topic | schema (JSON) | holds |
|---|---|---|
| ``/fearguard/image`` | ``foxglove.CompressedImage`` | the annotated frame, JPEG (frames given an image only) |
| ``/fearguard/command`` | ``fearguard.Command`` | fear, fear_level, mode, strategy, cause, speed_limit_mps, steering_deg |
| ``/fearguard/cues`` | ``fearguard.Cues`` | the five cues (``"inf"`` for nothing in range / never localised, null unknown) |
| ``/fearguard/reasons`` | ``foxglove.Log`` | the reasons, one line each; level INFO / WARNING / ERROR for NORMAL / CAUTION / EMERGENCY |

A run without a supervisor (a baseline) writes the image only. Written with the ``mcap`` package's writer and
Foxglove's JSON schemas (the properties Foxglove reads, from foxglove-sdk's ``schemas/jsonschema``): pure Python, no
Foxglove SDK needed (``pip install "fearguard[ros]"``). A run killed with SIGKILL keeps the chunks already written
(readable record by record, e.g. by ``fearguard replay``'s own MCAP stream reader), not the summary.
"""

from __future__ import annotations

import base64
import json
from collections.abc import Mapping
from pathlib import Path
from typing import Any, BinaryIO

import cv2
import numpy as np

from fearguard.cues import CUE_NAMES
from fearguard.errors import FearguardError
from fearguard.outputs.report import json_value
from fearguard.policy import Mode
from fearguard.supervisor import Command

MCAP_NAME = "run.mcap"
INSTALL_HINT = 'MCAP output needs the mcap package: pip install "fearguard[ros]"'
JPEG_QUALITY = 90  # [0-100] annotated frames: text stays sharp, ~25 kB per 320×240 frame
TOPICS = {"image": "/fearguard/image", "command": "/fearguard/command", "cues": "/fearguard/cues", "reasons": "/fearguard/reasons"}
LOG_LEVEL = {Mode.NORMAL: 2, Mode.CAUTION: 3, Mode.EMERGENCY: 4}  # foxglove.LogLevel INFO, WARNING, ERROR
_TIME = {"type": "object", "title": "time", "properties": {"sec": {"type": "integer", "minimum": 0},
                                                           "nsec": {"type": "integer", "minimum": 0, "maximum": 999999999}}}
_NUMBER_OR_TEXT = {"type": ["number", "string", "null"]}  # json_value: NaN → null, ±inf → "inf" / "-inf"
SCHEMAS: Mapping[str, dict[str, Any]] = {
    "image": {"title": "foxglove.CompressedImage", "description": "A compressed image", "type": "object", "properties": {
        "timestamp": {**_TIME, "description": "Timestamp of image"}, "frame_id": {"type": "string"},
        "data": {"type": "string", "contentEncoding": "base64"}, "format": {"type": "string"}},
        "required": ["timestamp", "frame_id", "data", "format"]},
    "command": {"title": "fearguard.Command", "description": "What fearguard decided for one frame", "type": "object", "properties": {
        "timestamp": _TIME, "fear": {"type": "number"}, "fear_level": {"type": "string"}, "mode": {"type": "string"},
        "strategy": {"type": "string"}, "cause": {"type": "string"}, "speed_limit_mps": {"type": "number"},
        "steering_deg": {"type": "number"}}},
    "cues": {"title": "fearguard.Cues", "description": "The five risk cues of one frame", "type": "object",
             "properties": {"timestamp": _TIME, **{name: _NUMBER_OR_TEXT for name in CUE_NAMES}}},
    "reasons": {"title": "foxglove.Log", "description": "A log message", "type": "object", "properties": {
        "timestamp": {**_TIME, "description": "Timestamp of log message"},
        "level": {"title": "foxglove.LogLevel", "oneOf": [{"title": t, "const": i} for i, t in
                                                          enumerate(("UNKNOWN", "DEBUG", "INFO", "WARNING", "ERROR", "FATAL"))]},
        "message": {"type": "string"}, "name": {"type": "string"}, "file": {"type": "string"},
        "line": {"type": "integer", "minimum": 0}},
        "required": ["timestamp", "level", "message", "name", "file", "line"]},
}


def _time(stamp_ns: int) -> dict[str, int]:
    return {"sec": stamp_ns // 1_000_000_000, "nsec": stamp_ns % 1_000_000_000}


class McapSink:
    """Writes run.mcap frame by frame (``write``), finished by ``close``."""

    def __init__(self, path: str | Path) -> None:
        try:
            from mcap.writer import Writer
        except ModuleNotFoundError:
            raise FearguardError(INSTALL_HINT) from None
        self.path = Path(path)
        self.frames = 0
        self._last_ns = -1
        self._file: BinaryIO | None = self.path.open("wb")
        self._writer = Writer(self._file)
        self._writer.start(profile="", library="fearguard")
        self._channels: dict[str, int] = {}
        for key, schema in SCHEMAS.items():
            schema_id = self._writer.register_schema(name=schema["title"], encoding="jsonschema", data=json.dumps(schema).encode())
            self._channels[key] = self._writer.register_channel(topic=TOPICS[key], message_encoding="json", schema_id=schema_id)

    def write(self, stamp_ns: int, cmd: Command | None, image_bgr: np.ndarray | None) -> None:
        """One frame: the annotated image (when given) and, with a Command, the command, the cues and the reasons.

        Stamps are held non-decreasing and non-negative (a recording whose clock steps back is written at the last time)."""
        stamp_ns = max(int(stamp_ns), self._last_ns, 0)
        self._last_ns = stamp_ns
        when = _time(stamp_ns)
        if image_bgr is not None:
            ok, jpeg = cv2.imencode(".jpg", image_bgr, [cv2.IMWRITE_JPEG_QUALITY, JPEG_QUALITY])
            if ok:
                self._add("image", stamp_ns, {"timestamp": when, "frame_id": "camera", "format": "jpeg",
                                              "data": base64.b64encode(jpeg.tobytes()).decode("ascii")})
        if cmd is not None:
            self._add("command", stamp_ns, json_value({
                "timestamp": when, "fear": cmd.fear, "fear_level": cmd.fear_level.name, "mode": cmd.mode.name,
                "strategy": cmd.strategy.name, "cause": cmd.cause.value if cmd.cause is not None else "fault",
                "speed_limit_mps": cmd.speed_limit_mps, "steering_deg": cmd.steering_deg}))
            self._add("cues", stamp_ns, {"timestamp": when, **json_value(dict(zip(CUE_NAMES, cmd.cues.values(), strict=True)))})
            self._add("reasons", stamp_ns, {"timestamp": when, "level": LOG_LEVEL[cmd.mode], "message": "\n".join(cmd.reasons),
                                            "name": "fearguard", "file": "", "line": 0})
        self.frames += 1

    def _add(self, key: str, stamp_ns: int, message: Mapping[str, Any]) -> None:
        data = json.dumps(message, allow_nan=False, separators=(",", ":")).encode()
        self._writer.add_message(channel_id=self._channels[key], log_time=stamp_ns, publish_time=stamp_ns, data=data)

    def close(self) -> None:
        """Write the summary and close the file (safe to call twice)."""
        if self._file is not None:
            file, self._file = self._file, None
            try:
                self._writer.finish()
            finally:
                file.close()
