"""A plan's rows on Dask: a local cluster of worker processes, or the workers of a scheduler that already runs.

``DaskExecutor(jobs=N)`` starts a ``distributed.LocalCluster`` of N single-threaded worker processes on this machine;
``DaskExecutor(scheduler="tcp://10.0.0.5:8786")`` connects a ``Client`` to a running scheduler (``dask scheduler``,
with ``dask worker`` processes on other machines: docs/cluster.md). Either is an ``Executor`` for ``run_plan``
(``drive/suite.py``): every spec is one task, ``submit(run_row, spec)``; rows are yielded as they complete
(``as_completed``), and ``run_plan`` appends each to runs.jsonl at once and puts them back in plan order.

Scheduling, retries and cancellation are Dask's, none is written here: a worker that dies mid-run has its task
rescheduled on another worker by the scheduler (up to ``distributed.scheduler.allowed-failures`` times, 3 by default),
so the run costs a re-run, never a missing or a duplicated row (each future completes once); a row that raises is
re-run ``RETRIES`` times (``submit(retries=)``), then its error ends the plan. A stop signal or Ctrl-C cancels the
futures and closes the client (and the local cluster, whose worker processes end with it): runs under way are
dropped, not results, and every finished row is already in runs.jsonl, which ``--resume`` completes.

Dask is an optional extra (``pip install "fearguard[cluster]"``): nothing here imports it until an executor is built,
so ``--jobs 1`` (the in-process loop) never pays for it, and without it the error says how to install it.
"""

from __future__ import annotations

import logging
import re
import time
import uuid
from collections.abc import Generator, Iterator, Sequence
from contextlib import contextmanager, suppress
from types import ModuleType
from typing import Any

from fearguard.drive.interrupt import StopSignal
from fearguard.drive.plan import RunSpec, run_row
from fearguard.errors import ClusterError

RETRIES = 1  # [-] re-runs of a row that raised (a shared data path not mounted yet on one worker); then the error is the plan's
POLL_S = 0.1  # [s] how often the wait for the next row looks at the stop flag (Dask's own as_completed waits as long)
CONNECT_TIMEOUT_S = 10.0  # [s] --scheduler: an address nothing answers on fails after this long (Dask's default is 30 s)
# LocalCluster's own log lines below ERROR are silenced (silence_logs): a cancelled run's warnings are expected noise
INSTALL_HINT = "pip install 'fearguard[cluster]' (Dask's distributed scheduler)"
# Dask's nanny starts its workers with MALLOC_TRIM_THRESHOLD_=65536 (distributed.nanny.pre-spawn-environ), which also
# switches off glibc's sliding mmap threshold: frame-sized arrays are then mapped and unmapped afresh and a simulator row
# ran ~1.5-2× slower than in this process (0.46 → 0.66 s measured). Unset, workers allocate as this process does; remote
# workers are set up the same way (docs/cluster.md: the YAML file, or --no-nanny).
# Dask's statistical profiler (distributed.worker.profile) samples the task thread's stack every 10 ms and folds the
# samples in on the worker's event loop; with MetaDrive building its map on the task thread, Panda3D aborted the worker
# process ("ReMutexPosixImpl::unlock(): Assertion `result == 0' failed", on the event loop's thread): 17 of 25 one-row suites
# here died on all four attempts (KilledWorker), 0 of 6 with the profiler off. Nothing here reads its profiles.
WORKER_CONFIG = {"distributed.nanny.pre-spawn-environ.MALLOC_TRIM_THRESHOLD_": None, "distributed.worker.profile.enabled": False}
ADDRESS = re.compile(r"((tcp|tls|ws|wss|ucx)://)?(\[[0-9A-Fa-f:]+\]|[A-Za-z0-9_.-]+)(:\d{1,5})?")  # a scheduler's address
ADDRESS_FORM = "a Dask scheduler address such as tcp://10.0.0.5:8786 (or HOST:PORT)"

Row = dict[str, Any]


def scheduler_address_ok(text: str) -> bool:
    """Whether ``text`` has the form of a scheduler address, ``[tcp://]HOST[:PORT]`` (checked before Dask is imported)."""
    match = ADDRESS.fullmatch(text.strip())
    return match is not None and (match.group(4) is None or 0 < int(match.group(4)[1:]) < 65536)


def require_distributed() -> ModuleType:
    """``distributed`` (Dask's scheduler and workers), or a ClusterError saying how to install it."""
    try:
        import distributed
    except ImportError as exc:
        raise ClusterError(f"--jobs N > 1 and --scheduler run the rows on Dask, which is not installed here ({exc}): "
                           f"{INSTALL_HINT}") from None
    return distributed


