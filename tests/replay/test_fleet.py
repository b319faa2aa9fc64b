"""``fearguard replay REC1 REC2 ...``: a fleet of real recordings as a plan of replay rows (replay/fleet.py), one folder
each, replays.md / replays.json; the same rows one after the other and on Dask workers; one recording as before."""

from __future__ import annotations

import json
from pathlib import Path

import pytest
from tests.conftest import SHARED_DATA

from fearguard.cli import main
from fearguard.drive.plan import run_row
from fearguard.replay.fleet import key_numbers, merge, plan, replay_options, top_causes

VIDEOS = [SHARED_DATA / "road" / "video" / name for name in ("solidWhiteRight.mp4", "solidYellowLeft.mp4")]
MODEL_CAR = SHARED_DATA / "modelcar" / "deeppicar-tape" / "video01.avi"  # a model car that loses its tape lane: EMERGENCY
CUT = ["--to", "2s", "--no-plots"]  # 2 s of each recording


@pytest.fixture(scope="module")
def recordings(shared_data: Path) -> list[str]:
    return [str(p) for p in (*VIDEOS, MODEL_CAR)]


def _rows(out: Path) -> list[dict]:
    """runs.jsonl without the timing field (frames per second of this machine) and the folders (each fleet has its own)."""
    rows = [json.loads(line) for line in (out / "runs.jsonl").read_text().splitlines()]
    return [{k: v for k, v in r.items() if k not in ("processing_fps", "folder", "spec")} for r in rows]


def test_a_fleet_writes_a_folder_per_recording_and_the_table(recordings: list[str], tmp_path: Path, capsys) -> None:
    assert main(["replay", *recordings, "--out", str(tmp_path), *CUT]) == 0
    out = capsys.readouterr().out
    for name in ("solidWhiteRight", "solidYellowLeft", "video01"):
        assert (tmp_path / name / "log.jsonl").is_file() and (tmp_path / name / "summary.json").is_file()
    data = json.loads((tmp_path / "replays.json").read_text())
    rows = {Path(r["recording"]).name: r for r in data["recordings"]}
    assert [Path(r["recording"]).name for r in data["recordings"]] == [Path(r).name for r in recordings]  # plan order
    car = rows["video01.avi"]
    assert car["emergency_episodes"] >= 1 and car["mode_s"]["EMERGENCY"] > 0 and top_causes(car)[0][0] == "road"
    assert rows["solidWhiteRight.mp4"]["frames"] == 50 and rows["solidWhiteRight.mp4"]["duration_s"] == pytest.approx(2.0)
    assert data["totals"]["recordings"] == 3 and data["totals"]["failed"] == 0
    table = (tmp_path / "replays.md").read_text()
    assert "| **3 recordings** |" in table and "road " in table and table in out
    assert car["lane_seen_share"] < 0.2 and car["eyes_advice"] and rows["solidWhiteRight.mp4"]["eyes_advice"] is None
    note = next(line for line in table.splitlines() if line.startswith("note: "))
    assert "video01" in note and "solidWhiteRight" not in note and "fearguard learn" in note  # the model car's, not the road's
    assert 0.0 <= data["totals"]["lane_seen_share"] <= 1.0
    summary = json.loads((tmp_path / "video01" / "summary.json").read_text())  # the row holds the summary's numbers
    assert {k: v for k, v in key_numbers(summary).items() if k != "processing_fps"} == \
           {k: v for k, v in car.items() if k in key_numbers(summary) and k != "processing_fps"}


@pytest.mark.slow
def test_a_fleet_on_two_dask_workers_gives_the_serial_rows(recordings: list[str], tmp_path: Path, dask_cluster) -> None:
    """``--scheduler``: the session's real scheduler and two workers (tests/conftest.py)."""
    assert main(["replay", *recordings, "--out", str(tmp_path / "serial"), *CUT]) == 0
    assert main(["replay", *recordings, "--out", str(tmp_path / "dask"), *CUT, "--scheduler", dask_cluster.address]) == 0
    serial, dask = (sorted(map(json.dumps, _rows(tmp_path / name))) for name in ("serial", "dask"))  # runs.jsonl: arrival order
    assert len(dask) == 3 and dask == serial
    assert (tmp_path / "dask" / "replays.md").read_text() == (tmp_path / "serial" / "replays.md").read_text()


