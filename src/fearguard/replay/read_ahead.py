"""Decoding ahead on another core: a recording's next frames are read while the current one is analysed.

OpenCV releases the GIL while it decodes and converts a frame (``VideoCapture.grab``/``retrieve``, ``imread``), so a
thread that reads frames runs beside the analysis on a second core; a replay then takes about as long as the slower of
the two instead of their sum. On one core the thread would only add hand-offs: ``usable_cores`` decides.

Written by hand (a thread and a bounded queue): the standard library has executors, not a read-ahead iterator that
stops its reader, and closes the source, as soon as the consumer stops.
"""

from __future__ import annotations

import os
import queue
import threading
from collections.abc import Generator, Iterator
from dataclasses import dataclass
from typing import TypeVar

T = TypeVar("T")

DEPTH = 3  # [items] read ahead at most (a 1280×720 BGR frame is 2.8 MB; a Pi 4 has room for a few)
_POLL_S = 0.05  # [s] how often a reader blocked on a full queue looks whether the consumer has stopped


def usable_cores() -> int:
    """Cores this process may run on (its CPU affinity where the platform has one, e.g. under ``taskset``)."""
    try:
        return len(os.sched_getaffinity(0))
    except AttributeError:  # macOS, Windows: no affinity call
        return os.cpu_count() or 1


@dataclass(frozen=True)
class _End:
    """The reader is done: the source ended, or raised ``error``."""

    error: BaseException | None = None


def read_ahead(items: Iterator[T], depth: int = DEPTH) -> Generator[T, None, None]:
    """The items of ``items``, in order, read by a background thread up to ``depth`` ahead.

    An exception raised by ``items`` is raised here, after the items before it. Closing this generator (``close()``,
    a ``break`` followed by garbage collection, an exception in the consumer) stops the reader and closes ``items``
    (a video source releases its capture) before ``close()`` returns: nothing reads the source afterwards.
    """
    buffer: queue.Queue[T | _End] = queue.Queue(maxsize=max(1, depth))
    stopping = threading.Event()

    def put(item: T | _End) -> bool:
        while not stopping.is_set():
            try:
                buffer.put(item, timeout=_POLL_S)
                return True
            except queue.Full:
                continue
        return False

    def reader() -> None:
        try:
            for item in items:
                if not put(item):
                    return
            put(_End())
        except BaseException as exc:  # handed to the consumer, which raises it in its own thread
            put(_End(exc))
        finally:
            close = getattr(items, "close", None)
            if close is not None:
                close()

    thread = threading.Thread(target=reader, name="fearguard-read-ahead", daemon=True)
    thread.start()
    try:
        while True:
            item = buffer.get()
            if isinstance(item, _End):
                if item.error is not None:
                    raise item.error
                return
            yield item
    finally:
        stopping.set()
        thread.join()
