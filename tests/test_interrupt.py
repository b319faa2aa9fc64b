"""One signal policy: SIGINT/SIGTERM set a flag the frame loop reads; a second signal, or any in a command
without a frame loop, raises KeyboardInterrupt; handlers are restored afterwards."""

from __future__ import annotations

import os
import signal
import threading

import pytest

from fearguard.drive.interrupt import StopSignal, stop_on_signals


def test_a_signal_sets_the_flag_and_the_exit_code() -> None:
    before = signal.getsignal(signal.SIGTERM)
    with stop_on_signals() as stop:
        assert not stop and stop.exit_code == 0 and stop.name is None
        os.kill(os.getpid(), signal.SIGTERM)
        assert stop and stop.name == "SIGTERM" and stop.exit_code == 143
        with pytest.raises(KeyboardInterrupt, match="SIGINT"):  # a second signal: stop now
            os.kill(os.getpid(), signal.SIGINT)
        assert stop.exit_code == 143  # the first signal decides the exit code
    assert signal.getsignal(signal.SIGTERM) is before


def test_a_process_about_to_exit_ignores_late_signals() -> None:
    before = {s: signal.getsignal(s) for s in (signal.SIGINT, signal.SIGTERM)}
    try:
        with stop_on_signals(ignore_after=True):
            pass
        assert signal.getsignal(signal.SIGTERM) == signal.SIG_IGN
        os.kill(os.getpid(), signal.SIGTERM)  # ignored: the finished run is not killed
    finally:
        for s, handler in before.items():
            signal.signal(s, handler)


def test_without_a_frame_loop_the_first_signal_interrupts() -> None:
    with stop_on_signals(StopSignal(raise_at_once=True)) as stop:
        with pytest.raises(KeyboardInterrupt):
            os.kill(os.getpid(), signal.SIGINT)
        assert stop.exit_code == 130


def test_outside_the_main_thread_nothing_is_installed() -> None:
    seen: list[StopSignal] = []

    def worker() -> None:
        with stop_on_signals() as stop:
            seen.append(stop)

    before = signal.getsignal(signal.SIGINT)
    thread = threading.Thread(target=worker)
    thread.start()
    thread.join()
    assert seen and not seen[0] and signal.getsignal(signal.SIGINT) is before
    stop = StopSignal()
    stop.request(signal.SIGINT)
    stop.request(signal.SIGTERM)
    assert stop.signum == signal.SIGINT
