"""A real Dask cluster for tests: ``dask scheduler`` and ``dask worker`` processes on 127.0.0.1, as docs/cluster.md
starts them (random free ports, one thread per worker, the worker YAML of the docs, in a folder of their own as on
another machine), each in its own process group so
a test can kill one worker (nanny and worker process: a machine gone) and the fixture cleans every one up."""

from __future__ import annotations

import json
import os
import signal
import subprocess
import sys
import time
from pathlib import Path

import pytest

START_TIMEOUT_S = 120.0  # [s] a loaded 2-core machine can take this long to import Dask and fearguard in a new process
WORKER_YAML = """distributed:
  nanny:
    pre-spawn-environ:
      MALLOC_TRIM_THRESHOLD_: null
  worker:
    profile:
      enabled: false
"""  # the file docs/cluster.md tells every worker machine to have


class DaskProcesses:
    """A scheduler and its workers, real processes; ``address`` is the scheduler's."""

    def __init__(self, folder: Path) -> None:
        self.folder = folder
        (folder / "dask-config").mkdir(parents=True, exist_ok=True)
        (folder / "dask-config" / "fearguard.yaml").write_text(WORKER_YAML)
        self.env = {**os.environ, "DASK_CONFIG": str(folder / "dask-config")}
        self.workers: list[subprocess.Popen] = []
        self.scheduler = self._start("scheduler", "--host", "127.0.0.1", "--port", "0", "--no-dashboard",
                                     "--scheduler-file", str(folder / "scheduler.json"))
        try:
            self.address = self._address(folder / "scheduler.json")
        except BaseException:  # pytest.fail (a scheduler that never came up) is one: no process is left behind
            self.close()
            raise

    def _start(self, *args: str) -> subprocess.Popen:
        log = open(self.folder / f"{args[0]}-{time.monotonic_ns()}.log", "wb")  # the process writes to it
        return subprocess.Popen([sys.executable, "-m", "dask", *args], env=self.env, stdout=log, stderr=subprocess.STDOUT,
                                start_new_session=True, cwd=self.folder)  # not the tests' folder: relative paths would not do

    def _address(self, path: Path) -> str:
        deadline = time.monotonic() + START_TIMEOUT_S
        while time.monotonic() < deadline:
            if self.scheduler.poll() is not None:
                pytest.fail(f"dask scheduler exited with {self.scheduler.returncode}; see {self.folder}")
            try:
                return str(json.loads(path.read_text())["address"])
            except (FileNotFoundError, json.JSONDecodeError, KeyError):
                time.sleep(0.2)
        pytest.fail(f"dask scheduler wrote no {path} in {START_TIMEOUT_S:.0f} s")

    def add_workers(self, n: int) -> None:
        """Start ``n`` more ``dask worker ADDRESS --nthreads 1`` processes and wait until the scheduler has them all."""
        for _ in range(n):
            self.workers.append(self._start("worker", self.address, "--nthreads", "1", "--no-dashboard", "--death-timeout", "60",
                                            "--local-directory", str(self.folder)))
        self.wait_for_workers(len(self.alive()))

    def alive(self) -> list[subprocess.Popen]:
        return [w for w in self.workers if w.poll() is None]

    def wait_for_workers(self, n: int) -> None:
        from distributed import Client

        with Client(self.address, timeout=START_TIMEOUT_S, set_as_default=False) as client:
            client.wait_for_workers(n, timeout=START_TIMEOUT_S)
            deadline = time.monotonic() + START_TIMEOUT_S
            while len(client.scheduler_info(n_workers=-1)["workers"]) != n and time.monotonic() < deadline:
                time.sleep(0.2)  # a killed worker leaves once the scheduler notices its connection closed

    def kill_worker(self) -> None:
        """SIGKILL one worker's whole process group (its nanny and its worker process): as if its machine went away."""
        worker = self.alive()[0]
        os.killpg(worker.pid, signal.SIGKILL)
        worker.wait()

    def close(self) -> None:
        """Every process group ended (SIGTERM, then SIGKILL after 30 s): no worker outlives the test."""
        groups = [*self.workers, self.scheduler]
        for proc in groups:
            _signal_group(proc, signal.SIGTERM)
        for proc in groups:
            try:
                proc.wait(timeout=30)
            except subprocess.TimeoutExpired:
                pass
            _signal_group(proc, signal.SIGKILL)  # whatever of the group is left (a worker process under its nanny)
            proc.wait()


def _signal_group(proc: subprocess.Popen, signum: int) -> None:
    try:
        os.killpg(proc.pid, signum)
    except ProcessLookupError:  # the whole group has ended
        pass
