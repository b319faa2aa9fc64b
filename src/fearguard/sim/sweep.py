"""A sweep over the numbers of the rule file and the vehicle: every combination × scenario × seed guarded, the unguarded
car once on the same scenarios and seeds, and which combinations keep the car safe at the least cost in progress.

``--set policy.hold_s=1,2,3 --set vehicle.max_speed_mps=1.5,2`` names dotted keys as the files do: ``policy.KEY`` is a
key of a rule file's ``[policy]`` table (``PolicyConfig``; each scenario's own rule file is the base), ``vehicle.KEY`` a
field of the supervisor's ``VehicleLimits`` (vehicle.toml; the car's physics stay the scenario's). Values are TOML
values (``1.5``, ``true``, ``"route"``). An unknown key gets "did you mean"; every combination is validated against every
scenario's rule file and vehicle through the same checks as the files (``fuzzy.loader.policy_with``, VehicleLimits), so
a sweep that would fail does so before it runs.

Rows are the simulator's suite rows (``sim/suite.py``'s ``run_row``): a guarded row carries its combination in the
spec's options (``"policy"``, ``"vehicle"``) and in its name, so it stays JSON-able, deterministic and resumable, and
runs on Dask like any row. ``merge`` gives per combination: collisions, lane departures, progress as a share of the
unguarded car's distance on the same scenarios and seeds, and time in EMERGENCY; the safe combinations (zero collisions,
zero departures) ranked by progress; and the Pareto front of incidents against progress, which ``sweep_figure`` plots.
"""

from __future__ import annotations

import itertools
import tomllib
from collections.abc import Iterable, Mapping, Sequence
from dataclasses import dataclass, fields, replace
from pathlib import Path
from typing import TYPE_CHECKING, Any

from fearguard.drive.plan import RunSpec
from fearguard.errors import SweepError
from fearguard.files.reader import suggestion
from fearguard.fuzzy.loader import load_rules, policy_with
from fearguard.policy.config import PolicyConfig
from fearguard.sim.scenario import load_scenario
from fearguard.vehicle import VehicleLimits

if TYPE_CHECKING:
    from matplotlib.figure import Figure

SECTIONS: dict[str, tuple[str, ...]] = {  # the numbers a sweep may set, by the file section they belong to
    "policy": tuple(f.name for f in fields(PolicyConfig) if f.name != "speed_fraction"),
    "vehicle": tuple(f.name for f in fields(VehicleLimits)),
}
KNOWN = tuple(f"{section}.{key}" for section, keys in SECTIONS.items() for key in keys)
FORM = "KEY=V1,V2,... with KEY one of policy.* (a rule file's [policy] table) or vehicle.* (VehicleLimits)"


@dataclass(frozen=True)
class Setting:
    """One ``--set``: a dotted key and the values to try, in the order given."""

    key: str  # e.g. "policy.hold_s"
    values: tuple[Any, ...]

    @property
    def section(self) -> str:
        return self.key.partition(".")[0]

    @property
    def name(self) -> str:
        return self.key.partition(".")[2]


def parse_setting(text: str) -> Setting:
    """``policy.hold_s=1,2,3`` → Setting; a SweepError naming the fix for an unknown key, a missing value or one that is
    not a TOML value."""
    key, sep, raw = text.partition("=")
    key = key.strip()
    if not sep or not key:
        raise SweepError(f"--set {text!r}: write {FORM}")
    if key == "policy.speed_fraction":
        raise SweepError("--set policy.speed_fraction: a table of five fractions is not swept; write one rule file per "
                         "variant and run the suite on each")
    if key not in KNOWN:
        raise SweepError(f"--set {text!r}: unknown key {key!r}{suggestion(key, KNOWN)}; the keys: policy.* "
                         f"({', '.join(SECTIONS['policy'])}) or vehicle.* ({', '.join(SECTIONS['vehicle'])})")
    items = [item.strip() for item in raw.split(",")]
    if not all(items):
        raise SweepError(f"--set {text!r}: give one or more values, e.g. {key}=1,2,3 (an empty value between commas)")
    values = tuple(_toml_value(key, item) for item in items)
    if len(set(map(repr, values))) != len(values):
        raise SweepError(f"--set {text!r}: a value is given twice")
    return Setting(key, values)  # types and ranges are checked against each scenario's files by ``plan``


def _toml_value(key: str, item: str) -> Any:
    try:
        return tomllib.loads(f"v = {item}")["v"]
    except tomllib.TOMLDecodeError:
        raise SweepError(f"--set {key}: {item!r} is not a value; give a number, true/false or a quoted string") from None


def _show(value: Any) -> str:
    """A value as it is written in a TOML file: 1.5, true, "name"."""
    if isinstance(value, bool):
        return "true" if value else "false"
    return f'"{value}"' if isinstance(value, str) else f"{value:g}" if isinstance(value, float) else str(value)


def _sweep_error(path: str | Path, where: str, problem: str) -> SweepError:
    return SweepError(f"{path}: {problem}")


