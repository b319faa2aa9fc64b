"""One signal policy for every command: SIGINT and SIGTERM finish the current frame, then stop cleanly.

``stop_on_signals()`` installs handlers that only set a flag (``StopSignal``); the frame loops of replay,
the closed loop and the suite read it after each frame, close the log and the video, write a summary
that says ``"interrupted": true`` and return; the CLI then exits 128 + the signal number (130 for
SIGINT / Ctrl-C, 143 for SIGTERM from ``systemctl stop``, ``docker stop`` or ``timeout``). A second
signal while stopping raises KeyboardInterrupt at once (the log is flushed per frame, so it stays
valid). Commands without a frame loop (rules check, calibrate, ...) stop at the first signal, with a
one-line message instead of a traceback. SIGKILL cannot be handled: what is on disk is what the recorder flushed (see ``recorder.py``).

Outside the main thread signal handlers cannot be installed; the flag then stays unset and a
KeyboardInterrupt is handled by the drivers as before.
"""

from __future__ import annotations

import signal
import threading
from collections.abc import Iterator
from contextlib import contextmanager
from types import FrameType

HANDLED = (signal.SIGINT, signal.SIGTERM)


class StopSignal:
    """Set when a stop signal arrived; falsy until then. ``exit_code`` is 128 + its number (0 if none).

    ``raise_at_once``: the handler also raises KeyboardInterrupt at the first signal (commands without
    a frame loop, and a CLI still starting); a frame loop sets it False to finish its frame instead.
    """

    def __init__(self, raise_at_once: bool = False) -> None:
        self.signum: int | None = None
        self.raise_at_once = raise_at_once

    def __bool__(self) -> bool:
        return self.signum is not None

    @property
    def name(self) -> str | None:
        return None if self.signum is None else signal.Signals(self.signum).name

    @property
    def exit_code(self) -> int:
        return 0 if self.signum is None else 128 + self.signum

    def request(self, signum: int) -> None:
        """Ask the running loop to stop after its current frame (what the handler does)."""
        if self.signum is None:
            self.signum = signum


@contextmanager
def stop_on_signals(stop: StopSignal | None = None, *, ignore_after: bool = False) -> Iterator[StopSignal]:
    """While inside: SIGINT/SIGTERM set the flag (a second one, or any with ``raise_at_once``, raises KeyboardInterrupt).

    The previous handlers are restored on the way out; with ``ignore_after`` (a process about to exit,
    its work written) the signals are ignored instead, so one arriving during interpreter shutdown
    cannot turn a finished run into a killed one.
    """
    stop = StopSignal() if stop is None else stop
    if threading.current_thread() is not threading.main_thread():
        yield stop
        return

    def handle(signum: int, frame: FrameType | None) -> None:
        again = bool(stop)
        stop.request(signum)
        if again or stop.raise_at_once:
            raise KeyboardInterrupt(signal.Signals(signum).name)

    previous = {s: signal.signal(s, handle) for s in HANDLED}
    try:
        yield stop
    finally:
        for s, old in previous.items():
            signal.signal(s, signal.SIG_IGN if ignore_after else old)
