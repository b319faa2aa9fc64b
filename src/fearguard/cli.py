"""Command line: ``demo``, ``rules check|plot|explain``, ``calibrate``, ``replay``, ``run``, ``scenarios``, ``suite``, ``sweep``,
``verify``, ``duckietown``, ``duckietown-suite``, ``metadrive``, ``metadrive-suite``.

A thin layer: it parses arguments, calls the library, prints, and maps errors to exit codes
(0 fine, 1 a check failed, 2 bad input: ``Type: message`` on stderr, 130 / 143 interrupted by SIGINT /
SIGTERM). Signals follow one policy (``interrupt.py``): the frame loops (replay, run, suite) finish the
current frame and write everything with ``"interrupted": true``; other commands stop at once. The
library is imported only after the handlers are installed, so a Ctrl-C during start-up is handled too.
Every ``--out`` is optional: without it the output goes to a new timestamped folder under
``./fearguard-out/`` and the command prints where. Warnings are one line on stderr (``warning: ...``).
"""

from __future__ import annotations

import argparse
import importlib
import math
import sys
import time
import warnings
from collections.abc import Callable, Sequence
from pathlib import Path
from typing import TYPE_CHECKING, Any

from fearguard.drive.interrupt import StopSignal, stop_on_signals
from fearguard.errors import FearguardError
from fearguard.lane import GUIDANCE, MARKINGS
from fearguard.vehicle import PRESETS

SIM_CONTROLLERS = ("guarded", "unguarded", "crisp", "aeb")  # sim.loop.CONTROLLERS, in its order (tests/test_cli_habits.py holds
#   them equal; importing the simulator here would cost every command its import)

if TYPE_CHECKING:
    from fearguard.cues import Cues
    from fearguard.observation import Lead
    from fearguard.supervisor import FearGuard

FRAME_LOOPS = ("replay", "run", "suite", "sweep", "metadrive", "metadrive-suite")  # commands that finish the current frame on a signal
MCAP_HELP = "also write run.mcap for Foxglove: the annotated image, the command, the cues and the reasons (the ros extra)"
VIDEO_HELP = "also write the annotated video (annotated.mp4, H.264; annotated.avi, MJPG, without the video extra)"
OUT_ROOT = Path("fearguard-out")  # where a command writes when --out is not given: OUT_ROOT/COMMAND-LABEL-YYYYmmdd-HHMMSS
OUT_HELP = "(default: a new folder fearguard-out/%s-...-TIMESTAMP)"

EXPLAIN_SETTLE_S = 10.0  # [s] explain shows the command after this long with the same cues
EXPLAIN_RATE_HZ = 10.0  # [Hz] frame rate of that settling run


def _parse_cues(text: str, brightness_band: tuple[float, float]) -> Cues:
    """NAME=VALUE,... over the calm picture (``cues.calm_values``: brightness in the middle of the rules' band)."""
    from fearguard.cues import CUE_NAMES, Cues, calm_values

    values = dict(zip(CUE_NAMES, calm_values(brightness_band), strict=True))
    for item in filter(None, (p.strip() for p in text.split(","))):
        name, sep, raw = item.partition("=")
        if not sep or name.strip() not in CUE_NAMES:
            raise FearguardError(f"--cues: {item!r} is not NAME=VALUE with NAME one of {', '.join(CUE_NAMES)}")
        try:
            values[name.strip()] = float(raw)
        except ValueError:
            raise FearguardError(f"--cues: {name.strip()}={raw!r} is not a number (nan and inf are allowed)") from None
    return Cues(**values)


def _settle(guard: FearGuard, cues: Cues, lead: Lead | None) -> object:
    """Run the guard on constant cues, the car driving at the limit, and return the last command."""
    from fearguard.observation import Observation

    speed, cmd = 0.0, None
    for k in range(int(EXPLAIN_SETTLE_S * EXPLAIN_RATE_HZ) + 1):
        cmd = guard.step(Observation(t_s=k / EXPLAIN_RATE_HZ, speed_mps=speed, cues=cues, lead=lead))
        speed = cmd.speed_limit_mps
    return cmd


def cmd_check(args: argparse.Namespace) -> int:
    from fearguard.fuzzy.check import check_rules
    from fearguard.fuzzy.loader import load_rules

    report = check_rules(load_rules(args.file))
    print("\n".join(report.lines()))
    return 0 if report.ok else 1


def cmd_plot(args: argparse.Namespace) -> int:
    from fearguard.fuzzy.loader import load_rules

    plot_rules = _desktop("fearguard.outputs.plot", "plots").plot_rules

    for path in plot_rules(load_rules(args.file), args.out or _new_out("rules-plot", Path(args.file or "default").stem)):
        print(path)
    return 0


def cmd_explain(args: argparse.Namespace) -> int:
    from fearguard.cues import CUE_NAMES
    from fearguard.fuzzy.loader import load_rules
    from fearguard.observation import Lead
    from fearguard.supervisor import FearGuard

    rules = load_rules(args.rules)
    cues = _parse_cues(args.cues, rules.brightness_band)
    result = rules.evaluate(cues)
    print("cues:  " + ", ".join(f"{n}={getattr(cues, n):g}" for n in CUE_NAMES))
    print(f"fear:  {result.fear:.3f}  level {result.level.name}  dominant cause {result.dominant_cause.value}")
    print("groups: " + ", ".join(f"{g}={f:.3f}" for g, f in result.group_fears.items()))
    print("top rules:")
    for text, strength in result.top_rules(args.top):
        print(f"  {strength:.2f}  {text}")
    lead = Lead(args.lead_bearing, args.lead_range) if args.lead_bearing is not None else None
    cmd = _settle(FearGuard(lambda frame: 0.0, rules=rules, vehicle=PRESETS["model_car"]), cues, lead)  # every cue applies
    print(f"command after {EXPLAIN_SETTLE_S:g} s with these cues (steering function says 0 deg):")
    print(f"  mode {cmd.mode.name}, strategy {cmd.strategy.name}, speed limit {cmd.speed_limit_mps:.2f} m/s, "
          f"steering {cmd.steering_deg:+.1f} deg")
    for reason in cmd.reasons:
        print(f"  - {reason}")
    return 0


def cmd_demo(args: argparse.Namespace) -> int:
    """A scripted cue-level drive through each hazard: what the supervisor does, frame by frame."""
    from fearguard.demo import demo_drive
    from fearguard.fuzzy.loader import load_rules

    for line in demo_drive(load_rules(args.rules)):
        print(line)
    return 0


def cmd_calibrate(args: argparse.Namespace) -> int:
    """Chessboard photos → camera.toml: found/missed per image, the RMS reprojection error, the intrinsics."""
    from dataclasses import replace

    from fearguard.camera import save_camera
    from fearguard.vision.calibration import CalibrationError, calibrate_chessboard, expand_image_paths, parse_pattern

    pattern = parse_pattern(args.pattern)
    paths = expand_image_paths(args.images)
    out = args.out or str(_new_out("calibrate", args.pattern) / "camera.toml")  # a given --out's folder must exist
    with _Progress("calibrate", unit="images") as progress:
        result = calibrate_chessboard(paths, pattern, args.square_m, args.mount_height_m, args.pitch_deg, on_image=progress.update)
    lines = {p: f"found   {e:.2f} px" for p, e in zip(result.found, result.per_image_error_px, strict=True)}
    lines |= {p: f"missed  {why}" for p, why in zip(result.missed, result.missed_reasons, strict=True)}
    width = max(len(p.name) for p in paths)
    for path in dict.fromkeys(paths):
        print(f"{path.name:<{width}}  {lines[path]}")
    for note in result.notes:
        print(f"note: {note}")
    cam = replace(result.camera, front_offset_m=args.front_offset_m)
    print(f"board found in {len(result.found)} of {len(lines)} images; RMS reprojection error {result.rms_px:.3f} px")
    dist = " ".join(f"{k} {v:+.4f}" for k, v in zip(("k1", "k2", "p1", "p2", "k3"), cam.distortion, strict=False))
    print(f"camera {cam.width_px}x{cam.height_px}: fx {cam.fx_px:.1f} fy {cam.fy_px:.1f} cx {cam.cx_px:.1f} cy {cam.cy_px:.1f} px; {dist}")
    try:
        if not args.out:
            Path(out).parent.mkdir(parents=True, exist_ok=True)
        save_camera(cam, out)
    except OSError as exc:
        raise CalibrationError(f"--out {out}: cannot write it ({exc.strerror}); choose a writable path") from exc
    print(f"wrote {Path(out)}")
    return 0


def _desktop(module: str, what: str) -> Any:
    """A module of the desktop extra (matplotlib, rich), or a FearguardError saying how to install it."""
    try:
        return importlib.import_module(module)
    except ModuleNotFoundError as exc:
        raise FearguardError(f"{what} need {exc.name} ({exc}): pip install 'fearguard[desktop]'") from None