class DaskExecutor:
    """Run a plan's rows on Dask: ``jobs`` local single-threaded worker processes, or an existing ``scheduler``'s workers.

    Calling it runs the specs (an ``Executor``: ``(specs, stop) → (index, row)`` as each row completes). ``workers`` is
    the number of workers the cluster had when last asked (progress bars show it); ``where`` says which cluster.
    """

    def __init__(self, *, jobs: int | None = None, scheduler: str | None = None, retries: int = RETRIES,
                 connect_timeout_s: float = CONNECT_TIMEOUT_S) -> None:
        if (jobs is None) == (scheduler is None):
            raise ValueError("give either jobs (a local cluster of that many worker processes) or scheduler (an address)")
        if jobs is not None and not (isinstance(jobs, int) and jobs >= 1):
            raise ValueError(f"jobs must be a whole number >= 1, got {jobs!r}")
        if scheduler is not None and not scheduler_address_ok(scheduler):
            raise ValueError(f"scheduler must be {ADDRESS_FORM}, got {scheduler!r}")
        require_distributed()  # before anything runs: the message says how to install it
        self.jobs, self.scheduler, self.retries, self.connect_timeout_s = jobs, scheduler, retries, connect_timeout_s
        self.workers = jobs or 0

    @property
    def where(self) -> str:
        """Which cluster, for a person: ``a local Dask cluster of 2 worker processes`` / ``the Dask scheduler at ...``."""
        if self.scheduler is not None:
            return f"the Dask scheduler at {self.scheduler}"
        return f"a local Dask cluster of {self.jobs} worker process{'es' if self.jobs != 1 else ''}"

    def __call__(self, specs: Sequence[RunSpec], stop: StopSignal | None = None) -> Generator[tuple[int, Row], None, None]:
        distributed = require_distributed()
        with self._client(distributed) as client:
            batch = uuid.uuid4().hex[:8]  # keys unique on a scheduler other plans (other people) share
            futures = [client.submit(run_row, spec, key=f"fearguard-row-{batch}-{i}", retries=self.retries, pure=False)
                       for i, spec in enumerate(specs)]
            index = {future.key: i for i, future in enumerate(futures)}
            try:
                for future, row in self._completed(distributed, client, futures, stop):
                    yield index[future.key], row
            finally:  # a stop, Ctrl-C, a failed row or the consumer gone: nothing more runs for this plan
                with suppress(distributed.client.ClosedClientError, OSError, TimeoutError):
                    client.cancel(futures)  # a client closed under us (its scheduler lost) has nothing left to cancel: the
                    #   error that says so and how to resume must not be replaced by this one (CI, a loaded machine)

    def _completed(self, distributed: ModuleType, client: Any, futures: list[Any],
                   stop: StopSignal | None) -> Iterator[tuple[Any, Row]]:
        """(future, row) as each completes; ends early when ``stop`` is set (looked at every POLL_S while waiting)."""
        done = distributed.as_completed(futures, with_results=True, loop=client.loop)
        while not done.is_empty():
            if stop:
                return
            if done.has_ready():
                future, row = next(done)
                if not isinstance(row, dict):  # cancelled under us: the scheduler was lost, or someone cancelled the plan
                    raise ClusterError(f"a run was cancelled on {self.where} ({type(row).__name__}: the scheduler was lost, or "
                                       "someone cancelled the plan); the finished rows are in runs.jsonl: run the same command "
                                       "with --resume to run only what is missing")
                yield future, row
            else:
                self.workers = len(client.scheduler_info(n_workers=-1).get("workers", {}))
                time.sleep(POLL_S)

    @contextmanager
    def _client(self, distributed: ModuleType) -> Iterator[Any]:
        """A Client on the scheduler, or on a LocalCluster started (and closed) here."""
        if self.scheduler is not None:
            try:
                client = distributed.Client(self.scheduler, timeout=self.connect_timeout_s, set_as_default=False)
            except (OSError, TimeoutError) as exc:
                raise ClusterError(f"cannot reach the Dask scheduler at {self.scheduler} ({type(exc).__name__}: {exc}); "
                                   "start one with `dask scheduler` and its workers with `dask worker ADDRESS --nthreads 1` "
                                   "(docs/cluster.md), or check the address") from None
            with client:
                yield client
            return
        import dask.config  # comes with distributed

        with dask.config.set(WORKER_CONFIG), \
                distributed.LocalCluster(n_workers=self.jobs, threads_per_worker=1, processes=True, dashboard_address=None,
                                         silence_logs=logging.ERROR) as cluster, \
                distributed.Client(cluster, set_as_default=False) as client:
            yield client


def executor_for(jobs: int = 1, scheduler: str | None = None) -> DaskExecutor | None:
    """The executor ``--jobs``/``--scheduler`` ask for: None (the in-process loop, Dask not imported) for one job and no
    scheduler; a ClusterError when Dask is needed and missing."""
    if scheduler is not None:
        return DaskExecutor(scheduler=scheduler)
    return DaskExecutor(jobs=jobs) if jobs > 1 else None
