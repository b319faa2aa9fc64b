"""The one driver loop: sense → decide → act → record, for every world and every controller.

``run`` owns what every driver used to write for itself: the loop, the stop signal (``drive/interrupt.py``: the
current frame finishes, everything is written), Ctrl-C (the same), closing the world, the per-frame record (the video
frame, then the flushed log line, the statistics and the trace) and the progress callback. Each world adds only its
``World`` and its metrics; the summary is built from the recorder's statistics and the world's own truth.
"""

from __future__ import annotations

import time
from collections.abc import Callable
from dataclasses import dataclass

from fearguard.drive.interrupt import StopSignal
from fearguard.drive.world import Controller, World
from fearguard.outputs.recorder import Recorder


@dataclass(frozen=True)
class Ran:
    """How a run ended: frames recorded, whether it was cut short and by what, and the controller's time per frame."""

    frames: int
    interrupted: bool
    stopped_by: str | None = None  # the signal that stopped it (None: Ctrl-C as KeyboardInterrupt, or none)
    controller_ms: tuple[float, ...] = ()  # [ms] per frame: perception + supervisor for a guarded controller


def run(world: World, controller: Controller, recorder: Recorder, *, stop: StopSignal | None = None,
        on_frame: Callable[[int, int | None], None] | None = None, total: int | None = None) -> Ran:
    """Drive until the world has nothing more to sense, says it is done, or a stop arrives; returns how it ended.

    The recorder is closed (log and video complete) and so is the world, whatever happened; a KeyboardInterrupt ends
    the run after what was recorded, like a stop signal. ``on_frame(frames, total)`` after every recorded frame.
    """
    interrupted = False
    spent: list[float] = []
    clock = time.perf_counter
    try:
        with recorder:
            while not stop:
                sensed = world.sense()
                if sensed is None:
                    break
                began = clock()
                decision = controller.decide(sensed)
                spent.append(1e3 * (clock() - began))
                outcome = world.act(sensed, decision)
                recorder.frame(sensed.index, sensed.t_s if outcome.t_s is None else outcome.t_s, decision.command,
                               image=sensed.image, analysis=decision.analysis, caption=outcome.caption,
                               speed_mps=outcome.speed_mps, fields=outcome.fields, stamp_ns=outcome.stamp_ns)
                if on_frame is not None:
                    on_frame(recorder.frames, total)
                if outcome.done:
                    break
    except KeyboardInterrupt:
        interrupted = True
    finally:
        world.close()
    return Ran(recorder.frames, interrupted or bool(stop), stop.name if stop else None, tuple(spent))