def _new_out(command: str, label: str) -> Path:
    """A fresh output folder for a command run without --out: fearguard-out/COMMAND-LABEL-YYYYmmdd-HHMMSS[-N]."""
    stem = OUT_ROOT / f"{command}-{Path(label).stem or command}-{time.strftime('%Y%m%d-%H%M%S')}"
    path, n = stem, 1
    while path.exists():
        n += 1
        path = stem.with_name(f"{stem.name}-{n}")
    return path


PLAIN_STEPS_MAX = 100  # [steps] without a terminal, a line per step up to this many steps (runs, images, invariants) ...
PLAIN_LINES = 20  # [lines] ... and for longer jobs (frames) a line every 1/20 of the job (5 %), or per PLAIN_UNKNOWN_EVERY
PLAIN_UNKNOWN_EVERY = 500  # [steps] a line every this many steps when the total is unknown


def plain_line_due(done: int, total: int | None) -> bool:
    """Whether a job's progress earns a line of its own in a log (stderr no terminal): a line per step for short jobs, every
    5 % for long ones, the last step always; step counts, not the clock, so a log reads the same on any machine."""
    if total is None or total <= 0:
        return done > 0 and done % PLAIN_UNKNOWN_EVERY == 0
    if total <= PLAIN_STEPS_MAX or done >= total:
        return done > 0
    return done * PLAIN_LINES // total != (done - 1) * PLAIN_LINES // total


class _Progress:
    """A progress bar on stderr (rich's; without rich a plain line redrawn in place); without a terminal (a CI log, a pipe,
    nohup) one line per step for short jobs and every 5 % for long ones (``plain_line_due``)."""

    def __init__(self, label: str, unit: str = "frames") -> None:
        self._label, self._unit, self._start = label, unit, time.perf_counter()
        self._drawn: float | None = None  # when the plain line was last drawn
        self._bar: Any = None
        self._live = sys.stderr.isatty()
        try:
            import rich.progress
            from rich.console import Console
        except ModuleNotFoundError:  # the core install has no rich: the plain line below
            return
        console = Console(stderr=True)
        self._bar = rich.progress.Progress(*self._columns(rich.progress), console=console, disable=not console.is_terminal,
                                           transient=False)
        self._task = self._bar.add_task(label, total=None, **self._fields())

    def _columns(self, p: Any) -> list[Any]:
        """The bar's columns (``p``: rich.progress)."""
        return [p.TextColumn(self._label), p.BarColumn(), p.MofNCompleteColumn(), p.TextColumn("{task.fields[rate]}"),
                p.TimeRemainingColumn()]

    def _fields(self) -> dict[str, Any]:
        return {"rate": ""}

    def __enter__(self) -> _Progress:
        if self._bar is not None:
            self._bar.__enter__()
        return self

    def __exit__(self, *exc: object) -> None:
        if self._bar is not None:
            self._bar.__exit__(None, None, None)
        elif self._live and self._drawn is not None:
            print(file=sys.stderr)

    def update(self, done: int, total: int | None) -> None:
        elapsed = time.perf_counter() - self._start
        rate = f"{done / elapsed:.{0 if self._unit == 'frames' else 2}f} {self._unit}/s" if elapsed > 0 and done else ""
        if not self._live:
            if plain_line_due(done, total):
                share = f" ({100 * done / total:.0f} %)" if total else ""
                print(f"{self._label}: {done}{f'/{total}' if total else ''} {self._unit}{share} {rate}".rstrip(), file=sys.stderr,
                      flush=True)
        elif self._bar is not None:
            self._bar.update(self._task, completed=done, total=total, rate=rate)
        elif self._live and (self._drawn is None or elapsed - self._drawn >= 0.5 or done == total):
            self._drawn = elapsed
            print(f"\r{self._label}: {done}{f'/{total}' if total else ''} {self._unit} {rate}   ", end="", file=sys.stderr, flush=True)


class _RunProgress(_Progress):
    """Progress over the runs of a plan (suite, sweep, fleet replay, duckietown-suite): runs done of the plan, failures,
    the time left and the workers running them; without a terminal a line per finished run, naming it and how it went.
    Resumed runs count as done; the time left is estimated from the runs finished in this session."""

    def __init__(self, label: str, executor: Any = None, *, line: Callable[[dict], str], failed: Callable[[dict], bool]) -> None:
        self._executor, self._line, self._failed = executor, line, failed
        self._failures, self._last, self._first_done = 0, "", None
        super().__init__(label, unit="runs")

    def _columns(self, p: Any) -> list[Any]:
        return [p.TextColumn(self._label), p.BarColumn(), p.MofNCompleteColumn(), p.TextColumn("{task.fields[failed]} failed"),
                p.TextColumn("{task.fields[workers]}"), p.TimeRemainingColumn()]

    def _fields(self) -> dict[str, Any]:
        return {"failed": 0, "workers": ""}

    @property
    def workers(self) -> str:
        """The workers running the rows: the cluster's, or this process."""
        n = int(getattr(self._executor, "workers", 1))
        return f"{n} worker{'s' if n != 1 else ''}"

    def row(self, row: dict) -> None:
        """A run finished (``run_plan``'s on_row): its line and whether it failed; ``update`` follows."""
        self._failures += bool(self._failed(row))
        self._last = self._line(row)

    def update(self, done: int, total: int | None) -> None:
        """``run_plan``'s on_progress: runs done (resumed ones included) of the plan's."""
        elapsed = time.perf_counter() - self._start
        first = self._first_done is None
        if first:
            self._first_done = done
        new = done - (self._first_done or 0)
        if self._bar is not None and self._live:
            if first:  # the resumed runs are no speed: the time left counts from here
                self._bar.reset(self._task, total=total, completed=done)
            self._bar.update(self._task, completed=done, total=total, failed=self._failures, workers=self.workers)
            return
        left = f", {_duration(elapsed / new * ((total or done) - done))} left" if new and done != total else ""
        text = f"{self._label}: {done}/{total} runs, {self._failures} failed, {self.workers}{left}"
        if self._live:
            self._drawn = elapsed
            print(f"\r{text}   ", end="", file=sys.stderr, flush=True)
        elif new or done:
            print(text + (f": {self._last}" if new else " (resumed)"), file=sys.stderr, flush=True)


def _duration(seconds: float) -> str:
    """A time left for a person: 45 s, 12 min, 2.5 h."""
    if seconds < 90:
        return f"{seconds:.0f} s"
    return f"{seconds / 60:.0f} min" if seconds < 5400 else f"{seconds / 3600:.1f} h"


def cmd_replay(args: argparse.Namespace) -> int:
    """A recorded drive → log.jsonl, summary.json, timeline.png (and annotated.mp4): where and why fear rose."""
    from fearguard.files.steer_import import resolve_steer
    from fearguard.replay.bags import BagTopics
    from fearguard.replay.run import ReplayOptions, replay
    from fearguard.vehicle import resolve_vehicle

    if (args.markings is not None or args.guidance is not None) and args.steer is not None:
        raise FearguardError("--markings and --guidance set the built-in lane model's; your own steering (--steer) finds its own")
    if len(args.recordings) > 1:
        return _replay_fleet(args)
    args.recording = args.recordings[0]
    steer, _ = resolve_steer(args.steer)
    options = ReplayOptions(
        rules=args.rules, camera=args.camera, sensor_log=args.sensor_log, strict=args.strict, no_ultrasonic=args.no_ultrasonic,
        qr_localisation=args.qr_localisation, speed_mps=args.speed_mps, fps=args.fps, start=args.from_, stop=args.to,
        every=args.every, video=args.video, plots=not args.no_plots, vehicle=resolve_vehicle(args.vehicle), steer=steer,
        mcap=args.mcap, topics=BagTopics(args.image_topic, args.range_topic, args.speed_topic, args.qr_topic), track=args.track,
        markings=args.markings, guidance=args.guidance,
    )
    out = args.out or _new_out("replay", args.recording.rstrip("/\\"))
    with _Progress("replay") as progress:
        result = replay(args.recording, out, options, on_frame=progress.update, stop=args.stop)
    _print_replay_summary(result.summary, result.out_dir)
    return _interrupted_exit(args.stop) if result.interrupted else 0


