"""What a run leaves behind: the per-frame JSON Lines log, the summary, the plots.

Shared by ``fearguard run`` (simulated scenarios) and ``fearguard replay`` (recorded drives). The log
uses the contract's names (docs/architecture.md): frame, t_s, the five cues, fear, fear_level, mode, strategy, speed_limit_mps,
steering_deg, reasons (plus extra fields a caller adds). Every line is flushed as it is written, so an
interrupted run keeps every frame it processed. JSON has no NaN or infinity: NaN (unknown) is written
as null, ±infinity as the strings "inf" / "-inf".
"""

from __future__ import annotations

import json
import math
from collections.abc import Iterable, Mapping, Sequence
from pathlib import Path
from typing import Any, TextIO

from fearguard.cues import CUE_NAMES
from fearguard.fear import FearLevel
from fearguard.policy import Mode
from fearguard.supervisor import Command

MODE_ORDER = tuple(m.name for m in Mode)
LEVEL_ORDER = tuple(level.name for level in FearLevel)


def json_value(value: Any) -> Any:
    """A value JSON can hold: NaN → None, ±inf → "inf"/"-inf", tuples → lists, enums → names."""
    if isinstance(value, float):
        if math.isnan(value):
            return None
        if math.isinf(value):
            return "inf" if value > 0 else "-inf"
        return value
    if isinstance(value, Mapping):
        return {str(k): json_value(v) for k, v in value.items()}
    if isinstance(value, list | tuple):
        return [json_value(v) for v in value]
    if hasattr(value, "name") and hasattr(value, "value"):
        return value.name
    return value


def from_json_number(value: Any) -> float:
    """The inverse of json_value for numbers: null → NaN, "inf" → inf."""
    return math.nan if value is None else float(value)


def command_record(frame: int, t_s: float, cmd: Command | None, **extra: Any) -> dict[str, Any]:
    """One log line: the contract's fields (docs/architecture.md) from a Command (None: unsupervised run), plus extras."""
    record: dict[str, Any] = {"frame": frame, "t_s": t_s}
    if cmd is not None:
        record.update(zip(CUE_NAMES, cmd.cues.values(), strict=True))
        record.update(
            fear=cmd.fear, fear_level=cmd.fear_level.name, mode=cmd.mode.name, strategy=cmd.strategy.name,
            speed_limit_mps=cmd.speed_limit_mps, steering_deg=cmd.steering_deg, reasons=list(cmd.reasons),
            cause=cmd.cause.value if cmd.cause is not None else "fault",
        )
    record.update(extra)
    return {k: json_value(v) for k, v in record.items()}


class JsonlLog:
    """Append-only JSON Lines file, one flushed line per frame (a crash keeps every line written)."""

    def __init__(self, path: str | Path) -> None:
        self.path = Path(path)
        self.path.parent.mkdir(parents=True, exist_ok=True)
        self._file: TextIO = self.path.open("w", encoding="utf-8")
        self.lines = 0

    def write(self, record: Mapping[str, Any]) -> None:
        self._file.write(json.dumps(record, allow_nan=False, separators=(",", ":")) + "\n")
        self._file.flush()
        self.lines += 1

    def close(self) -> None:
        self._file.close()

    def __enter__(self) -> JsonlLog:
        return self

    def __exit__(self, *exc: object) -> None:
        self.close()


def read_jsonl(path: str | Path) -> list[dict[str, Any]]:
    """Every complete line of a JSON Lines log (a torn last line from a killed writer is left out)."""
    records = []
    for line in Path(path).read_text(encoding="utf-8").splitlines():
        if line.strip():
            try:
                records.append(json.loads(line))
            except json.JSONDecodeError:
                break
    return records


def episodes(records: Sequence[Mapping[str, Any]], mode: str = "EMERGENCY") -> list[dict[str, Any]]:
    """Contiguous stretches in ``mode``: start/end (frame, t_s), the causes and strategies seen, the lowest limit."""
    found: list[dict[str, Any]] = []
    current: dict[str, Any] | None = None
    for r in records:
        if r.get("mode") == mode:
            if current is None:
                current = {"start_frame": r["frame"], "start_t_s": r["t_s"], "causes": {}, "strategies": {},
                           "min_speed_limit_mps": math.inf}
                found.append(current)
            current["end_frame"], current["end_t_s"] = r["frame"], r["t_s"]
            for key, field in (("causes", "cause"), ("strategies", "strategy")):
                current[key][r.get(field)] = current[key].get(r.get(field), 0) + 1
            current["min_speed_limit_mps"] = min(current["min_speed_limit_mps"], from_json_number(r.get("speed_limit_mps")))
            if "first_reasons" not in current:
                current["first_reasons"] = list(r.get("reasons", []))[:4]
        else:
            current = None
    for ep in found:
        ep["cause"] = max(ep["causes"], key=ep["causes"].get)
    return found


