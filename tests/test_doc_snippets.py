"""Every python and bash block of README.md and docs/*.md runs as written (issue 37).

A block runs unless the line before its fence says otherwise, with the reason:
``<!-- snippet: skip — why -->`` (not here: e.g. another environment runs it, or it names a user's files),
``<!-- snippet: slow — why -->`` (run with the slow tests) or ``<!-- snippet: needs MODULE — why -->`` (run where MODULE
imports: .ci/highway.sh runs the highway-env blocks in its environment). Blocks run in a fresh folder laid out like a
clone (its .venv, rules/, scenarios/, benchmarks/ and ``../shared/data`` reached as in the README), python blocks by
this interpreter, bash blocks by bash with ``set -euo pipefail``.
"""

from __future__ import annotations

import importlib.util
import os
import re
import subprocess
import sys
from dataclasses import dataclass
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
DOCS = [ROOT / "README.md", *sorted((ROOT / "docs").glob("*.md"))]
MARKER = re.compile(r"<!-- snippet: (skip|slow|needs (\w+)) — (.+?) -->")
BLOCK = re.compile(r"^```(python|bash)\n(.*?)^```", re.S | re.M)
LINKED = (".venv", "rules", "scenarios", "benchmarks", "src", "docs", "README.md", "pyproject.toml")


@dataclass(frozen=True)
class Snippet:
    doc: str
    line: int
    language: str
    code: str
    mode: str  # "run", "skip", "slow", "needs"
    needs: str | None
    why: str

    @property
    def id(self) -> str:
        return f"{self.doc}:{self.line}-{self.mode}" + (f"_{self.needs}" if self.needs else "")


def snippets() -> list[Snippet]:
    found = []
    for doc in DOCS:
        text = doc.read_text(encoding="utf-8")
        for m in BLOCK.finditer(text):
            before = text[: m.start()].rstrip("\n").rsplit("\n", 1)[-1]
            marker = MARKER.fullmatch(before.strip())
            mode, needs, why = ("run", None, "") if marker is None else (marker[1].split()[0], marker[2], marker[3])
            found.append(Snippet(str(doc.relative_to(ROOT)), text[: m.start()].count("\n") + 1, m[1], m[2], mode, needs, why))
    return found


SNIPPETS = snippets()


def test_every_block_that_does_not_run_here_says_why() -> None:
    assert len(SNIPPETS) >= 28
    for s in SNIPPETS:
        assert s.mode == "run" or len(s.why) > 20, s.id
    assert sum(s.mode == "run" for s in SNIPPETS) >= 1


def _sandbox(tmp_path: Path) -> Path:
    """A folder laid out like a clone beside shared/: the README's relative paths work, outputs stay in tmp_path."""
    clone = tmp_path / "clone"
    clone.mkdir()
    for name in LINKED:
        if (ROOT / name).exists():
            (clone / name).symlink_to(ROOT / name)
    shared = ROOT.parent / "shared"
    if shared.exists():
        (tmp_path / "shared").symlink_to(shared)
    return clone


def _run(snippet: Snippet, tmp_path: Path) -> None:
    if snippet.needs is not None and importlib.util.find_spec(snippet.needs) is None:
        pytest.skip(f"{snippet.needs} is not installed here: {snippet.why}")
    clone = _sandbox(tmp_path)
    env = {**os.environ, "MPLBACKEND": "Agg", "PYTHONPATH": str(ROOT)}
    if snippet.language == "python":
        argv = [sys.executable, "-c", snippet.code]
    else:
        argv = ["bash", "-euo", "pipefail", "-c", snippet.code]
    done = subprocess.run(argv, cwd=clone, capture_output=True, text=True, timeout=1200, env=env, stdin=subprocess.DEVNULL)
    output = f"--- stdout\n{done.stdout[-3000:]}\n--- stderr\n{done.stderr[-3000:]}"
    assert done.returncode == 0, f"{snippet.id} failed:\n{snippet.code}\n{output}"


@pytest.mark.parametrize("snippet", [s for s in SNIPPETS if s.mode in ("run", "needs")], ids=lambda s: s.id)
def test_the_block_runs_as_written(snippet: Snippet, tmp_path: Path) -> None:
    _run(snippet, tmp_path)


@pytest.mark.slow
@pytest.mark.parametrize("snippet", [s for s in SNIPPETS if s.mode == "slow"], ids=lambda s: s.id)
def test_the_slow_block_runs_as_written(snippet: Snippet, tmp_path: Path) -> None:
    _run(snippet, tmp_path)