def _replay_fleet(args: argparse.Namespace) -> int:
    """Several recordings → one folder each under --out, replays.md / replays.json: the fleet as a plan of replay rows
    (``replay/fleet.py``), one after the other or on Dask; exit 1 if a recording could not be replayed."""
    from fearguard.camera import load_camera
    from fearguard.drive.suite import run_plan
    from fearguard.files.steer_import import resolve_steer
    from fearguard.fuzzy.loader import load_rules
    from fearguard.outputs.recorder import write_json
    from fearguard.replay import fleet
    from fearguard.vehicle import resolve_vehicle

    if args.sensor_log is not None:
        raise FearguardError("replay: --sensor-log belongs to one recording; replay a fleet of recordings that carry their own "
                             "sensors (ROS bags, Donkey tubs), or each recording with its log on its own")
    executor = _executor(args)
    load_rules(args.rules), resolve_vehicle(args.vehicle), resolve_steer(args.steer)  # a bad option fails before any replay
    if args.camera:
        load_camera(args.camera)
    out = Path(args.out) if args.out else _new_out("replay", f"fleet-{len(args.recordings)}")
    out.mkdir(parents=True, exist_ok=True)
    options = {"rules": args.rules, "camera": args.camera, "strict": args.strict, "no_ultrasonic": args.no_ultrasonic,
               "qr_localisation": args.qr_localisation, "speed_mps": args.speed_mps, "fps": args.fps, "start": args.from_,
               "stop": args.to, "every": args.every, "video": args.video, "plots": not args.no_plots, "mcap": args.mcap,
               "vehicle": args.vehicle, "steer": args.steer, "track": args.track, "markings": args.markings,
               "guidance": args.guidance,
               "topics": {"image": args.image_topic, "range": args.range_topic, "speed": args.speed_topic, "qr": args.qr_topic}}
    specs = fleet.plan(args.recordings, out, options)
    print(f"replay: {len(specs)} recordings → {out}{_on(executor)}", file=sys.stderr)
    with _RunProgress("replay", executor, line=_fleet_line, failed=lambda r: "error" in r) as bar:
        result = run_plan(specs, runs_log=out / "runs.jsonl", resume=args.resume, stop=args.stop, executor=executor,
                          on_row=bar.row, on_progress=bar.update)
    data, markdown = fleet.merge(result.rows)
    (out / "replays.md").write_text(markdown, encoding="utf-8")
    write_json(out / "replays.json", {"interrupted": result.interrupted, "planned": result.planned, **data})
    print(markdown)
    print(f"wrote {out}/replays.md, replays.json, runs.jsonl and a folder per recording ({len(result.rows)} of {result.planned})")
    if result.interrupted:
        print(f"interrupted by {result.stopped_by}: run the same command with --resume to replay the rest")
        return _interrupted_exit(args.stop)
    return 1 if data["totals"]["failed"] else 0


def _fleet_line(row: dict) -> str:
    if "error" in row:
        return f"{row['recording']}: {row['error']}"
    emergency = row["mode_s"]["EMERGENCY"]
    return f"{row['recording']}: {row['frames']} frames, EMERGENCY {emergency:.1f} s, {row['emergency_episodes']} episode(s)"


def _interrupted_exit(stop: StopSignal) -> int:
    """128 + the signal's number (130 for a KeyboardInterrupt raised without a handler)."""
    return stop.exit_code or 130


def _print_replay_summary(summary: dict, out_dir: object) -> None:
    levels = summary.get("fear_level_share", {})
    modes = summary.get("mode_share", {})
    fps = summary.get("processing_fps")
    total, selected = summary.get("expected_frames"), summary.get("selected_frames")
    of = f" of {selected}" if selected is not None else ""
    if total is not None and selected != total:
        of += f" selected by --from/--to/--every ({total} in the recording)"
    rate = f" ({fps:.0f} frames/s)" if fps else ""
    print(f"frames {summary.get('processed_frames', 0)}{of}{rate}")
    print("fear level  " + "  ".join(f"{k} {100 * v:.0f}%" for k, v in levels.items()))
    print("mode        " + "  ".join(f"{k} {100 * v:.0f}%" for k, v in modes.items()))
    episodes = summary.get("emergency_episodes", [])
    print(f"emergency episodes: {len(episodes)}")
    for ep in episodes[:10]:
        print(f"  {ep['start_t_s']:.2f}–{ep['end_t_s']:.2f} s  cause {ep['cause']}  {'; '.join(ep.get('first_reasons', [])[:2])}")
    for st in summary.get("elevated_fear", [])[:10]:
        print(f"  fear ≥ MEDIUM {st['start_t_s']:.2f}–{st['end_t_s']:.2f} s, peak {st['peak_fear']:.2f}: {'; '.join(st.get('why', []))}")
    if summary.get("stopped_early"):
        print(f"note: {summary['stopped_early']}")
    if summary.get("recording_pauses"):
        pauses = summary["recording_pauses"]
        longest = max(pauses, key=lambda p: p["paused_s"])
        print(f"note: {len(pauses)} recording pause(s) (a Donkey tub records only while the car drives): the supervisor "
              f"started afresh after each; longest {longest['paused_s']:.1f} s before frame {longest['frame']}")
    advice = (summary.get("eyes_check") or {}).get("advice")
    if advice:
        print(f"note: {advice}")
    if summary.get("skipped"):
        print(f"note: {len(summary['skipped'])} frame(s) skipped, first: {summary['skipped'][0]['reason']}")
    for issue in summary.get("sensor_log_issues", [])[:10]:
        print(f"sensor log line {issue['line']}: {issue['problem']} (skipped)")
    if summary.get("interrupted"):
        print(f"interrupted{_by(summary)}: the log holds every frame processed so far")
    plotted = summary.get("frames") and not summary.get("interrupted") and (Path(str(out_dir)) / "timeline.png").is_file()
    print(f"wrote {out_dir}/log.jsonl, summary.json" + (", timeline.png" if plotted else ""))
    video = summary.get("video")
    if video:
        rescaled = f", {video['rescaled_frames']} frame(s) of another size scaled to the first" if video["rescaled_frames"] else ""
        print(f"video {video['path']} ({video['frames']} frames{rescaled})")
    if summary.get("mcap"):
        print(f"foxglove {summary['mcap']['path']} ({summary['mcap']['frames']} frames)")
    if summary.get("bag_topics"):
        print("bag topics: " + ", ".join(f"{role} {topic}" for role, topic in summary["bag_topics"].items()))


def _by(summary: dict) -> str:
    return f" by {summary['stopped_by']}" if summary.get("stopped_by") else ""


def cmd_learn(args: argparse.Namespace) -> int:
    """Recordings of normal driving → a track profile (.npz) and track.png beside it; prints what it learnt."""
    import numpy as np

    from fearguard.camera import load_camera
    from fearguard.track.floor import USUAL_SHARE
    from fearguard.track.learn import LearnOptions, learn_track
    from fearguard.track.light import LIGHT_PERCENTILES, grey_levels
    from fearguard.track.picture import draw_track
    from fearguard.track.profile import FAMILIAR_AT_REFERENCE, REFERENCE_PERCENTILE, UNFAMILIAR_RATIO, save_track

    options = LearnOptions(fps=args.fps, start=args.from_, stop=args.to, every=args.every,
                           camera=load_camera(args.camera) if args.camera else None)
    with _Progress("learn") as progress:
        learnt = learn_track(args.recordings, options, on_frame=lambda n: progress.update(n, None))
    out = save_track(learnt.profile, args.out)
    picture = draw_track(learnt, out.with_suffix(".png"))
    p = learnt.profile
    colours = ", ".join(f"BGR {tuple(int(v) for v in c)}" for c in p.marking_colours_bgr) or "none seen in most frames"
    lane = ("the camera's lane model sees this track" if p.lane_confidence_median >= 0.5 else
            "the camera's lane model does not see this track's guidance: the lane cue will read familiarity")
    print(f"learnt {p.frames_learnt} frames of {learnt.frames_read} read ({learnt.frames_standing} with the car standing or "
          f"backing left out, {learnt.skipped} unreadable)")
    print(f"  light: brightness band {p.brightness_band[0]:.0f}–{p.brightness_band[1]:.0f} (2nd–98th percentile)"
          + ("" if p.light is None else f"; grey at the {'/'.join(f'{q:g}' for q in LIGHT_PERCENTILES)}th percentiles typically "
             f"{'/'.join(f'{g:.0f}' for g in grey_levels(np.median(p.light.levels, axis=0)))}, reference distance "
             f"{p.light_reference:.3f}"))
    print(f"  lane: median confidence {p.lane_confidence_median:.2f} on the recordings, looking for {p.markings} markings "
          f"({'black or dark tape' if p.markings == 'dark' else 'paint or light tape'}), guided by "
          f"{p.guidance.replace('_', ' ')}: {lane}")
    print(f"  markings: {colours}")
    floor = p.floor
    print("  floor: none learnt" if floor is None else
          f"  floor: {len(floor.colours_lab)} colours, usually seen on {float((floor.usual >= USUAL_SHARE).mean()):.0%} of the "
          f"picture, {floor.hidden_usual:.2f} of it hidden on a typical frame")
    print(f"  familiarity: {p.bank.shape[0]} frames kept, {p.basis.shape[0]} components; fully familiar up to distance "
          f"{p.typical_distance:.3f} (the typical recorded frame), {FAMILIAR_AT_REFERENCE:.1f} at {p.reference_distance:.3f} "
          f"(the recordings' {REFERENCE_PERCENTILE:g}th percentile), 0 from {UNFAMILIAR_RATIO * p.reference_distance:.3f}")
    print(f"wrote {out} and {picture}")
    return 0


