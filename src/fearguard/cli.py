"""Command line: ``fearguard demo``, ``fearguard rules check|plot|explain``.

A thin layer: it parses arguments, calls the library, prints, and maps errors to exit codes
(0 fine, 1 a check failed, 2 bad input: ``Type: message`` on stderr).
"""

from __future__ import annotations

import argparse
import math
import sys
from collections.abc import Sequence

from fearguard.cues import CUE_NAMES, Cues
from fearguard.errors import FearguardError
from fearguard.fuzzy.check import check_rules
from fearguard.fuzzy.loader import load_rules
from fearguard.policy import Lead
from fearguard.supervisor import FearGuard, Observation

EXPLAIN_SETTLE_S = 10.0  # [s] explain shows the command after this long with the same cues
EXPLAIN_RATE_HZ = 10.0  # [Hz] frame rate of that settling run
CALM = {"lane_confidence": 0.9, "brightness": 120.0, "occlusion": 0.0, "obstacle_range_m": math.inf, "qr_staleness_s": 0.5}


def _parse_cues(text: str) -> Cues:
    values = dict(CALM)
    for item in filter(None, (p.strip() for p in text.split(","))):
        name, sep, raw = item.partition("=")
        if not sep or name.strip() not in CUE_NAMES:
            raise FearguardError(f"--cues: {item!r} is not NAME=VALUE with NAME one of {', '.join(CUE_NAMES)}")
        try:
            values[name.strip()] = float(raw)
        except ValueError:
            raise FearguardError(f"--cues: {name.strip()}={raw!r} is not a number (nan and inf are allowed)") from None
    return Cues(**values)


def _settle(guard: FearGuard, cues: Cues, lead: Lead | None) -> object:
    """Run the guard on constant cues, the car driving at the limit, and return the last command."""
    speed, cmd = 0.0, None
    for k in range(int(EXPLAIN_SETTLE_S * EXPLAIN_RATE_HZ) + 1):
        cmd = guard.step(Observation(t_s=k / EXPLAIN_RATE_HZ, speed_mps=speed, cues=cues, lead=lead))
        speed = cmd.speed_limit_mps
    return cmd


def cmd_check(args: argparse.Namespace) -> int:
    report = check_rules(load_rules(args.file))
    print("\n".join(report.lines()))
    return 0 if report.ok else 1


def cmd_plot(args: argparse.Namespace) -> int:
    from fearguard.plot import plot_rules

    for path in plot_rules(load_rules(args.file), args.out):
        print(path)
    return 0


def cmd_explain(args: argparse.Namespace) -> int:
    rules = load_rules(args.rules)
    cues = _parse_cues(args.cues)
    result = rules.evaluate(cues)
    print("cues:  " + ", ".join(f"{n}={getattr(cues, n):g}" for n in CUE_NAMES))
    print(f"fear:  {result.fear:.3f}  level {result.level.name}  dominant cause {result.dominant_cause.value}")
    print("groups: " + ", ".join(f"{g}={f:.3f}" for g, f in result.group_fears.items()))
    print("top rules:")
    for text, strength in result.top_rules(args.top):
        print(f"  {strength:.2f}  {text}")
    lead = Lead(args.lead_bearing, args.lead_range) if args.lead_bearing is not None else None
    cmd = _settle(FearGuard(lambda frame: 0.0, rules=rules), cues, lead)
    print(f"command after {EXPLAIN_SETTLE_S:g} s with these cues (steering function says 0 deg):")
    print(f"  mode {cmd.mode.name}, strategy {cmd.strategy.name}, speed limit {cmd.speed_limit_mps:.2f} m/s, "
          f"steering {cmd.steering_deg:+.1f} deg")
    for reason in cmd.reasons:
        print(f"  - {reason}")
    return 0


def cmd_demo(args: argparse.Namespace) -> int:
    """A scripted cue-level drive through each hazard: what the supervisor does, frame by frame."""
    from fearguard.demo import demo_drive

    for line in demo_drive(load_rules(args.rules)):
        print(line)
    return 0


def build_parser() -> argparse.ArgumentParser:
    parser = argparse.ArgumentParser(prog="fearguard", description=__doc__.splitlines()[0])
    sub = parser.add_subparsers(dest="command", required=True)
    demo = sub.add_parser("demo", help="a scripted drive through glare, occlusion, an obstacle and stale QR")
    demo.add_argument("--rules", default=None, help="rule file (default: the bundled model-car rules)")
    demo.set_defaults(func=cmd_demo)
    rules = sub.add_parser("rules", help="check, plot or explain a rule base")
    rsub = rules.add_subparsers(dest="rules_command", required=True)
    check = rsub.add_parser("check", help="validate; prove completeness and monotonicity on a dense grid")
    check.add_argument("file", nargs="?", default=None)
    check.set_defaults(func=cmd_check)
    plot = rsub.add_parser("plot", help="membership functions and fear surfaces as PNG")
    plot.add_argument("file", nargs="?", default=None)
    plot.add_argument("--out", required=True, help="directory for the PNG files")
    plot.set_defaults(func=cmd_plot)
    explain = rsub.add_parser("explain", help="fear, level, top rules and the command for given cues")
    explain.add_argument("--cues", required=True, help="e.g. lane_confidence=0.2,occlusion=0.8 (others calm)")
    explain.add_argument("--rules", default=None, help="rule file (default: bundled)")
    explain.add_argument("--lead-bearing", type=float, default=None, help="a lead vehicle at this bearing (deg, + left)")
    explain.add_argument("--lead-range", type=float, default=None, help="its range (m)")
    explain.add_argument("--top", type=int, default=3, help="how many rules to show")
    explain.set_defaults(func=cmd_explain)
    return parser


def main(argv: Sequence[str] | None = None) -> int:
    args = build_parser().parse_args(argv)
    try:
        return int(args.func(args))
    except FearguardError as exc:
        print(f"{type(exc).__name__}: {exc}", file=sys.stderr)
        return 2
    except BrokenPipeError:  # output piped into `head`: stop quietly
        sys.stderr.close()
        return 0


if __name__ == "__main__":  # pragma: no cover
    sys.exit(main())
