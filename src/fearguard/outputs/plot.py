"""Pictures of a rule base: membership functions and fear surfaces (PNG, matplotlib)."""

from __future__ import annotations

from pathlib import Path

import matplotlib

matplotlib.use("Agg")  # files only: no screen on the cars and CI machines this runs on
import matplotlib.pyplot as plt
import numpy as np

from fearguard.cues import CUE_NAMES, CUE_SPECS, calm_values
from fearguard.fuzzy.rulebase import RuleBase

UNITS = {**{spec.name: spec.unit for spec in CUE_SPECS}, "fear": "0..1"}


def _axis_label(name: str) -> str:
    return f"{name} ({UNITS[name]})" if name in UNITS else name


def _thresholds(ax: plt.Axes, rb: RuleBase, horizontal: bool = True) -> None:
    """The policy's caution and emergency fear thresholds, labelled, so a curve can be read against them."""
    draw = ax.axhline if horizontal else ax.axvline
    draw(rb.policy.caution_fear, color="orange", ls="--", lw=1, label=f"caution {rb.policy.caution_fear:.2f}")
    draw(rb.policy.emergency_enter_fear, color="red", ls="--", lw=1, label=f"emergency {rb.policy.emergency_enter_fear:.2f}")


def _best_cues(rb: RuleBase) -> np.ndarray:
    """A calm reference point: every cue at its least fearful value."""
    return np.array(calm_values(rb.brightness_band))


def plot_rules(rb: RuleBase, out_dir: str | Path) -> list[Path]:
    """Write memberships.png, fear_by_cue.png and one fear_<group>.png per group; return the paths."""
    out = Path(out_dir)
    out.mkdir(parents=True, exist_ok=True)
    written = []
    variables = [*rb.variables.values(), rb.fear_variable]
    fig, axes = plt.subplots(len(variables), 1, figsize=(8.5, 2.3 * len(variables)), squeeze=False)
    for ax, var in zip(axes[:, 0], variables, strict=True):
        for term, mf in var.terms.items():
            ax.plot(var.universe, mf, label=term)
        if var.normal_band is not None:
            ax.axvspan(*var.normal_band, color="green", alpha=0.08, label="normal band")
        if var is rb.fear_variable:
            _thresholds(ax, rb, horizontal=False)
        ax.set_title(f"{var.name}: terms", fontsize=9)
        ax.set_xlabel(_axis_label(var.name), fontsize=8)
        ax.set_ylabel("membership", fontsize=8)
        ax.set_ylim(-0.02, 1.05)
        ax.legend(fontsize=7, loc="upper left", bbox_to_anchor=(1.01, 1.0), borderaxespad=0.0)  # beside the plot, never on a curve
    fig.suptitle(f"{rb.name}: membership functions", fontsize=10)
    fig.tight_layout()
    written.append(out / "memberships.png")
    fig.savefig(written[-1], dpi=90)
    plt.close(fig)

    base = _best_cues(rb)
    names = list(rb.variables)
    fig, axes = plt.subplots(len(names), 1, figsize=(8.5, 2.2 * len(names)), squeeze=False)
    for ax, name in zip(axes[:, 0], names, strict=True):
        u = rb.variables[name].universe
        x = np.tile(base, (len(u), 1))
        x[:, CUE_NAMES.index(name)] = u
        ax.plot(u, rb.evaluate_batch(x), color="crimson", label="fear")
        _thresholds(ax, rb)
        ax.set_title(f"fear vs {name} (other cues calm)", fontsize=9)
        ax.set_xlabel(_axis_label(name), fontsize=8)
        ax.set_ylabel("fear", fontsize=8)
        ax.set_ylim(0, 1.02)
        ax.legend(fontsize=7, loc="upper left", bbox_to_anchor=(1.01, 1.0), borderaxespad=0.0)
    fig.suptitle(f"{rb.name}: fear along each cue", fontsize=10)
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
            _thresholds(ax, rb)
            ax.set_xlabel(_axis_label(first))
            ax.set_ylabel("group fear")
            ax.set_ylim(0, 1.02)
            ax.legend(fontsize=7, loc="best")
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
            bar = fig.colorbar(mesh, ax=ax, label="group fear")
            for level, colour in ((rb.policy.caution_fear, "orange"), (rb.policy.emergency_enter_fear, "red")):
                bar.ax.axhline(level, color=colour, lw=1.5)
            ax.contour(b, a, fear, levels=[rb.policy.caution_fear, rb.policy.emergency_enter_fear], colors=["orange", "red"],
                       linewidths=1)
            ax.set_xlabel(_axis_label(second))
            ax.set_ylabel(_axis_label(first))
        ax.set_title(f"group {group.name} ({group.cause.value})", fontsize=10)
        fig.tight_layout()
        written.append(out / f"fear_{group.name}.png")
        fig.savefig(written[-1], dpi=90)
        plt.close(fig)
    return written