def cmd_run(args: argparse.Namespace) -> int:
    """One scenario closed loop → log.jsonl, summary.json, plots (and the video); exit 1 if an expectation fails."""
    from fearguard.sim.scenario import find_scenario, load_scenario
    from fearguard.sim.suite import run_to_folder

    scenario = load_scenario(find_scenario(args.scenario))
    controller = "unguarded" if args.unguarded else (args.baseline or "guarded")
    out = Path(args.out) if args.out else _new_out("run", f"{scenario.name}-{controller}")
    with _Progress(scenario.name) as progress:
        result = run_to_folder(scenario, out, args.seed, controller, args.video, progress.update, stop=args.stop, mcap=args.mcap,
                               track=args.track)
    m = result.metrics
    print(f"{scenario.name} ({controller}, seed {result.seed}): {result.frames} frames, {m.distance_m:.1f} m, "
          f"mean speed {m.mean_speed_mps or 0.0:.2f} m/s, collisions {m.collisions}, lane departures {m.lane_departures}, "
          f"emergency entries {m.emergency_entries}")
    if result.interrupted:
        by = f" by {result.stopped_by}" if result.stopped_by else ""
        print(f"interrupted{by} after {result.frames} frames: the expectations are not judged on a cut-short run "
              "(summary.json says interrupted, passed false)")
    else:
        for e in result.expectations:
            print(f"  {'n/a ' if e.ok is None else 'ok  ' if e.ok else 'FAIL'} {e.name}: {e.detail}")
    plots = "" if result.interrupted else (", timeline.png, trajectory.png" if controller == "guarded" else ", trajectory.png")
    print(f"wrote {out}/log.jsonl, summary.json{plots}")
    if result.video_path is not None:
        print(f"video {result.video_path}")
    if args.mcap:
        print(f"foxglove {out}/run.mcap")
    if result.interrupted:
        return _interrupted_exit(args.stop)
    return 0 if result.passed else 1


def cmd_suite(args: argparse.Namespace) -> int:
    """Every scenario guarded and with the baselines → a comparison table (markdown + JSON); exit 1 if guarded fails.

    Each finished run is appended to runs.jsonl at once; ``--resume`` skips the runs already there.
    """
    from fearguard.outputs.recorder import write_json
    from fearguard.sim.loop import CONTROLLERS
    from fearguard.sim.suite import row_line, run_suite, scenario_files, suite_markdown, suite_table, suite_totals

    files = scenario_files(args.folder)
    if not files:
        raise FearguardError(f"suite: no *.toml scenarios in {args.folder}; give a folder of scenario files")
    executor = _executor(args)  # before anything is written: without Dask, a one-line error
    out = Path(args.out) if args.out else _latest_suite() if args.resume else _new_out("suite", f"{args.seeds}seeds")
    out.mkdir(parents=True, exist_ok=True)
    controllers = [c for c in CONTROLLERS if c in (args.controllers or CONTROLLERS)]  # the table's order, each once
    print(f"suite: {len(files)} scenarios × {args.seeds} seed(s) × {', '.join(controllers)} → {out}{_on(executor)}", file=sys.stderr)
    with _RunProgress("suite", executor, line=row_line, failed=lambda r: r["controller"] == "guarded" and not r["passed"]) as bar:
        progress = run_suite(files, args.seeds, controllers, on_run=print if args.verbose else None, runs_log=out / "runs.jsonl",
                             resume=args.resume, stop=args.stop, on_progress=bar.update, executor=executor, on_row=bar.row)
    rows = progress.rows
    markdown = suite_markdown(rows, controllers)
    (out / "suite.md").write_text(markdown, encoding="utf-8")
    write_json(out / "suite.json", {"interrupted": progress.interrupted, "stopped_by": progress.stopped_by,
                                    "planned_runs": progress.planned, "finished_runs": len(rows), "resumed_runs": progress.resumed,
                                    "runs": rows, "table": suite_table(rows)})
    print(markdown)
    print("totals: " + "; ".join(
        f"{t['controller']} {t['failed']} of {t['runs']} runs failed an outcome ({t['collisions']} collisions, "
        f"{t['lane_departures']} departures)" + (f", {t['supervisor_failed']} failed a supervisor check" if t["controller"] == "guarded"
                                                 else "") for t in suite_totals(rows, controllers)))
    print(f"wrote {out}/runs.jsonl, suite.md, suite.json ({len(rows)} of {progress.planned} runs"
          + (f", {progress.resumed} resumed)" if progress.resumed else ")"))
    if progress.interrupted:
        print(f"interrupted by {progress.stopped_by}: the table holds the finished runs; run the same command with --resume to go on")
        return _interrupted_exit(args.stop)
    return 0 if all(r["passed"] for r in rows if r["controller"] == "guarded") else 1


def _executor(args: argparse.Namespace) -> Any:
    """The executor ``--jobs``/``--scheduler`` ask for (None: the in-process loop; Dask is imported only otherwise)."""
    if args.jobs == 1 and args.scheduler is None:
        return None
    from fearguard.drive.cluster import executor_for

    return executor_for(args.jobs, args.scheduler)


def _on(executor: Any) -> str:
    """`` on a local Dask cluster of 2 worker processes`` for a command's first line ('' in this process)."""
    return f" on {executor.where}" if executor is not None else ""


def cmd_sweep(args: argparse.Namespace) -> int:
    """Numbers of the rules and the vehicle × scenarios × seeds, guarded, against the unguarded car → sweep.md, sweep.json,
    sweep.png; exit 1 if no combination kept zero collisions and zero lane departures."""
    from fearguard.drive.suite import run_plan
    from fearguard.outputs.recorder import write_json
    from fearguard.sim import sweep
    from fearguard.sim.suite import scenario_files

    files = scenario_files(args.folder)
    specs = sweep.plan(files, args.seeds, args.set)  # every combination checked against every scenario's files first
    executor = _executor(args)
    out = Path(args.out) if args.out else _new_out("sweep", f"{len(specs)}runs")
    out.mkdir(parents=True, exist_ok=True)
    combos = len(sweep.combinations(args.set))
    print(f"sweep: {combos} combination(s) × {len(files)} scenarios × {args.seeds} seed(s), guarded, and the unguarded car once "
          f"({len(specs)} runs) → {out}{_on(executor)}", file=sys.stderr)
    with _RunProgress("sweep", executor, line=sweep.row_line, failed=lambda r: r["controller"] == "guarded"
                      and bool(r["collisions"] or r["lane_departures"])) as bar:
        result = run_plan(specs, runs_log=out / "runs.jsonl", resume=args.resume, stop=args.stop, executor=executor,
                          on_row=bar.row, on_progress=bar.update)
    table, reference = sweep.merge(result.rows), sweep.unguarded_totals(result.rows)
    markdown = sweep.sweep_markdown(table, reference)
    (out / "sweep.md").write_text(markdown, encoding="utf-8")
    write_json(out / "sweep.json", {"interrupted": result.interrupted, "planned_runs": result.planned, "finished_runs": len(result.rows),
                                    "settings": {s.key: list(s.values) for s in args.set}, "combinations": table,
                                    "safe_ranked": [t["combination"] for t in sweep.ranked_safe(table)], "unguarded": reference})
    plotted = ""
    if table:
        try:
            sweep.sweep_figure(table, reference, title=out.name).savefig(out / "sweep.png", dpi=90)
            plotted = ", sweep.png"
        except ModuleNotFoundError as exc:  # the core install has no matplotlib
            print(f"warning: sweep.png needs {exc.name}: pip install 'fearguard[desktop]'", file=sys.stderr)
    print(markdown)
    print(f"wrote {out}/runs.jsonl, sweep.md, sweep.json{plotted} ({len(result.rows)} of {result.planned} runs)")
    if result.interrupted:
        print(f"interrupted by {result.stopped_by}: the table holds the finished runs; run the same command with --resume to go on")
        return _interrupted_exit(args.stop)
    return 0 if sweep.ranked_safe(table) else 1


def _setting(text: str) -> Any:
    """An argparse type for ``sweep --set KEY=V1,V2``: a known dotted key and TOML values (exit 2 with "did you mean")."""
    from fearguard.sim.sweep import parse_setting

    try:
        return parse_setting(text)
    except FearguardError as exc:
        raise argparse.ArgumentTypeError(str(exc)) from None