def test_an_unreadable_recording_is_a_row_with_its_error_and_the_fleet_goes_on(recordings: list[str], tmp_path: Path) -> None:
    missing = str(tmp_path / "no_such_video.mp4")
    assert main(["replay", recordings[0], missing, "--out", str(tmp_path / "out"), *CUT]) == 1
    data = json.loads((tmp_path / "out" / "replays.json").read_text())
    assert data["totals"]["failed"] == 1 and data["recordings"][0]["frames"] == 50
    assert "SourceError" in data["recordings"][1]["error"] and "could not be replayed" in (tmp_path / "out" / "replays.md").read_text()


def test_resume_replays_only_the_recordings_not_done(recordings: list[str], tmp_path: Path) -> None:
    assert main(["replay", *recordings[:2], "--out", str(tmp_path), *CUT]) == 0
    first = (tmp_path / "solidWhiteRight" / "log.jsonl").stat().st_mtime_ns
    assert main(["replay", *recordings, "--out", str(tmp_path), *CUT, "--resume"]) == 0
    assert (tmp_path / "solidWhiteRight" / "log.jsonl").stat().st_mtime_ns == first  # not replayed again
    assert (tmp_path / "video01" / "log.jsonl").is_file() and len(_rows(tmp_path)) == 3


def test_one_recording_keeps_the_single_replay_and_its_outputs(recordings: list[str], tmp_path: Path, capsys) -> None:
    assert main(["replay", recordings[0], "--out", str(tmp_path), *CUT]) == 0
    assert sorted(p.name for p in tmp_path.iterdir()) == ["log.jsonl", "summary.json"]  # no fleet files, no subfolder
    assert capsys.readouterr().out.startswith("frames 50")


def test_a_sensor_log_belongs_to_one_recording(recordings: list[str], tmp_path: Path, capsys) -> None:
    assert main(["replay", *recordings[:2], "--sensor-log", "log.csv", "--out", str(tmp_path)]) == 2
    assert "--sensor-log belongs to one recording" in capsys.readouterr().err
    assert main(["replay", *recordings[:2], "--rules", "nope.toml", "--out", str(tmp_path / "x")]) == 2  # checked before any replay
    assert not (tmp_path / "x").exists()


def test_the_plan_names_each_recording_its_own_folder_and_a_worker_rebuilds_the_options(tmp_path: Path) -> None:
    specs = plan(["a/tub_1", "b/tub_1/", "c.mp4"], tmp_path, {"vehicle": "donkey", "every": 2, "rules": None,
                                                                "topics": {"image": "/cam", "range": None, "speed": None, "qr": None}})
    assert [Path(s.options["folder"]).name for s in specs] == ["tub_1", "tub_1-2", "c"]
    assert len({s.key for s in specs}) == 3 and all(Path(s.options["recording"]).is_absolute() for s in specs)
    options = replay_options(specs[0].options)
    assert options.every == 2 and options.vehicle.max_speed_mps == 2.0 and options.topics.image == "/cam" and options.steer is None


def test_key_numbers_and_the_table_from_a_summary() -> None:
    summary = {"processed_frames": 40, "fps": 20.0, "mode_share": {"NORMAL": 0.5, "EMERGENCY": 0.5},
               "emergency_episodes": [{"causes": {"road": 10, "collision": 4}}, {"causes": {"road": 6}}],
               "elevated_fear": [{"causes": {"road": 30}}], "fear_mean": 0.4, "fear_max": 0.9, "processing_fps": 99.0}
    row = key_numbers(summary, every=1)
    assert row["duration_s"] == 2.0 and row["mode_s"] == {"NORMAL": 1.0, "CAUTION": 0.0, "EMERGENCY": 1.0}
    assert row["emergency_causes"] == {"road": 0.8, "collision": 0.2} and top_causes(row) == [("road", 0.8), ("collision", 0.2)]
    calm = key_numbers({"processed_frames": 0}, every=1)
    assert calm["duration_s"] == 0.0 and top_causes(calm) == []
    data, markdown = merge([{"recording": "r1", "folder": "x", **row}, {"recording": "r2", "folder": "y", "error": "SourceError: bad"}])
    assert data["totals"]["failed"] == 1 and data["totals"]["frames"] == 40 and "road 0.8 s, collision 0.2 s" in markdown


def test_a_replay_row_runs_through_the_plan(recordings: list[str], tmp_path: Path) -> None:
    spec = plan([recordings[0]], tmp_path, {"stop": "1s", "plots": False})[0]
    row = run_row(spec)
    assert row["spec"]["world"] == "replay" and row["frames"] == 25 and (tmp_path / "solidWhiteRight" / "summary.json").is_file()
