"""Fear ranks the labelled road pictures as a person does (benchmarks/eval_fear_auroc.py, held-out half)."""

from __future__ import annotations

import sys
from pathlib import Path

import pytest

BENCHMARKS = Path(__file__).resolve().parents[2] / "benchmarks"
sys.path.insert(0, str(BENCHMARKS))
import eval_fear_auroc as labelled  # noqa: E402  (the evaluation script is the single home of the method)


def test_labels_cover_every_kind_of_picture():
    rows = labelled.load("all")
    assert len(rows) == 224
    assert {r["half"] for r in rows} == {"tune", "eval"}
    assert {r["visible"] for r in rows} == {"both", "one", "none"}
    assert {r["exposure"] for r in rows} == {"ok", "dark", "glare"}


@pytest.mark.slow
def test_fear_auroc_on_the_held_out_half(shared_data: Path):
    scored = labelled.score(labelled.load("eval"))
    lost, degraded = labelled.aurocs(scored)
    assert lost >= 0.85, f"AUROC lost {lost:.3f}"
    assert degraded >= 0.75, f"AUROC degraded vs clean {degraded:.3f}"


def test_auroc_counts_ties_half():
    assert labelled.auroc([0.9, 0.5], [0.1, 0.5]) == 0.875