def _latest_suite() -> Path:
    """``suite --resume`` without --out: the newest fearguard-out/suite-* folder (the one an interruption left)."""
    found = sorted((p for p in OUT_ROOT.glob("suite-*") if (p / "runs.jsonl").is_file()), key=lambda p: p.stat().st_mtime)
    if not found:
        raise FearguardError(f"suite --resume: no earlier suite under {OUT_ROOT}/ to resume; give its folder with --out")
    return found[-1]


def cmd_scenarios(args: argparse.Namespace) -> int:
    """The bundled scenarios: name and one-line description (``fearguard run NAME`` runs one)."""
    from fearguard.sim.scenario import load_scenario
    from fearguard.sim.suite import scenario_files

    scenarios = [load_scenario(p) for p in scenario_files(args.folder)]
    width = max((len(sc.name) for sc in scenarios), default=0)
    for sc in scenarios:
        print(f"{sc.name:<{width}}  {sc.description}")
    return 0


def cmd_verify(args: argparse.Namespace) -> int:
    """Every safety invariant searched with hypothesis for one car → a table; shrunk counterexamples as JSON Lines."""
    try:
        from fearguard.testing.verify import verify_command
    except ImportError as exc:  # hypothesis is an optional extra
        raise FearguardError(f"fearguard verify needs hypothesis ({exc}): pip install 'fearguard[testing]'") from None
    only = tuple(filter(None, (args.only or "").split(",")))
    return verify_command(args.rules, args.vehicle, args.steer, args.examples, args.seed, args.out, only, args.replay,
                          track=args.track)


def cmd_duckietown(args: argparse.Namespace) -> int:
    """One drive in gym-duckietown (guarded, or a baseline) → log.jsonl, summary.json, plots (and annotated.mp4)."""
    from fearguard.worlds.duckietown.drive import DriveOptions, drive
    from fearguard.worlds.duckietown.report import print_drive

    if args.list_maps:
        from fearguard.worlds.duckietown.world import map_names

        print("\n".join(map_names()))
        return 0
    if args.map is None:
        raise FearguardError("duckietown: give a MAP (see --list-maps)")
    out = args.out or _new_out("duckietown", args.map)
    try:
        options = DriveOptions(
            map_name=args.map, seconds=args.seconds, controller=args.baseline or "guarded", cruise_mps=args.cruise_mps,
            obstacle=args.obstacle, ahead_m=args.ahead, remove_after_s=args.remove_after, range_sensor=args.range,
            domain_rand=args.domain_rand, seed=args.seed, width_px=args.width, height_px=args.width * 3 // 4, rules=args.rules,
            video=args.video, plots=not args.no_plots, mcap=args.mcap, route=args.route == "map", lane=args.lane,
        )
    except ValueError as exc:
        raise FearguardError(f"duckietown: {exc}") from None
    with _Progress(f"duckietown {args.map}") as progress:
        result = drive(options, out, progress.update)
    print_drive(result.summary)
    plots = (", drive.png" + (", timeline.png" if options.controller == "guarded" else "")) if options.plots else ""
    print(f"wrote {out}/log.jsonl, summary.json{plots}")
    if result.video_path is not None:
        print(f"video {result.video_path}")
    if args.mcap:
        print(f"foxglove {out}/run.mcap")
    if result.interrupted:
        print("interrupted: the log holds every step driven so far")
        return 130
    return 0


def cmd_duckietown_suite(args: argparse.Namespace) -> int:
    """The development maps guarded / unguarded / expert, obstacles, domain randomisation → suite.md, suite.json."""
    from fearguard.worlds.duckietown.suite import run_suite

    executor = _executor(args)
    out = args.out or _new_out("duckietown-suite", f"{args.seeds}seeds")
    print(f"duckietown-suite → {out}{_on(executor)}", file=sys.stderr)
    def failed(r: dict) -> bool:
        return r["controller"] == "guarded" and bool(r["departures"] or r["collisions"] or r["invalid_pose"])

    with _RunProgress("duckietown-suite", executor, line=lambda r: f"{r['run']} {r['controller']}", failed=failed) as bar:
        table = run_suite(out, seconds=args.seconds, seeds=args.seeds, maps=args.maps, rand_seconds=args.rand_seconds,
                          executor=executor, on_run=lambda line: print(line, flush=True), resume=args.resume,
                          on_progress=bar.update, on_row=bar.row)
    print(table)
    print(f"wrote {out}/runs.jsonl, suite.md, suite.json")
    return 0


def cmd_metadrive(args: argparse.Namespace) -> int:
    """One drive in MetaDrive (guarded, or a baseline) → log.jsonl, summary.json, timeline.png (and annotated.mp4)."""
    from fearguard.worlds.metadrive.drive import DriveOptions, drive
    from fearguard.worlds.metadrive.report import print_drive

    out = args.out or _new_out("metadrive", f"{args.map}-seed{args.seed}")
    try:
        options = DriveOptions(
            map_blocks=args.map, lanes=args.lanes, traffic_density=args.traffic, lighting=args.lighting, seed=args.seed,
            seconds=args.seconds, controller=args.baseline or "guarded", cruise_mps=args.cruise_mps, range_sensor=args.range,
            lead=args.lead, lead_ahead_m=args.lead_ahead, lead_speed_mps=args.lead_speed, width_px=args.width,
            height_px=args.width * 3 // 4, rules=args.rules, video=args.video, plots=not args.no_plots, mcap=args.mcap,
            route=args.route == "map",
        )
    except ValueError as exc:
        raise FearguardError(f"metadrive: {exc}") from None
    with _Progress(f"metadrive {args.map} seed {args.seed}", unit="steps") as progress:
        result = drive(options, out, progress.update, stop=args.stop)
    print_drive(result.summary)
    print(f"wrote {out}/log.jsonl, summary.json" + (", timeline.png" if options.plots and options.controller == "guarded" else ""))
    if result.video_path is not None:
        print(f"video {result.video_path}")
    if result.interrupted:
        print("interrupted: the log holds every step driven so far")
        return _interrupted_exit(args.stop)
    return 0


def cmd_metadrive_suite(args: argparse.Namespace) -> int:
    """Development seeds guarded / unguarded / expert, a stopped car, night → runs.jsonl, suite.md, suite.json."""
    from fearguard.worlds.metadrive.drive import DriveOptions
    from fearguard.worlds.metadrive.suite import plan, run_suite

    executor = _executor(args)  # before anything is written: without Dask, a one-line error
    out = (Path(args.out) if args.out else Path(_new_out("metadrive-suite", f"{len(args.seeds)}seeds"))).resolve()  # workers elsewhere
    try:
        base = DriveOptions(map_blocks=args.map, lanes=args.lanes, traffic_density=args.traffic, cruise_mps=args.cruise_mps)
        specs = plan(args.seeds, args.seconds, args.stopped_seeds, args.night_seeds, out, base, args.controllers)
    except ValueError as exc:
        raise FearguardError(f"metadrive-suite: {exc}") from None
    print(f"metadrive-suite: {len(specs)} drives → {out}{_on(executor)}", file=sys.stderr)
    def failed(r: dict) -> bool:
        return r["controller"] == "guarded" and bool(r.get("crashes") or r.get("out_of_road"))

    with _RunProgress("metadrive-suite", executor, line=lambda r: f"{r['run']} {r['controller']}", failed=failed) as bar:
        table, interrupted = run_suite(out, specs, executor=executor, on_run=lambda line: print(line, flush=True),
                                       resume=args.resume, stop=args.stop, on_progress=bar.update, on_row=bar.row)
    print(table)
    print(f"wrote {out}/runs.jsonl, suite.md, suite.json")
    if interrupted:
        print("interrupted: the table holds the finished drives; run the same command with --resume to go on")
        return _interrupted_exit(args.stop)
    return 0


def _blocks(text: str) -> str:
    """An argparse type: a MetaDrive block string (S straight, C curve, r/R ramps, X/T/O junctions, ...)."""
    from fearguard.worlds.metadrive.world import BLOCK_LETTERS

    if not text or not set(text) <= BLOCK_LETTERS:
        raise argparse.ArgumentTypeError(f"{text!r} is not a MetaDrive block string: letters of {''.join(sorted(BLOCK_LETTERS))}, "
                                         "e.g. SCSC (straight, curve, straight, curve)")
    return text


def _count(minimum: int) -> Callable[[str], int]:
    """An argparse type: a whole number >= minimum (a clear usage error, exit 2, before anything runs)."""

    def parse(text: str) -> int:
        try:
            value = int(text)
        except ValueError:
            raise argparse.ArgumentTypeError(f"{text!r} is not a whole number") from None
        if value < minimum:
            raise argparse.ArgumentTypeError(f"must be >= {minimum}, got {value}")
        return value

    return parse