def shares(records: Sequence[Mapping[str, Any]], field: str, names: Iterable[str]) -> dict[str, float]:
    """Share of frames with each value of a field (0 for values never seen)."""
    n = max(1, sum(1 for r in records if field in r))
    return {name: sum(1 for r in records if r.get(field) == name) / n for name in names}


def summarize(records: Sequence[Mapping[str, Any]]) -> dict[str, Any]:
    """Frames, share of time per fear level and mode, emergency episodes, and where fear rose (and why)."""
    summary: dict[str, Any] = {"frames": len(records)}
    if not records or "fear" not in records[0]:
        return summary
    summary["fear_level_share"] = shares(records, "fear_level", LEVEL_ORDER)
    summary["mode_share"] = shares(records, "mode", MODE_ORDER)
    summary["emergency_episodes"] = episodes(records)
    summary["elevated_fear"] = elevated(records)
    fears = [from_json_number(r["fear"]) for r in records]
    summary["fear_mean"] = sum(fears) / len(fears)
    summary["fear_max"] = max(fears)
    return json_value(summary)


def elevated(records: Sequence[Mapping[str, Any]], min_level: str = "MEDIUM") -> list[dict[str, Any]]:
    """Stretches with fear at or above ``min_level``: when, how high, and the cue that drove it most often."""
    order = {name: i for i, name in enumerate(LEVEL_ORDER)}
    threshold = order[min_level]
    out: list[dict[str, Any]] = []
    current: dict[str, Any] | None = None
    for r in records:
        if order.get(r.get("fear_level"), 0) >= threshold:
            if current is None:
                current = {"start_t_s": r["t_s"], "peak_fear": 0.0, "causes": {}, "cue_at_peak": {}}
                out.append(current)
            current["end_t_s"] = r["t_s"]
            fear = from_json_number(r["fear"])
            current["causes"][r.get("cause")] = current["causes"].get(r.get("cause"), 0) + 1
            if fear > current["peak_fear"]:
                current["peak_fear"] = fear
                current["peak_t_s"] = r["t_s"]
                current["cue_at_peak"] = {name: r.get(name) for name in CUE_NAMES}
                current["why"] = [x for x in r.get("reasons", []) if x.startswith("rule ")][:2]
        else:
            current = None
    return out


def plot_timeline(records: Sequence[Mapping[str, Any]], path: str | Path, title: str = "", extra_speed: str | None = None) -> Path:
    """Cues, fear, speed limit (and the vehicle's speed if logged) and mode over time, one PNG."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    t = [r["t_s"] for r in records]
    fig, axes = plt.subplots(5, 1, figsize=(11, 11), sharex=True)
    for name, ax in zip(("lane_confidence", "occlusion"), (axes[0], axes[0]), strict=True):
        ax.plot(t, [from_json_number(r.get(name)) for r in records], label=name)
    axes[0].set_ylim(-0.05, 1.05)
    axes[0].legend(loc="upper right")
    axes[1].plot(t, [from_json_number(r.get("brightness")) for r in records], color="goldenrod", label="brightness")
    ax2 = axes[1].twinx()
    ax2.plot(t, [min(10.0, from_json_number(r.get("obstacle_range_m"))) for r in records], color="crimson", label="obstacle_range_m (≤10)")
    ax2.plot(t, [min(60.0, from_json_number(r.get("qr_staleness_s"))) for r in records], color="slateblue", label="qr_staleness_s (≤60)")
    axes[1].legend(loc="upper left")
    ax2.legend(loc="upper right")
    axes[2].plot(t, [from_json_number(r.get("fear")) for r in records], color="black", label="fear")
    axes[2].set_ylim(-0.05, 1.05)
    axes[2].legend(loc="upper right")
    axes[3].plot(t, [from_json_number(r.get("speed_limit_mps")) for r in records], label="speed_limit_mps")
    if extra_speed:
        axes[3].plot(t, [from_json_number(r.get(extra_speed)) for r in records], label=extra_speed)
    axes[3].legend(loc="upper right")
    axes[4].step(t, [MODE_ORDER.index(r["mode"]) if r.get("mode") in MODE_ORDER else -1 for r in records], where="post")
    axes[4].set_yticks(range(len(MODE_ORDER)), MODE_ORDER)
    axes[4].set_xlabel("t [s]")
    fig.suptitle(title)
    fig.tight_layout()
    path = Path(path)
    fig.savefig(path, dpi=90)
    plt.close(fig)
    return path