def _check(combination: Mapping[str, Any], policy: PolicyConfig, limits: VehicleLimits, source: str) -> None:
    """The combination applied to a rule file's policy and a vehicle, validated as their files are (a SweepError)."""
    changes = split(combination)
    if changes["policy"]:
        policy_with(policy, changes["policy"], source, error=_sweep_error)
    try:
        replace(limits, **changes["vehicle"])
    except ValueError as exc:
        raise SweepError(f"{source}: {exc}") from None


def split(combination: Mapping[str, Any]) -> dict[str, dict[str, Any]]:
    """``{"policy.hold_s": 1}`` → ``{"policy": {"hold_s": 1}, "vehicle": {}}``: the options ``run_scenario`` takes."""
    out: dict[str, dict[str, Any]] = {section: {} for section in SECTIONS}
    for key, value in combination.items():
        section, _, name = key.partition(".")
        out[section][name] = value
    return out


def combinations(settings: Sequence[Setting]) -> list[dict[str, Any]]:
    """Every combination of the settings' values (the first setting varies slowest); a key set twice is a SweepError."""
    keys = [s.key for s in settings]
    twice = sorted({k for k in keys if keys.count(k) > 1})
    if twice:
        raise SweepError(f"--set {', '.join(twice)} given more than once; give every value in one --set, e.g. {twice[0]}=1,2")
    return [dict(zip(keys, values, strict=True)) for values in itertools.product(*(s.values for s in settings))]


def label(combination: Mapping[str, Any]) -> str:
    """``policy.hold_s=1 vehicle.max_speed_mps=1.5``: a combination in one line (its rows' names carry it)."""
    return " ".join(f"{k}={_show(v)}" for k, v in combination.items())


def plan(files: Iterable[Path], seeds: int, settings: Sequence[Setting]) -> list[RunSpec]:
    """The unguarded car once per scenario × seed, then every combination guarded on the same scenarios and seeds; every
    combination checked against each scenario's rule file and vehicle first."""
    if not (isinstance(seeds, int) and seeds >= 1):
        raise ValueError(f"seeds must be a whole number >= 1, got {seeds!r}")
    combos = combinations(settings)
    scenarios = [(str(Path(p).resolve()), load_scenario(p)) for p in files]
    policies: dict[str, PolicyConfig] = {}
    for _, scenario in scenarios:
        rules_path = str(scenario.rules_path)
        policy = policies.setdefault(rules_path, load_rules(rules_path).policy)
        for combo in combos:
            _check(combo, policy, scenario.vehicle.limits, f"--set {label(combo)} on scenario {scenario.name} (rules {rules_path})")
    specs = [RunSpec("sim", sc.name, "unguarded", sc.seed + k, {"file": path}) for path, sc in scenarios for k in range(seeds)]
    for combo in combos:
        name = label(combo)
        specs += [RunSpec("sim", f"{sc.name} [{name}]", "guarded", sc.seed + k, {"file": path, **split(combo), "combination": name})
                  for path, sc in scenarios for k in range(seeds)]
    return specs


def merge(rows: Sequence[Mapping[str, Any]]) -> list[dict[str, Any]]:
    """Per combination (plan order): runs, collisions, lane departures, distance, progress (its distance over the unguarded
    car's on the same scenarios and seeds), EMERGENCY seconds (total and per run), safe (no collision, no departure), and
    whether it is on the Pareto front of incidents (collisions + departures) against progress."""
    unguarded = {(r["scenario"], r["seed"]): r for r in rows if r["controller"] == "unguarded"}
    table: dict[str, dict[str, Any]] = {}
    for r in rows:
        if r["controller"] != "guarded":
            continue
        options = r["spec"]["options"]
        t = table.setdefault(options["combination"], {
            "combination": options["combination"], "policy": options.get("policy", {}), "vehicle": options.get("vehicle", {}),
            "runs": 0, "collisions": 0, "lane_departures": 0, "distance_m": 0.0, "unguarded_distance_m": 0.0, "emergency_s": 0.0,
            "compared_runs": 0})
        t["runs"] += 1
        t["collisions"] += r["collisions"]
        t["lane_departures"] += r["lane_departures"]
        t["emergency_s"] += r.get("emergency_s") or 0.0
        base = unguarded.get((r["scenario"], r["seed"]))
        if base is not None:  # progress compares like with like: only the runs whose unguarded twin is there
            t["distance_m"] += r["distance_m"]
            t["unguarded_distance_m"] += base["distance_m"]
            t["compared_runs"] += 1
    out = list(table.values())
    for t in out:
        t["progress"] = t["distance_m"] / t["unguarded_distance_m"] if t["unguarded_distance_m"] > 0 else None
        t["emergency_s_per_run"] = t["emergency_s"] / t["runs"]
        t["incidents"] = t["collisions"] + t["lane_departures"]
        t["safe"] = t["incidents"] == 0
    for t in out:
        t["pareto"] = not any(_dominates(o, t) for o in out)
    return out


def _dominates(a: Mapping[str, Any], b: Mapping[str, Any]) -> bool:
    """``a`` is at least as safe and makes at least as much progress as ``b``, and is strictly better in one."""
    pa, pb = a["progress"] or 0.0, b["progress"] or 0.0
    return a["incidents"] <= b["incidents"] and pa >= pb and (a["incidents"] < b["incidents"] or pa > pb)