def _bounded_count(low: int, high: int) -> Callable[[str], int]:
    """An argparse type: a whole number in low..high (exit 2, one line)."""
    at_least = _count(low)

    def parse(text: str) -> int:
        value = at_least(text)
        if value > high:
            raise argparse.ArgumentTypeError(f"must be <= {high}, got {value}")
        return value

    return parse


def _number(low: float | None = None, *, above: float | None = None, below: float | None = None) -> Callable[[str], float]:
    """An argparse type: a finite number, at least ``low`` / more than ``above`` / less than ``below`` (exit 2, one line)."""

    def parse(text: str) -> float:
        try:
            value = float(text)
        except ValueError:
            raise argparse.ArgumentTypeError(f"{text!r} is not a number") from None
        if not math.isfinite(value):
            raise argparse.ArgumentTypeError(f"must be a finite number, got {text!r}")
        if low is not None and value < low:
            raise argparse.ArgumentTypeError(f"must be >= {low:g}, got {value:g}")
        if above is not None and value <= above:
            raise argparse.ArgumentTypeError(f"must be > {above:g}, got {value:g}")
        if below is not None and value >= below:
            raise argparse.ArgumentTypeError(f"must be < {below:g}, got {value:g}")
        return value

    return parse


def _position(text: str) -> str:
    """An argparse type for ``--from/--to``: seconds ('12.5s', '12.5') or a frame ('300f'); inside the recording is
    checked once it is open."""
    from fearguard.replay.sources import POSITION_FORMS, position_form_ok

    if not position_form_ok(text):
        raise argparse.ArgumentTypeError(f"{text!r}: {POSITION_FORMS}")
    return text


def _scheduler(text: str) -> str:
    """An argparse type for ``--scheduler``: a Dask scheduler's address (whether it answers is checked when the run starts)."""
    from fearguard.drive.cluster import ADDRESS_FORM, scheduler_address_ok

    if not scheduler_address_ok(text):
        raise argparse.ArgumentTypeError(f"{text!r} is not {ADDRESS_FORM}")
    return text.strip()


def _batch_options(parser: argparse.ArgumentParser, what: str) -> None:
    """``--jobs N`` / ``--scheduler ADDRESS`` (one or the other) of every command that runs a plan of runs."""
    where = parser.add_mutually_exclusive_group()
    where.add_argument("--jobs", type=_count(1), default=1, help=f"{what} at a time on a local Dask cluster of N single-threaded "
                       "worker processes (default 1: one after the other in this process, no Dask); needs fearguard[cluster]")
    where.add_argument("--scheduler", type=_scheduler, default=None, metavar="ADDRESS",
                       help=f"run the {what} on the workers of a running Dask scheduler, e.g. tcp://10.0.0.5:8786 (docs/cluster.md)")


def _folder(text: str) -> str:
    """An argparse type: an existing folder to read from."""
    if not Path(text).is_dir():
        raise argparse.ArgumentTypeError(f"{text!r} is not an existing folder" + (" (it is a file)" if Path(text).exists() else ""))
    return text


def _out_folder(text: str) -> str:
    """An argparse type: a folder to write into; an existing file there (or above it) is a usage error, exit 2."""
    path = Path(text)
    for where in (path, *path.parents):
        if where.exists():
            if not where.is_dir():
                raise argparse.ArgumentTypeError(f"{where} is a file, not a folder; give a folder to write the outputs into")
            break
    return text


def _version() -> str:
    """The installed distribution's version (pyproject.toml's), or a note when run from a source tree."""
    from importlib.metadata import PackageNotFoundError, version

    try:
        return version("fearguard")
    except PackageNotFoundError:
        return "(not installed: run from a source tree)"


class _VersionAction(argparse.Action):
    """``--version``: the version looked up only when asked (importlib.metadata costs ~50 ms of every start)."""

    def __init__(self, option_strings: list[str], dest: str = argparse.SUPPRESS, **kwargs: Any) -> None:
        super().__init__(option_strings, dest, nargs=0, default=argparse.SUPPRESS, help="show the version and exit", **kwargs)

    def __call__(self, parser: argparse.ArgumentParser, *args: Any, **kwargs: Any) -> None:
        print(f"fearguard {_version()}")  # on stdout, as argparse's own version action does
        parser.exit()


def _one_line_warning(message: Warning | str, category: type[Warning], filename: str, lineno: int, file: Any = None,
                      line: str | None = None) -> None:
    """warnings.showwarning for the command line: ``warning: message`` on stderr, no source line."""
    print(f"warning: {message}", file=sys.stderr)


