"""run.mcap for Foxglove (issue 37): written behind the Recorder by replay and run, read back with the mcap package's reader."""

from __future__ import annotations

import base64
import itertools
import json
import sys
from pathlib import Path

import cv2
import numpy as np
import pytest
from mcap.reader import make_reader

import fearguard as fg
from fearguard.cli import main
from fearguard.errors import FearguardError
from fearguard.outputs.mcap import MCAP_NAME, TOPICS
from fearguard.outputs.recorder import Recorder
from tests.replay.bag_writer import Msg, bag_path, frames_as_messages, raw_image, write_bag

SCHEMA_OF = {TOPICS["image"]: "foxglove.CompressedImage", TOPICS["command"]: "fearguard.Command", TOPICS["cues"]: "fearguard.Cues",
             TOPICS["reasons"]: "foxglove.Log"}
SHORT = "name = 'short'\nduration_s = 1.0\n[[road.segments]]\nkind = 'straight'\nlength_m = 40.0\n[expect]\nno_collision = true\n"


def read_mcap(path: Path) -> dict[str, list[tuple[int, dict]]]:
    """topic → [(log_time ns, decoded JSON)], checking every channel's schema is the one the topic promises (JSON schema)."""
    out: dict[str, list[tuple[int, dict]]] = {}
    with path.open("rb") as fh:
        for schema, channel, message in make_reader(fh).iter_messages(log_time_order=False):
            assert schema.encoding == "jsonschema" and channel.message_encoding == "json"
            assert schema.name == SCHEMA_OF[channel.topic] == json.loads(schema.data)["title"]
            assert message.publish_time == message.log_time
            out.setdefault(channel.topic, []).append((message.log_time, json.loads(message.data)))
    return out


def check_one_per_frame(topics: dict[str, list[tuple[int, dict]]], frames: int) -> None:
    assert set(topics) == set(SCHEMA_OF)
    for topic, messages in topics.items():
        stamps = [t for t, _ in messages]
        assert len(messages) == frames, topic
        assert all(a < b for a, b in itertools.pairwise(stamps)), f"{topic}: stamps not increasing"
        for t, body in messages:
            assert body["timestamp"] == {"sec": t // 10**9, "nsec": t % 10**9}


def test_replay_of_a_bag_writes_run_mcap_stamped_with_the_bags_own_times(tmp_path: Path) -> None:
    rng = np.random.default_rng(3)
    stamps = [1_700_000_000 * 10**9 + i * 50_000_000 + 17 for i in range(8)]
    images = [rng.integers(0, 256, (120, 160, 3), dtype=np.uint8) for _ in stamps]
    messages = frames_as_messages(stamps, [raw_image(im) for im in images], compressed_images=False)
    messages.append(Msg("/sonar", "sensor_msgs/msg/Range", stamps[0] - 1, {"range": 0.6}))
    bag = write_bag(bag_path(tmp_path, "ros2-mcap"), "ros2-mcap", sorted(messages, key=lambda m: m.log_ns))
    assert main(["replay", str(bag), "--mcap", "--no-plots", "--out", str(tmp_path / "o")]) == 0
    topics = read_mcap(tmp_path / "o" / MCAP_NAME)
    check_one_per_frame(topics, 8)
    assert [t for t, _ in topics[TOPICS["image"]]] == stamps  # the input's stamps: both files open side by side
    rows = [json.loads(line) for line in (tmp_path / "o" / "log.jsonl").read_text().splitlines()]
    assert [r["source_frame"] for r in rows] == stamps
    for (_, command), (_, cues), (_, log), row in zip(topics[TOPICS["command"]], topics[TOPICS["cues"]], topics[TOPICS["reasons"]], rows,
                                                       strict=True):
        assert {k: command[k] for k in ("fear", "fear_level", "mode", "strategy", "speed_limit_mps", "steering_deg")} == \
            {k: row[k] for k in ("fear", "fear_level", "mode", "strategy", "speed_limit_mps", "steering_deg")}
        assert cues["obstacle_range_m"] == row["obstacle_range_m"] and cues["lane_confidence"] == row["lane_confidence"]
        assert log["message"].split("\n") == row["reasons"] and log["level"] in (2, 3, 4) and log["name"] == "fearguard"
    jpeg = base64.b64decode(topics[TOPICS["image"]][0][1]["data"])
    assert cv2.imdecode(np.frombuffer(jpeg, np.uint8), cv2.IMREAD_COLOR).shape == (120, 160, 3)
    summary = json.loads((tmp_path / "o" / "summary.json").read_text())
    assert summary["mcap"]["frames"] == 8 and summary["bag_topics"] == {"image": "/camera/image", "range": "/sonar"}


def test_run_writes_run_mcap_one_message_per_frame_per_topic(tmp_path: Path, capsys) -> None:
    scenario = tmp_path / "short.toml"
    scenario.write_text(SHORT)
    assert main(["run", str(scenario), "--mcap", "--out", str(tmp_path / "r")]) == 0
    assert f"foxglove {tmp_path / 'r'}/run.mcap" in capsys.readouterr().out
    rows = (tmp_path / "r" / "log.jsonl").read_text().splitlines()
    topics = read_mcap(tmp_path / "r" / MCAP_NAME)
    check_one_per_frame(topics, len(rows))
    assert [t for t, _ in topics[TOPICS["command"]]] == [round(json.loads(r)["t_s"] * 1e9) for r in rows]  # the simulated clock


def test_the_recorder_writes_images_alone_without_a_supervisor_and_holds_stamps_in_order(tmp_path: Path) -> None:
    image = np.full((120, 160, 3), 90, np.uint8)
    guard = fg.FearGuard(lambda frame: 0.0)
    cmd = guard.step(fg.Observation(t_s=0.0, speed_mps=0.5, cues=fg.Cues(lane_confidence=0.9, brightness=120.0, occlusion=0.0,
                                                                         obstacle_range_m=float("inf"), qr_staleness_s=0.0)))
    with Recorder(tmp_path, fps=20.0, mcap=True) as rec:
        assert rec.annotates and rec.mcap_path == tmp_path / MCAP_NAME
        rec.frame(0, 0.0, None, image=image)  # a baseline: no Command, the picture only
        rec.frame(1, 0.05, cmd, image=None, stamp_ns=10)  # no picture: the command, cues and reasons only
        rec.frame(2, 0.10, cmd, image=image, stamp_ns=5)  # a clock that steps back is written at the last time
    rec.close()  # twice is fine
    with (tmp_path / MCAP_NAME).open("rb") as fh:
        seen = [(c.topic, m.log_time) for _, c, m in make_reader(fh).iter_messages(log_time_order=False)]
    assert seen == [(TOPICS["image"], 0), *[(TOPICS[k], 10) for k in ("command", "cues", "reasons")],
                    (TOPICS["image"], 10), *[(TOPICS[k], 10) for k in ("command", "cues", "reasons")]]
    nothing = Recorder(None, fps=20.0, mcap=True)
    assert nothing.mcap_path is None and not nothing.annotates


def test_without_the_mcap_package_the_error_says_how_to_install_it(tmp_path: Path, monkeypatch) -> None:
    monkeypatch.setitem(sys.modules, "mcap.writer", None)
    with pytest.raises(FearguardError, match=r'pip install "fearguard\[ros\]"'):
        Recorder(tmp_path, fps=20.0, mcap=True)
