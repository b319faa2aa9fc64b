"""An optional deadline on the wrapped steering function (off by default).

The function runs in one worker thread; the supervisor waits at most ``deadline_s`` for its answer, and a
later answer counts as a fault for that frame. While a late call is still running, the next frames do not
start another one (a stuck estimator would pile up threads): they are faults too, until it returns.
This trades determinism for timeliness — whether an answer makes the deadline depends on the machine's
load — so it is off by default, and replays and tests that must repeat byte for byte leave it off.
KeyboardInterrupt and SystemExit raised inside the function propagate, as without a deadline.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from concurrent.futures import Future, ThreadPoolExecutor
from concurrent.futures import TimeoutError as FutureTimeout
from typing import Any


class SteeringDeadline:
    """Calls a function with a deadline: ``call(fn, arg)`` → (answer, "") or (None, why it is late)."""

    def __init__(self, deadline_s: float) -> None:
        if isinstance(deadline_s, bool) or not isinstance(deadline_s, int | float) or not math.isfinite(deadline_s) or deadline_s <= 0:
            raise ValueError(f"steering_deadline_s must be a finite number > 0 (or None: off), got {deadline_s!r}")
        self.deadline_s = float(deadline_s)
        self._pool = ThreadPoolExecutor(max_workers=1, thread_name_prefix="fearguard-steering")
        self._busy: Future[Any] | None = None

    def call(self, fn: Callable[[Any], Any], arg: Any) -> tuple[Any, str]:
        if self._busy is not None and not self._busy.done():
            return None, f"fault: steering function still busy with an earlier frame (deadline {self.deadline_s:.3f} s)"
        future = self._pool.submit(fn, arg)
        try:
            return future.result(timeout=self.deadline_s), ""
        except FutureTimeout:
            self._busy = future
            return None, f"fault: steering function did not answer within its deadline of {self.deadline_s:.3f} s"
