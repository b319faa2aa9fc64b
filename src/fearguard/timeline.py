"""A run's timeline: per-frame columns of cues and decisions (``Trace``), and its plot (timeline.png).

The recorder fills a Trace frame by frame in memory, so the plot needs no read-back of the log. Values
are plain floats: NaN where a frame had no Command (unsupervised run) or no reading; infinite ranges
and staleness are clipped for the plot only.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from pathlib import Path

from fearguard.cues import CUE_NAMES
from fearguard.report import MODE_ORDER
from fearguard.supervisor import Command

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


def plot_timeline(trace: Trace, path: str | Path, title: str = "", with_speed: bool = False) -> Path:
    """Cues, fear, speed limit (and the vehicle's speed with ``with_speed``) and mode over time, one PNG."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    t = trace.t_s
    fig, axes = plt.subplots(5, 1, figsize=(11, 11), sharex=True)
    for name in ("lane_confidence", "occlusion"):
        axes[0].plot(t, trace.cues[name], label=name)
    axes[0].set_ylim(-0.05, 1.05)
    axes[0].legend(loc="upper right")
    axes[1].plot(t, trace.cues["brightness"], color="goldenrod", label="brightness")
    ax2 = axes[1].twinx()
    ax2.plot(t, [min(RANGE_CLIP_M, v) for v in trace.cues["obstacle_range_m"]], color="crimson", label="obstacle_range_m (≤10)")
    ax2.plot(t, [min(STALENESS_CLIP_S, v) for v in trace.cues["qr_staleness_s"]], color="slateblue", label="qr_staleness_s (≤60)")
    axes[1].legend(loc="upper left")
    ax2.legend(loc="upper right")
    axes[2].plot(t, trace.fear, color="black", label="fear")
    axes[2].set_ylim(-0.05, 1.05)
    axes[2].legend(loc="upper right")
    axes[3].plot(t, trace.speed_limit_mps, label="speed_limit_mps")
    if with_speed:
        axes[3].plot(t, trace.speed_mps, label="speed_mps")
    axes[3].legend(loc="upper right")
    axes[4].step(t, [MODE_ORDER.index(m) if m in MODE_ORDER else -1 for m in trace.mode], where="post")
    axes[4].set_yticks(range(len(MODE_ORDER)), MODE_ORDER)
    axes[4].set_xlabel("t [s]")
    fig.suptitle(title)
    fig.tight_layout()
    path = Path(path)
    fig.savefig(path, dpi=90)
    plt.close(fig)
    return path