def build_parser() -> argparse.ArgumentParser:
    parser = argparse.ArgumentParser(prog="fearguard", description="a fuzzy, affective safety supervisor around your steering function")
    parser.add_argument("--version", action=_VersionAction)
    sub = parser.add_subparsers(dest="command", required=True)
    demo = sub.add_parser("demo", help="a scripted drive through glare, occlusion, an obstacle and stale QR")
    demo.add_argument("--rules", default=None, help="rule file (default: the bundled model-car rules)")
    demo.set_defaults(func=cmd_demo)
    rules = sub.add_parser("rules", help="check, plot or explain a rule base")
    rsub = rules.add_subparsers(dest="rules_command", required=True)
    check = rsub.add_parser("check", help="validate; prove completeness and monotonicity on a dense grid")
    check.add_argument("file", nargs="?", default=None)
    check.set_defaults(func=cmd_check)
    plot = rsub.add_parser("plot", help="membership functions and fear surfaces as PNG")
    plot.add_argument("file", nargs="?", default=None)
    plot.add_argument("--out", type=_out_folder, default=None, help="directory for the PNG files " + OUT_HELP % "rules-plot")
    plot.set_defaults(func=cmd_plot)
    explain = rsub.add_parser("explain", help="fear, level, top rules and the command for given cues")
    explain.add_argument("--cues", required=True, help="e.g. lane_confidence=0.2,occlusion=0.8 (others calm)")
    explain.add_argument("--rules", default=None, help="rule file (default: bundled)")
    explain.add_argument("--lead-bearing", type=_number(above=-90.0, below=90.0), default=None,
                         help="a lead vehicle at this bearing (deg, + left)")
    explain.add_argument("--lead-range", type=_number(0.0), default=None, help="its range (m)")
    explain.add_argument("--top", type=_count(1), default=3, help="how many rules to show")
    explain.set_defaults(func=cmd_explain)
    calibrate = sub.add_parser("calibrate", help="camera intrinsics and distortion from chessboard photos → camera.toml")
    calibrate.add_argument("images", nargs="*", help="chessboard photos, or folders of *.jpg/*.png")
    calibrate.add_argument("--pattern", default="9x6", help="inner corners COLSxROWS (default 9x6: a board of 10×7 squares)")
    calibrate.add_argument("--square-m", type=_number(above=0.0), default=1.0,
                           help="side of one square in metres (does not change the intrinsics)")
    calibrate.add_argument("--mount-height-m", type=_number(above=0.0), default=None,
                           help="camera height above the ground (m), for ground ranges")
    calibrate.add_argument("--pitch-deg", type=_number(above=-90.0, below=90.0), default=0.0,
                           help="camera pitch, positive = looking down (deg)")
    calibrate.add_argument("--front-offset-m", type=_number(0.0), default=0.0,
                           help="the lens's distance behind the car's front bumper (m): ranges are given from the front")
    calibrate.add_argument("--out", default=None, help="camera file to write (TOML), e.g. camera.toml "
                           "(default: camera.toml in a new folder fearguard-out/calibrate-...-TIMESTAMP)")
    calibrate.set_defaults(func=cmd_calibrate)
    rp = sub.add_parser("replay", help="recorded drives (video, image folder, Donkey tub, ROS bag) through the supervisor, open loop")
    rp.add_argument("recordings", nargs="+", metavar="recording",
                    help="video file, folder of images, Donkey Car tub folder or ROS bag; several: a fleet, a folder each under --out")
    rp.add_argument("--out", type=_out_folder, default=None,
                    help="output folder (log.jsonl, summary.json, timeline.png, the video; a fleet: a folder per recording, "
                    "replays.md, replays.json) " + OUT_HELP % "replay")
    rp.add_argument("--vehicle", default=None, help="vehicle preset (" + ", ".join(PRESETS) + ") or vehicle.toml "
                    "(default: VehicleLimits(), a 1:10 car capped at 2 m/s); the range sensor is what the sensor log has")
    rp.add_argument("--steer", default=None, help="your steering function module:function, frame -> degrees "
                    "(default: the built-in HoughLaneSteering)")
    rp.add_argument("--sensor-log", default=None, help="CSV or JSON Lines with t_s and sensor columns, aligned by time")
    rp.add_argument("--strict", action="store_true", help="reject a sensor log with any malformed line (default: report and skip)")
    rp.add_argument("--camera", default=None, help="camera.toml from `fearguard calibrate`")
    rp.add_argument("--rules", default=None, help="rule file (default: the bundled model-car rules)")
    rp.add_argument("--track", default=None, help="track profile from `fearguard learn` (adds the familiarity cue)")
    rp.add_argument("--markings", choices=MARKINGS, default=None, help="the track's markings the built-in lane model looks for: "
                    "light paint or tape, or dark (black) tape on a paler floor (default: the track profile's, else light)")
    rp.add_argument("--guidance", choices=GUIDANCE, default=None, help="what the track guides the car by: the lane's two lines, "
                    "or one line — a centre line, one edge — whose own support is the lane confidence (default: the track "
                    "profile's, else two_lines)")
    rp.add_argument("--no-ultrasonic", action="store_true", help="the car has no ultrasonic (even if the log has a column)")
    rp.add_argument("--qr-localisation", action="store_true", help="the car localises with QR markers (scan frames, staleness cue)")
    rp.add_argument("--speed-mps", type=_number(0.0), default=None, help="the recording's speed when the log has none (default: unknown)")
    rp.add_argument("--fps", type=_number(above=0.0), default=None, help="frame rate of an image folder (or to override a video's)")
    rp.add_argument("--from", dest="from_", type=_position, default=None, help="start: seconds ('12.5s') or a frame ('300f')")
    rp.add_argument("--to", type=_position, default=None, help="end (exclusive): seconds or a frame")
    rp.add_argument("--every", type=_count(1), default=1, help="process every N-th frame (N >= 1)")
    rp.add_argument("--video", action="store_true", help=VIDEO_HELP)
    rp.add_argument("--no-plots", action="store_true", help="skip timeline.png")
    rp.add_argument("--mcap", action="store_true", help=MCAP_HELP)
    for role, what in (("image", "the camera (sensor_msgs/Image or CompressedImage)"), ("range", "the range sensor (sensor_msgs/Range)"),
                       ("speed", "the speed (nav_msgs/Odometry, geometry_msgs/TwistStamped or Twist)"),
                       ("qr", "QR payloads (std_msgs/String)")):
        rp.add_argument(f"--{role}-topic", default=None, help=f"a ROS bag's topic for {what} (default: the only one there is"
                        + ("" if role == "image" else "; none: ignore it") + ")")
    rp.add_argument("--resume", action="store_true", help="a fleet: skip the recordings already in OUT/runs.jsonl")
    _batch_options(rp, "recordings")
    rp.set_defaults(func=cmd_replay)
    lp = sub.add_parser("learn", help="recordings of normal driving → a track profile: the familiarity cue, the light and the lane "
                        "as this track has them (docs/learning.md)")
    lp.add_argument("recordings", nargs="+", metavar="recording", help="video file, folder of images, Donkey Car tub or ROS bag")
    lp.add_argument("--out", required=True, help="the profile to write (.npz); track.png is drawn beside it")
    lp.add_argument("--camera", default=None, help="camera.toml from `fearguard calibrate` (the lane model's camera)")
    lp.add_argument("--fps", type=_number(above=0.0), default=None, help="frame rate of an image folder (or to override a video's)")
    lp.add_argument("--from", dest="from_", type=_position, default=None, help="start: seconds ('12.5s') or a frame ('300f')")
    lp.add_argument("--to", type=_position, default=None, help="end (exclusive): seconds or a frame")
    lp.add_argument("--every", type=_count(1), default=1, help="learn every N-th frame (N >= 1)")
    lp.set_defaults(func=cmd_learn)
    run = sub.add_parser("run", help="one scenario closed loop: rendered frames → perception → supervisor → car")
    run.add_argument("scenario", help="a bundled scenario's name (e.g. night; `fearguard scenarios` lists them) or a scenario file")
    run.add_argument("--seed", type=_count(0), default=None, help="random seed >= 0 (default: the scenario's)")
    who = run.add_mutually_exclusive_group()
    who.add_argument("--unguarded", action="store_true", help="no supervisor: cruise speed, the estimator alone")
    who.add_argument("--baseline", choices=SIM_CONTROLLERS[1:], default=None, help="a baseline speed rule instead of fearguard")
    run.add_argument("--out", type=_out_folder, default=None, help="output folder " + OUT_HELP % "run")
    run.add_argument("--video", action="store_true", help=VIDEO_HELP)
    run.add_argument("--mcap", action="store_true", help=MCAP_HELP)
    run.add_argument("--track", default=None, help="track profile from `fearguard learn` for the guarded supervisor")
    run.set_defaults(func=cmd_run)
    suite = sub.add_parser("suite", help="every scenario guarded and with the baselines: a comparison table")
    suite.add_argument("folder", nargs="?", type=_folder, default=None, help="folder of scenario files (default: the bundled library)")
    suite.add_argument("--seeds", type=_count(1), default=10, help="seeds per scenario, >= 1 (default 10)")
    suite.add_argument("--out", type=_out_folder, default=None, help="output folder for runs.jsonl, suite.md and suite.json "
                       + OUT_HELP % "suite")
    suite.add_argument("--resume", action="store_true", help="skip the runs already in OUT/runs.jsonl (after an interruption; "
                       "without --out: the newest fearguard-out/suite-* folder)")
    suite.add_argument("--verbose", action="store_true", help="print each run as it finishes")
    suite.add_argument("--controllers", nargs="+", choices=SIM_CONTROLLERS, default=None, metavar="NAME",
                       help=f"only these controllers ({', '.join(SIM_CONTROLLERS)}; default: all): e.g. `--controllers guarded` "
                       "checks a change of the rules or the perception in a quarter of the time")
    _batch_options(suite, "runs")
    suite.set_defaults(func=cmd_suite)
    sw = sub.add_parser("sweep", help="numbers of the rules and the vehicle × scenarios × seeds: safety against progress")
    sw.add_argument("folder", nargs="?", type=_folder, default=None, help="folder of scenario files (default: the bundled library)")
    sw.add_argument("--set", type=_setting, action="append", required=True, metavar="KEY=V1,V2",
                    help="values to try for a number of the rule file (policy.hold_s=1,2,3) or the vehicle "
                    "(vehicle.max_speed_mps=1.5,2); repeat for more keys: every combination runs")
    sw.add_argument("--seeds", type=_count(1), default=3, help="seeds per scenario, >= 1 (default 3)")
    sw.add_argument("--out", type=_out_folder, default=None, help="output folder for runs.jsonl, sweep.md, sweep.json, sweep.png "
                    + OUT_HELP % "sweep")
    sw.add_argument("--resume", action="store_true", help="skip the runs already in OUT/runs.jsonl (after an interruption)")
    _batch_options(sw, "runs")
    sw.set_defaults(func=cmd_sweep)
    listing = sub.add_parser("scenarios", help="list the bundled scenarios (name and what each tests)")
    listing.add_argument("folder", nargs="?", type=_folder, default=None,
                         help="another folder of scenario files (default: the bundled library)")
    listing.set_defaults(func=cmd_scenarios)
    verify = sub.add_parser("verify", help="search every safety invariant with hypothesis for your rules, vehicle and steering")
    verify.add_argument("--rules", default=None, help="rule file (default: the bundled model-car rules)")
    verify.add_argument("--vehicle", default=None, help="vehicle preset name or vehicle.toml (default: VehicleLimits())")
    verify.add_argument("--steer", default=None, help="steering function module:function (default: scripted outputs)")
    verify.add_argument("--examples", type=_count(1), default=100, help="examples per invariant (default 100)")
    verify.add_argument("--seed", type=_count(0), default=0, help="search seed: the same seed tries the same examples (default 0)")
    verify.add_argument("--only", default=None, help="comma-separated invariant keys or numbers, e.g. 2,monotone")
    verify.add_argument("--out", default="fearguard-counterexamples", help="folder for counterexample files")
    verify.add_argument("--replay", default=None, help="re-run a counterexample file instead: exit 1 if it still fails")
    verify.add_argument("--track", default=None, help="track profile from `fearguard learn`: verify the supervisor that reads it")
    verify.set_defaults(func=cmd_verify)
    dt = sub.add_parser("duckietown", help="drive a Duckiebot in gym-duckietown (needs `bash .ci/duckietown.sh`)")
    dt.add_argument("map", nargs="?", default=None, help="map name, e.g. loop_empty, small_loop, zigzag_dists, straight_road")
    dt.add_argument("--out", default=None, help="output folder (log.jsonl, summary.json, drive.png, timeline.png, the video) "
                    + OUT_HELP % "duckietown")
    dt.add_argument("--seconds", type=_number(above=0.0), default=60.0, help="simulated duration (default 60)")
    dt.add_argument("--cruise-mps", type=_number(above=0.0), default=0.2, help="cruise speed (default 0.2 m/s)")
    dt.add_argument("--obstacle", choices=("duck", "cone", "duckiebot"), default=None, help="a static obstacle on the lane ahead")
    dt.add_argument("--ahead", type=_number(above=0.0), default=1.0,
                    help="its distance ahead of the front bumper along the lane (m, default 1.0)")
    dt.add_argument("--remove-after", type=_number(0.0), default=3.0, help="take it away after the robot stood still this long (s)")
    dt.add_argument("--range", choices=("none", "tof"), default="none", help="range sensor: none (a DB18) or a front time-of-flight")
    dt.add_argument("--baseline", choices=("unguarded", "expert"), default=None,
                    help="unguarded: the lane steering alone at cruise; expert: the simulator's ground-truth pure pursuit")
    dt.add_argument("--domain-rand", action="store_true", help="the simulator's domain randomisation (lighting, colours, camera pose)")
    dt.add_argument("--seed", type=_count(0), default=0, help="random seed (domain randomisation, sensor noise)")
    dt.add_argument("--width", type=_count(40), default=320, help="camera width in pixels, 4:3 (default 320; 160 is faster)")
    dt.add_argument("--rules", default=None, help="rule file (default: the bundled rules/duckiebot.toml)")
    dt.add_argument("--route", choices=("map", "none"), default="map",
                    help="map: the intersection navigation's way through junctions from the map (default); none: lanes only")
    dt.add_argument("--lane", choices=("preset", "camera"), default="preset",
                    help="preset: Duckietown's lane and paint (default); camera: what the camera alone knows (its height and "
                         "pitch; the lane width measured from the picture), as a Duckiebot with its own camera.toml")
    dt.add_argument("--video", action="store_true", help=VIDEO_HELP)
    dt.add_argument("--mcap", action="store_true", help=MCAP_HELP)
    dt.add_argument("--no-plots", action="store_true", help="skip drive.png and timeline.png")
    dt.add_argument("--list-maps", action="store_true", help="print the maps the simulator ships and exit")
    dt.set_defaults(func=cmd_duckietown)
    dts = sub.add_parser("duckietown-suite", help="the development maps guarded and with both baselines, obstacles, 10 randomised seeds")
    dts.add_argument("--out", default=None,
                     help="output folder (one folder per run, suite.md, suite.json) " + OUT_HELP % "duckietown-suite")
    dts.add_argument("--seconds", type=_number(above=0.0), default=60.0, help="duration of each drive (default 60)")
    dts.add_argument("--seeds", type=_count(0), default=10, help="domain-randomised seeds (default 10)")
    dts.add_argument("--maps", nargs="*", default=None, help="lane maps (default: loop_empty small_loop zigzag_dists straight_road)")
    dts.add_argument("--rand-seconds", type=_number(above=0.0), default=None, help="duration of each randomised drive (default: --seconds)")
    dts.add_argument("--resume", action="store_true", help="skip the drives already in OUT/runs.jsonl (after an interruption)")
    _batch_options(dts, "drives")
    dts.set_defaults(func=cmd_duckietown_suite)
    md = sub.add_parser("metadrive", help="drive MetaDrive's road car from its camera (needs `bash .ci/metadrive.sh`)")
    md.add_argument("--map", type=_blocks, default="SCSC", help="MetaDrive block string (default SCSC: straight, curve, straight, curve)")
    md.add_argument("--lanes", type=_bounded_count(1, 6), default=3, help="lanes per direction, 1..6 (default 3)")
    md.add_argument("--traffic", type=_number(0.0, below=1.000001), default=0.05,
                    help="MetaDrive's traffic density 0..1 (default 0.05, light; 0.1 is MetaDrive's default, 0.3 dense)")
    md.add_argument("--lighting", choices=("day", "dusk", "night"), default="day", help="light preset (docs/metadrive.md)")
    md.add_argument("--seed", type=_count(0), default=0, help="MetaDrive scenario seed (map geometry, traffic); default 0")
    md.add_argument("--seconds", type=_number(above=0.0), default=30.0, help="simulated duration (default 30)")
    md.add_argument("--cruise-mps", type=_number(above=0.0, below=22.3), default=10.0, help="cruise speed (default 10 m/s)")
    md.add_argument("--baseline", choices=("unguarded", "expert"), default=None,
                    help="unguarded: the lane steering alone at cruise; expert: MetaDrive's own IDM policy at cruise")
    md.add_argument("--range", choices=("none", "radar"), default="none",
                    help="forward range sensor: none (camera only) or a 0.3-80 m radar from the simulator's truth")
    md.add_argument("--route", choices=("map", "none"), default="map",
                    help="map: the navigation's route steering where the markings end (policy.route; default); none: the camera alone")
    md.add_argument("--lead", choices=("slower", "stopped"), default=None, help="add a car in the ego's lane ahead")
    md.add_argument("--lead-ahead", type=_number(above=0.0), default=35.0,
                    help="its distance ahead, bumper to bumper (m, default 35: on the first block, the lanes MetaDrive knows at the start)")
    md.add_argument("--lead-speed", type=_number(above=0.0), default=5.0, help="the slower lead's speed (m/s, default 5)")
    md.add_argument("--width", type=_count(160), default=320, help="camera width in pixels, 4:3 (default 320)")
    md.add_argument("--rules", default=None, help="rule file (default: the bundled rules/road_car.toml)")
    md.add_argument("--out", type=_out_folder, default=None, help="output folder (log.jsonl, summary.json, timeline.png, the video) "
                    + OUT_HELP % "metadrive")
    md.add_argument("--video", action="store_true", help=VIDEO_HELP)
    md.add_argument("--no-plots", action="store_true", help="skip timeline.png")
    md.add_argument("--mcap", action="store_true", help=MCAP_HELP)
    md.set_defaults(func=cmd_metadrive)
    mds = sub.add_parser("metadrive-suite", help="MetaDrive: development seeds guarded and with both baselines, a stopped car, night")
    mds.add_argument("--out", default=None, help="output folder (runs.jsonl, suite.md, suite.json, a folder per drive) "
                     + OUT_HELP % "metadrive-suite")
    mds.add_argument("--seeds", type=_count(0), nargs="+", default=[0, 1, 2], help="day seeds (default 0 1 2)")
    mds.add_argument("--stopped-seeds", type=_count(0), nargs="*", default=[0], help="seeds with a stopped car in the lane (default 0)")
    mds.add_argument("--night-seeds", type=_count(0), nargs="*", default=[0], help="seeds driven at night (default 0)")
    mds.add_argument("--seconds", type=_number(above=0.0), default=30.0, help="duration of each drive (default 30)")
    mds.add_argument("--controllers", nargs="+", choices=("guarded", "unguarded"), default=["guarded", "unguarded"],
                     help="the day drives besides the expert's (default: guarded unguarded)")
    mds.add_argument("--map", type=_blocks, default="SCSC", help="MetaDrive block string (default SCSC)")
    mds.add_argument("--lanes", type=_bounded_count(1, 6), default=3, help="lanes per direction (default 3)")
    mds.add_argument("--traffic", type=_number(0.0, below=1.000001), default=0.05, help="traffic density 0..1 (default 0.05)")
    mds.add_argument("--cruise-mps", type=_number(above=0.0, below=22.3), default=10.0, help="cruise speed (default 10 m/s)")
    mds.add_argument("--resume", action="store_true", help="skip the drives already in OUT/runs.jsonl (after an interruption)")
    _batch_options(mds, "drives")
    mds.set_defaults(func=cmd_metadrive_suite)
    return parser


