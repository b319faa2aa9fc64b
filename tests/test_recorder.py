"""The recorder every driver uses: flushed log, video before log line, typed stats built in memory, atomic summary."""

from __future__ import annotations

import json
import math
from pathlib import Path

import numpy as np
import pytest

from fearguard.cues import Cues
from fearguard.fear import Cause, FearLevel
from fearguard.outputs.recorder import CommandStats, Elevated, Episode, Recorder, write_json
from fearguard.outputs.report import read_jsonl
from fearguard.outputs.video import count_frames
from fearguard.policy import Mode, Strategy
from fearguard.supervisor import Command, FearGuard, Observation

CALM = Cues(0.9, 120.0, 0.0, math.inf, 0.5)


def command(mode: str = "NORMAL", fear: float = 0.1, level: str = "LOW", strategy: str = "PASS_THROUGH", limit: float = 2.0,
            cause: Cause | None = Cause.ROAD, reasons: tuple[str, ...] = ("rule a", "note b")) -> Command:
    return Command(0.0, limit, Mode[mode], Strategy[strategy], fear, FearLevel[level], CALM, reasons, cause=cause)


def frame(k: int) -> np.ndarray:
    img = np.full((48, 64, 3), 40, np.uint8)
    img[:, k % 64] = 255
    return img


def test_the_log_holds_one_flushed_line_per_frame_with_the_extra_fields(tmp_path: Path) -> None:
    rec = Recorder(tmp_path, fps=10.0)
    rec.frame(0, 0.0, command(), fields={"x_m": 1.5})
    lines = (tmp_path / "log.jsonl").read_text().splitlines()  # flushed before close
    assert len(lines) == 1 and json.loads(lines[0])["x_m"] == 1.5
    rec.frame(1, 0.1, None, fields={"x_m": 2.0})
    rec.close()
    rec.close()  # twice is fine
    records = read_jsonl(tmp_path / "log.jsonl")
    assert [r["frame"] for r in records] == [0, 1] and "fear" not in records[1]
    assert rec.log_path == tmp_path / "log.jsonl" and rec.video_path is None and rec.video_frames_rescaled == 0


def test_stats_match_what_a_person_counts_by_hand() -> None:
    with Recorder(None, fps=10.0) as rec:
        script = [
            command(), command(level="MEDIUM", fear=0.5, reasons=("rule lane lost", "note", "rule dark")),
            command("EMERGENCY", 0.8, "HIGH", "STOP", 0.0, Cause.COLLISION, ("rule obstacle", "x", "y", "z", "w")),
            command("EMERGENCY", 0.7, "HIGH", "CRAWL", 0.3, None),
            command("EMERGENCY", 0.9, "VERY_HIGH", "STOP", 0.0, Cause.COLLISION),
            None,
            command("CAUTION", 0.0, "MEDIUM"),
        ]
        for k, cmd in enumerate(script):
            rec.frame(k, k / 10, cmd)
    assert rec.log_path is None and rec.write_summary({"a": 1}) is None and rec.plot_timeline() is None
    s = rec.stats
    assert s.frames == 7 and s.supervised_frames == 6
    assert s.mode_share == pytest.approx({"NORMAL": 2 / 6, "CAUTION": 1 / 6, "EMERGENCY": 3 / 6})
    assert s.fear_level_share == pytest.approx({"VERY_LOW": 0.0, "LOW": 1 / 6, "MEDIUM": 2 / 6, "HIGH": 2 / 6, "VERY_HIGH": 1 / 6})
    (ep,) = s.emergency_episodes
    assert (ep.start_frame, ep.end_frame, ep.start_t_s, ep.end_t_s) == (2, 4, 0.2, 0.4)
    assert ep.causes == {"collision": 2, "fault": 1} and ep.strategies == {"STOP": 2, "CRAWL": 1} and ep.cause == "collision"
    assert ep.min_speed_limit_mps == 0.0 and ep.first_reasons == ("rule obstacle", "x", "y", "z")
    first, second = s.elevated_fear
    assert (first.start_t_s, first.end_t_s, first.peak_fear, first.peak_t_s) == (0.1, 0.4, 0.9, 0.4)
    assert first.causes == {"road": 1, "collision": 2, "fault": 1}
    assert second.peak_t_s is None and second.why is None  # fear 0.0 never rose above the start
    assert s.fear_mean == pytest.approx(3.0 / 6) and s.fear_max == 0.9
    data = s.to_json()
    assert data["emergency_episodes"][0]["cause"] == "collision" and list(data["emergency_episodes"][0]) == [
        "start_frame", "start_t_s", "causes", "strategies", "min_speed_limit_mps", "end_frame", "end_t_s", "first_reasons", "cause"]
    assert data["elevated_fear"][0]["why"] == ["rule a"] and "peak_t_s" not in data["elevated_fear"][1]
    assert data["elevated_fear"][0]["cue_at_peak"]["obstacle_range_m"] == "inf"
    json.dumps(data, allow_nan=False)


