"""A run's timeline: per-frame columns of cues and decisions (``Trace``), and its plot (timeline.png).

The recorder fills a Trace frame by frame in memory, so the plot needs no read-back of the log. Values
are plain floats: NaN where a frame had no Command (unsupervised run) or no reading; infinite ranges
and staleness are clipped for the plot only.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from pathlib import Path
from typing import TYPE_CHECKING

from fearguard.cues import CUE_NAMES, CUE_SPECS
from fearguard.policy import MODE_ORDER
from fearguard.supervisor import Command

if TYPE_CHECKING:
    from matplotlib.axes import Axes
    from matplotlib.figure import Figure

    from fearguard.fuzzy.rulebase import RuleBase

RANGE_CLIP_M = 10.0  # [m] obstacle range drawn up to this
STALENESS_CLIP_S = 60.0  # [s] QR staleness drawn up to this


@dataclass
class Trace:
    """Per-frame columns for the timeline plot (NaN where a frame had no Command or no value)."""

    t_s: list[float] = field(default_factory=list)
    cues: dict[str, list[float]] = field(default_factory=lambda: {name: [] for name in CUE_NAMES})
    fear: list[float] = field(default_factory=list)
    speed_limit_mps: list[float] = field(default_factory=list)
    speed_mps: list[float] = field(default_factory=list)
    mode: list[str | None] = field(default_factory=list)
    strategy: list[str | None] = field(default_factory=list)

    def add(self, t_s: float, cmd: Command | None, speed_mps: float | None = None) -> None:
        """Append one frame (``speed_mps``: the vehicle's speed when the driver knows it)."""
        self.t_s.append(t_s)
        values = cmd.cues.values() if cmd is not None else (math.nan,) * len(CUE_NAMES)
        for name, value in zip(CUE_NAMES, values, strict=True):
            self.cues[name].append(value)
        self.fear.append(cmd.fear if cmd is not None else math.nan)
        self.speed_limit_mps.append(cmd.speed_limit_mps if cmd is not None else math.nan)
        self.speed_mps.append(math.nan if speed_mps is None else speed_mps)
        self.mode.append(cmd.mode.name if cmd is not None else None)
        self.strategy.append(cmd.strategy.name if cmd is not None else None)


STRATEGY_COLOURS = {"FOLLOW_LEAD": "tab:blue", "CRAWL": "tab:orange", "STOP": "tab:red"}  # PASS_THROUGH: no shading


def plot_timeline(trace: Trace, path: str | Path, title: str = "", with_speed: bool = False, rules: RuleBase | None = None) -> Path:
    """``timeline_figure`` as a PNG at ``path``."""
    path = Path(path)
    timeline_figure(trace, title, with_speed, rules).savefig(path, dpi=90, pil_kwargs={"compress_level": 1})  # fast deflate
    return path


def timeline_figure(trace: Trace, title: str = "", with_speed: bool = False, rules: RuleBase | None = None) -> Figure:
    """Cues, fear, speed limit (and the vehicle's speed with ``with_speed``), mode and strategy over time.

    Every panel has its unit and a fixed scale where the quantity has one (brightness 0–255, shares and fear 0–1),
    so camera noise is not magnified; ``rules``: the supervisor's rule base, whose caution and emergency thresholds
    are drawn on the fear and whose normal brightness band is shaded. Legends sit in a fixed right margin, clear of
    the data (a constrained layout costs ~0.25 s more). Built on a bare ``matplotlib.figure.Figure``: files only, no
    pyplot to import.
    """
    from matplotlib.figure import Figure

    t = trace.t_s
    fig = Figure(figsize=(11, 12.5))
    axes = fig.subplots(6, 1, sharex=True, height_ratios=(1, 1, 1, 1, 1, 0.8))
    fig.subplots_adjust(left=0.105, right=0.79, top=0.965, bottom=0.045, hspace=0.12)  # fixed: legends fit on the right
    cue, light, rng, fear, speed, mode = axes
    for spec in CUE_SPECS:
        if spec.panel == "share":  # the cues that are shares 0..1 (cues.CUE_SPECS decides)
            cue.plot(t, trace.cues[spec.name], lw=1, label=spec.name)
    cue.set(ylim=(-0.05, 1.05), ylabel="share (0–1)")
    light.plot(t, trace.cues["brightness"], color="goldenrod", lw=1, label="brightness")
    if rules is not None:
        low, high = rules.brightness_band
        light.axhspan(low, high, color="goldenrod", alpha=0.12, lw=0, label=f"normal band {low:.0f}–{high:.0f}")
    light.set(ylim=(0, 255), yticks=(0, 64, 128, 192, 255), ylabel="grey level (0–255)")
    rng.plot(t, [min(RANGE_CLIP_M, v) for v in trace.cues["obstacle_range_m"]], color="crimson", lw=1,
             label="obstacle range")
    rng.set(ylim=(0, RANGE_CLIP_M * 1.05), ylabel=f"range (m, ≤ {RANGE_CLIP_M:g})")
    staleness = trace.cues["qr_staleness_s"]
    if any(math.isfinite(v) and v > 0 for v in staleness):  # a car without QR localisation has none: no empty axis
        stale = rng.twinx()
        stale.plot(t, [min(STALENESS_CLIP_S, v) for v in staleness], color="slateblue", lw=1, label="QR staleness")
        stale.set(ylim=(0, STALENESS_CLIP_S * 1.05), ylabel=f"QR staleness (s, ≤ {STALENESS_CLIP_S:.0f})")
        _legend(rng, extra=stale, x=1.09)  # beyond the twin axis's labels
    else:
        _legend(rng)
    fear.plot(t, trace.fear, color="black", lw=1, label="fear")
    if rules is not None:
        p = rules.policy
        fear.axhline(p.caution_fear, color="orange", ls="--", lw=1, label=f"caution ≥ {p.caution_fear:g}")
        fear.axhline(p.emergency_enter_fear, color="red", ls="--", lw=1, label=f"emergency ≥ {p.emergency_enter_fear:g}")
    fear.set(ylim=(-0.05, 1.05), ylabel="fear (0–1)")
    speed.plot(t, trace.speed_limit_mps, lw=1, label="speed limit")
    if with_speed:
        speed.plot(t, trace.speed_mps, lw=1, label="speed")
    speed.set_ylim(bottom=0)
    speed.set_ylabel("speed (m/s)")
    levels = [MODE_ORDER.index(m) if m in MODE_ORDER else math.nan for m in trace.mode]
    mode.step(t, levels, where="post", color="black", lw=1.2, label="mode")
    for name, colour in STRATEGY_COLOURS.items():
        where = [s == name for s in trace.strategy]
        if any(where):
            mode.fill_between(t, -0.4, len(MODE_ORDER) - 0.6, where=where, step="post", color=colour, alpha=0.3, lw=0,
                              label=f"strategy {name}")
    mode.set(ylim=(-0.4, len(MODE_ORDER) - 0.6), yticks=range(len(MODE_ORDER)), yticklabels=MODE_ORDER, ylabel="mode", xlabel="t (s)")
    for ax in (cue, light, fear, speed, mode):
        _legend(ax)
    if t:
        mode.set_xlim(t[0], t[-1] if t[-1] > t[0] else t[0] + 1.0)
    if title:
        fig.suptitle(title)
    return fig


def _legend(ax: Axes, extra: Axes | None = None, x: float = 1.01) -> None:
    """The panel's legend to the right of it, clear of the data (``extra``: a twin axis whose lines join it)."""
    handles, labels = ax.get_legend_handles_labels()
    if extra is not None:
        more = extra.get_legend_handles_labels()
        handles, labels = handles + more[0], labels + more[1]
    ax.legend(handles, labels, loc="upper left", bbox_to_anchor=(x, 1.0), borderaxespad=0.0, fontsize="small", frameon=False)