def main(argv: Sequence[str] | None = None, *, exiting: bool = False) -> int:
    """Run one command; ``exiting``: the process ends right after (signals are then ignored, not restored)."""
    with stop_on_signals(ignore_after=exiting) as stop, warnings.catch_warnings():  # before anything else: a Ctrl-C is ours
        warnings.showwarning = _one_line_warning
        try:
            args = build_parser().parse_args(argv)
            args.stop = stop
            if args.command not in FRAME_LOOPS:  # no frame to finish: stop at once (also for a signal during start-up)
                stop.raise_at_once = True
                if stop:
                    raise KeyboardInterrupt
            code = int(args.func(args))
            if stop:  # the signal came after the work was done and written: still say so in the exit code
                print(f"interrupted by {stop.name} (after the work was done)", file=sys.stderr)
                return _interrupted_exit(stop)
            return code
        except FearguardError as exc:
            print(f"{type(exc).__name__}: {exc}", file=sys.stderr)
            return 2
        except KeyboardInterrupt:
            print(f"interrupted{f' by {stop.name}' if stop else ''}", file=sys.stderr)
            return _interrupted_exit(stop)
        except BrokenPipeError:  # output piped into `head`: stop quietly
            sys.stderr.close()
            return 0


def entry() -> None:
    """The ``fearguard`` console script."""
    sys.exit(main(exiting=True))


if __name__ == "__main__":  # pragma: no cover
    entry()
