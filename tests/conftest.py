"""Shared fixtures; hypothesis runs derandomized (fixed seed) so CI is repeatable."""

from __future__ import annotations

import importlib.util
from pathlib import Path

import pytest
from hypothesis import settings

import fearguard as fg

settings.register_profile("fearguard", derandomize=True, max_examples=150, deadline=None, print_blob=True)
settings.load_profile("fearguard")

# Modules that need an optional reader or writer (both are in `.[test]`, so the main run always collects them); an
# environment built for one integration (e.g. .ci/donkey.sh's, with the wheel alone) skips collecting them.
collect_ignore = [path for module, path in (("rosbags", "replay/test_bags.py"), ("mcap", "test_mcap_out.py"))
                  if importlib.util.find_spec(module) is None]

RULES_DIR = Path(__file__).resolve().parents[1] / "rules"
SHARED_DATA = Path(__file__).resolve().parents[2] / "shared" / "data"  # real recordings, never copied into the repo


@pytest.fixture(scope="session")
def shared_data() -> Path:
    """The real recorded data folder (../shared/data); tests using it skip, loudly, only if it is absent."""
    if not SHARED_DATA.is_dir():
        pytest.skip(f"real data folder {SHARED_DATA} is absent")
    return SHARED_DATA


@pytest.fixture(scope="session")
def rules() -> fg.RuleBase:
    return fg.load_rules()


@pytest.fixture
def write_rules(tmp_path: Path):
    """Write a variant of the default rule file: replace(old, new) pairs applied to its text."""

    def write(*replacements: tuple[str, str], name: str = "variant.toml") -> Path:
        text = (RULES_DIR / "default.toml").read_text()
        for old, new in replacements:
            assert old in text, f"fixture text not found: {old!r}"
            text = text.replace(old, new)
        path = tmp_path / name
        path.write_text(text)
        return path

    return write


@pytest.fixture(scope="session")
def dask_cluster(tmp_path_factory: pytest.TempPathFactory):
    """A real ``dask scheduler`` and two ``dask worker --nthreads 1`` processes on 127.0.0.1 (random free ports), started
    once per test session: a start costs seconds (each worker imports fearguard on its first row), so the tests that run
    plans on Dask share it; a test that kills a worker starts another before it ends. Every process ends with the session."""
    pytest.importorskip("distributed", reason="Dask is not installed (pip install 'fearguard[cluster]')")
    from tests.drive.dask_cluster import DaskProcesses

    processes = DaskProcesses(tmp_path_factory.mktemp("dask"))
    try:
        processes.add_workers(2)
        yield processes
    finally:
        processes.close()