def test_an_open_episode_is_included_as_it_stands() -> None:
    rec = Recorder(None, fps=10.0)
    rec.frame(0, 0.0, command("EMERGENCY", 0.8, "HIGH", "STOP", 0.0))
    assert len(rec.stats.emergency_episodes) == 1 and len(rec.stats.elevated_fear) == 1
    rec.frame(1, 0.1, command("EMERGENCY", 0.9, "HIGH", "STOP", math.nan))
    assert rec.stats.emergency_episodes[0].min_speed_limit_mps == 0.0


def test_a_run_without_a_supervisor_summarises_to_its_frame_count() -> None:
    rec = Recorder(None, fps=10.0, video=True)  # nothing on disk: no video either
    assert rec.video_path is None
    assert rec.stats.to_json() == {"frames": 0} and rec.stats.fear_mean is None and rec.stats.fear_max is None
    rec.frame(0, 0.0, None, speed_mps=1.0)
    assert rec.stats == CommandStats(1, 0, rec.stats.fear_level_share, rec.stats.mode_share, (), (), None, None)
    assert rec.stats.to_json() == {"frames": 1}
    assert math.isnan(rec.trace.fear[0]) and rec.trace.speed_mps == [1.0] and rec.trace.mode == [None]


def test_the_video_frame_is_written_before_the_log_line(tmp_path: Path) -> None:
    with Recorder(tmp_path, fps=10.0, video=True, video_kind="h264") as rec:
        for k in range(6):
            rec.frame(k, k / 10, command() if k % 2 else None, image=frame(k), caption=f"k {k}")
            logged = len((tmp_path / "log.jsonl").read_text().splitlines())
            assert count_frames(rec.video_path) >= logged - 1  # what a kill at this moment would leave
        rec.frame(6, 0.6, command(), image=None)  # no image: logged, not in the video
    assert rec.video_path == tmp_path / "annotated.mp4" and count_frames(rec.video_path) == 6
    assert rec.frames == 7


def test_a_video_of_mixed_frame_sizes_keeps_every_frame(tmp_path: Path) -> None:
    with Recorder(tmp_path, fps=10.0, video=True, video_kind="mjpg") as rec:
        for k, (w, h) in enumerate([(64, 48), (32, 24), (64, 48), (100, 30)]):
            rec.frame(k, k / 10, command(), image=np.full((h, w, 3), 90, np.uint8))
    assert rec.video_path == tmp_path / "annotated.avi" and rec.video_frames_rescaled == 2
    assert count_frames(rec.video_path) == 4


def test_summary_is_written_atomically_and_plain_json(tmp_path: Path) -> None:
    rec = Recorder(tmp_path, fps=10.0)
    path = rec.write_summary({"x": math.nan, "y": math.inf, "z": (1, 2)})
    assert path == tmp_path / "summary.json" and json.loads(path.read_text()) == {"x": None, "y": "inf", "z": [1, 2]}
    assert not list(tmp_path.glob(".*.tmp"))
    assert write_json(tmp_path / "list.json", [1.0, math.nan]).read_text() == "[\n  1.0,\n  null\n]\n"
    rec.close()


def test_the_timeline_is_plotted_from_memory(tmp_path: Path) -> None:
    guard = FearGuard(lambda f: 0.0)
    rec = Recorder(tmp_path, fps=10.0)
    assert rec.plot_timeline() is None  # nothing recorded yet
    for k in range(5):
        rec.frame(k, k / 10, guard.step(Observation(t_s=k / 10, speed_mps=1.0, cues=CALM)), speed_mps=1.0)
    rec.close()
    (tmp_path / "log.jsonl").unlink()  # the plot does not read the log back
    path = rec.plot_timeline("five frames", with_speed=True)
    assert path == tmp_path / "timeline.png" and path.stat().st_size > 10_000
    assert rec.plot_timeline("without the speed").stat().st_size > 10_000


def test_episode_and_elevated_values_are_frozen() -> None:
    ep = Episode(0, 0.0, 1, 0.1, {"road": 2}, {"STOP": 2}, 0.0, ())
    st = Elevated(0.0, 0.1, 0.5, {"road": 2}, 0.1, {}, ("rule x",))
    with pytest.raises(AttributeError):
        ep.start_frame = 3  # type: ignore[misc]
    assert st.to_json()["why"] == ["rule x"]