def ranked_safe(table: Sequence[Mapping[str, Any]]) -> list[Mapping[str, Any]]:
    """The combinations with no collision and no departure, most progress first (ties: less time in EMERGENCY)."""
    return sorted((t for t in table if t["safe"]), key=lambda t: (-(t["progress"] or 0.0), t["emergency_s"]))


def unguarded_totals(rows: Sequence[Mapping[str, Any]]) -> dict[str, Any]:
    """The unguarded car's runs, collisions and departures on the sweep's scenarios and seeds (the reference)."""
    mine = [r for r in rows if r["controller"] == "unguarded"]
    return {"runs": len(mine), "collisions": sum(r["collisions"] for r in mine), "lane_departures": sum(r["lane_departures"] for r in mine),
            "distance_m": sum(r["distance_m"] for r in mine)}


def row_line(row: Mapping[str, Any]) -> str:
    """One finished run of a sweep in a line: its scenario, seed, controller, combination and outcome."""
    combination = row["spec"]["options"].get("combination") if "spec" in row else None
    return (f"{row['scenario']} seed {row['seed']} {row['controller']}{f' [{combination}]' if combination else ''}: "
            f"collisions {row['collisions']}, departures {row['lane_departures']}, {row['distance_m']:.1f} m")


def _percent(share: float | None) -> str:
    return f"{100 * share:.0f} %" if share is not None else "–"


def sweep_markdown(table: Sequence[Mapping[str, Any]], reference: Mapping[str, Any]) -> str:
    """Every combination, then the safe ones ranked by progress, then the unguarded reference."""
    head = "| combination | runs | collisions | lane departures | progress (of unguarded) | EMERGENCY s (per run) | Pareto |"
    lines = [head, "|---|---|---|---|---|---|---|"]
    lines += [f"| {t['combination']} | {t['runs']} | {t['collisions']} | {t['lane_departures']} | {_percent(t['progress'])} | "
              f"{t['emergency_s']:.1f} ({t['emergency_s_per_run']:.1f}) | {'yes' if t['pareto'] else ''} |" for t in table]
    safe = ranked_safe(table)
    lines += ["", "Safe (no collision, no lane departure), most progress first:", ""]
    if safe:
        lines += ["| rank | combination | progress (of unguarded) | EMERGENCY s |", "|---|---|---|---|"]
        lines += [f"| {i} | {t['combination']} | {_percent(t['progress'])} | {t['emergency_s']:.1f} |" for i, t in enumerate(safe, 1)]
    else:
        lines.append("none: every combination had a collision or a lane departure")
    lines += ["", f"Unguarded on the same scenarios and seeds: {reference['runs']} runs, {reference['collisions']} collisions, "
                  f"{reference['lane_departures']} lane departures, {reference['distance_m']:.1f} m."]
    return "\n".join(lines) + "\n"


def sweep_figure(table: Sequence[Mapping[str, Any]], reference: Mapping[str, Any], title: str = "sweep") -> Figure:
    """Safety against progress: a point per combination (incidents = collisions + lane departures, over progress as a share
    of the unguarded car's), the Pareto front as a step line, the unguarded car at 100 %."""
    from matplotlib.figure import Figure

    fig = Figure(figsize=(10, 6))
    ax = fig.subplots()
    fig.subplots_adjust(left=0.09, right=0.97, top=0.92, bottom=0.1)
    points: dict[tuple[float, int], list[Mapping[str, Any]]] = {}  # combinations that land on one point share a label
    for t in table:
        points.setdefault((round(100 * (t["progress"] or 0.0), 1), t["incidents"]), []).append(t)
    for (x, y), mine in points.items():
        ax.scatter([x], [y], s=40, color="tab:green" if mine[0]["safe"] else "tab:red", zorder=3)
        ax.annotate("\n".join(t["combination"] for t in mine), (x, y), textcoords="offset points", xytext=(6, 4), fontsize="x-small")
    front = sorted({p for p, mine in points.items() if any(t["pareto"] for t in mine)})
    if len(front) > 1:
        ax.step([x for x, _ in front], [y for _, y in front], where="post", color="grey", lw=1, label="Pareto front", zorder=2)
    ref = reference["collisions"] + reference["lane_departures"]
    ax.scatter([100.0], [ref], marker="s", s=50, color="black", label="unguarded", zorder=3)
    xs = [x for x, _ in points] + [100.0]
    ax.set_xlim(min(xs) - 0.15 * (max(xs) - min(xs) + 1), max(xs) + 0.6 * (max(xs) - min(xs) + 1))
    ax.set_ylim(-0.5, max([y for _, y in points] + [ref]) + 1)
    ax.yaxis.get_major_locator().set_params(integer=True)
    ax.set(xlabel="progress (% of the unguarded car's distance, same scenarios and seeds)",
           ylabel="incidents (collisions + lane departures)", title=f"{title}: safety against progress (green: safe)")
    ax.legend(loc="upper left", fontsize="small", frameon=False)
    return fig
