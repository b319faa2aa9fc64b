"""Pictures of a rule base: membership functions and fear surfaces (PNG, matplotlib)."""

from __future__ import annotations

from pathlib import Path

import matplotlib

matplotlib.use("Agg")  # files only: no screen on the cars and CI machines this runs on
import matplotlib.pyplot as plt
import numpy as np

from fearguard.cues import CUE_NAMES
from fearguard.fuzzy.rulebase import RuleBase


def _best_cues(rb: RuleBase) -> np.ndarray:
    """A calm reference point: every cue at its least fearful value."""
    return np.array([1.0, sum(rb.brightness_band) / 2.0, 0.0, np.inf, 0.0])


def plot_rules(rb: RuleBase, out_dir: str | Path) -> list[Path]:
    """Write memberships.png, fear_by_cue.png and one fear_<group>.png per group; return the paths."""
    out = Path(out_dir)
    out.mkdir(parents=True, exist_ok=True)
    written = []
    variables = [*rb.variables.values(), rb.fear_variable]
    fig, axes = plt.subplots(len(variables), 1, figsize=(7, 2.2 * len(variables)), squeeze=False)
    for ax, var in zip(axes[:, 0], variables, strict=True):
        for term, mf in var.terms.items():
            ax.plot(var.universe, mf, label=term)
        if var.normal_band is not None:
            ax.axvspan(*var.normal_band, color="green", alpha=0.08, label="normal band")
        ax.set_title(var.name, fontsize=9)
        ax.set_ylim(-0.02, 1.05)
        ax.legend(fontsize=7, loc="center right")
    fig.tight_layout()
    written.append(out / "memberships.png")
    fig.savefig(written[-1], dpi=90)
    plt.close(fig)

    base = _best_cues(rb)
    names = list(rb.variables)
    fig, axes = plt.subplots(len(names), 1, figsize=(7, 2.0 * len(names)), squeeze=False)
    for ax, name in zip(axes[:, 0], names, strict=True):
        u = rb.variables[name].universe
        x = np.tile(base, (len(u), 1))
        x[:, CUE_NAMES.index(name)] = u
        ax.plot(u, rb.evaluate_batch(x), color="crimson")
        ax.set_title(f"fear vs {name} (other cues calm)", fontsize=9)
        ax.set_ylim(0, 1)
    fig.tight_layout()
    written.append(out / "fear_by_cue.png")
    fig.savefig(written[-1], dpi=90)
    plt.close(fig)

    for gi, group in enumerate(rb.groups):
        fig, ax = plt.subplots(figsize=(6, 4.5))
        first = group.inputs[0]
        ua = rb.variables[first].universe
        if len(group.inputs) == 1:
            x = np.tile(base, (len(ua), 1))
            x[:, CUE_NAMES.index(first)] = ua
            ax.plot(ua, rb.group_fears_batch(x)[:, gi])
            ax.set_xlabel(first)
            ax.set_ylabel("fear")
            ax.set_ylim(0, 1)
        else:
            second = group.inputs[1]
            ub = rb.variables[second].universe
            a = np.linspace(ua[0], ua[-1], 120)
            b = np.linspace(ub[0], ub[-1], 120)
            ga, gb = np.meshgrid(a, b, indexing="ij")
            x = np.tile(base, (ga.size, 1))
            x[:, CUE_NAMES.index(first)] = ga.ravel()
            x[:, CUE_NAMES.index(second)] = gb.ravel()
            fear = rb.group_fears_batch(x)[:, gi].reshape(ga.shape)
            mesh = ax.pcolormesh(b, a, fear, vmin=0, vmax=1, cmap="inferno", shading="auto")
            fig.colorbar(mesh, ax=ax, label="fear")
            ax.set_xlabel(second)
            ax.set_ylabel(first)
        ax.set_title(f"group {group.name} ({group.cause.value})", fontsize=10)
        fig.tight_layout()
        written.append(out / f"fear_{group.name}.png")
        fig.savefig(written[-1], dpi=90)
        plt.close(fig)
    return written
