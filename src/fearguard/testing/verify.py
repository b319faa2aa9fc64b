"""Search every invariant with hypothesis; shrink a failure into the smallest history; save and replay it.

``verify(subject, examples, seed)`` runs ``hypothesis.find`` for each invariant: up to ``examples``
generated cases, each checked; the first case that breaks the invariant is shrunk by hypothesis into
the smallest one that still does, which becomes the ``Counterexample``. The search is deterministic:
the same subject, examples and seed try the same cases (``random.Random(seed)``, no example database).
"""

from __future__ import annotations

import random
import sys
import warnings
from collections.abc import Callable, Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from hypothesis import HealthCheck, Phase, find, settings
from hypothesis.errors import HypothesisWarning, NoSuchExample

import fearguard as fg
from fearguard.testing.history import Case, load_case, save_case
from fearguard.testing.invariants import INVARIANTS, Invariant, invariant
from fearguard.testing.subject import SetupError, Subject, run

DEFAULT_EXAMPLES = 100  # [cases] per invariant


@dataclass(frozen=True)
class Counterexample:
    """The smallest case hypothesis found that breaks an invariant, and what the checker said about it."""

    invariant: Invariant
    message: str
    case: Case
    subject: Subject

    def commands(self) -> dict[str, list[fg.Command]]:
        return {name: list(run(self.subject, history).commands) for name, history in self.case.runs}

    def text(self, max_frames: int = 12) -> str:
        """A readable report: the broken invariant, why, and the history frame by frame with the commands
        (a long one: its first and last ``max_frames // 2`` frames, where it starts and where it breaks)."""
        out = [f"invariant {self.invariant.number} ({self.invariant.title}) fails: {self.message}"]
        if self.case.note:
            out.append(f"case: {self.case.note}")
        runs = {name: run(self.subject, history) for name, history in self.case.runs}
        cmds = {name: list(r.commands) for name, r in runs.items()}
        scripted = self.subject.steer is None  # else the subject's own function answered: show what it said
        for name, history in self.case.runs:
            out.append(f"run {name!r}, {len(history)} frame(s):")
            half = max(1, max_frames // 2)
            shown = range(len(history)) if len(history) <= max_frames else [*range(half), *range(len(history) - half, len(history))]
            for i in shown:
                if len(history) > max_frames and i == len(history) - half:
                    out.append(f"  ... {len(history) - 2 * half} frame(s) like these (all in the file) ...")
                answered = runs[name].steering_in
                answer = history[i].steer_output if scripted or i >= len(answered) else answered[i]
                out.append(_frame_text(i, history[i], cmds[name][i] if i < len(cmds[name]) else None, answer))
        return "\n".join(out)

    def save(self, path: str | Path) -> Path:
        """Write the case as a replayable JSON Lines history (``fearguard verify --replay FILE``)."""
        header = {"invariant": self.invariant.key, "number": self.invariant.number, "message": self.message, **self.subject.header()}
        return save_case(path, self.case, header, self.commands())


def _frame_text(i: int, step: Any, c: fg.Command | None, answer: Any) -> str:
    obs = f"t={step.t_s!r} v={step.speed_mps!r}"
    if step.cues is not None:
        obs += " cues=(" + ", ".join(repr(getattr(step.cues, n)) for n in fg.CUE_NAMES) + ")"
    if step.frame is not None:
        obs += f" frame={step.frame.to_json()}"
    for fname in ("ultrasonic_range_m", "odometer_m", "qr_payload", "lead"):
        if getattr(step, fname) is not None:
            obs += f" {fname}={getattr(step, fname)!r}"
    obs += f" steer→{answer!r}"
    res = f"{c.mode.name} {c.strategy.name} limit {c.speed_limit_mps:.4g} steer {c.steering_deg:+.4g} fear {c.fear:.3g}" if c else "-"
    return f"  {i:>3} {obs}\n      ⇒ {res}"


@dataclass(frozen=True)
class Outcome:
    """What the search of one invariant found."""

    invariant: Invariant
    examples: int  # cases tried before the first failure (all of them when it passed)
    counterexample: Counterexample | None = None

    @property
    def passed(self) -> bool:
        return self.counterexample is None

    @property
    def result(self) -> str:
        return "ok" if self.counterexample is None else f"FAILED: {self.counterexample.message}"


def search_settings(examples: int, shrink: bool = True) -> settings:
    """Hypothesis settings for a search: no database (deterministic), no deadline, generation (and shrinking)."""
    phases = (Phase.generate, Phase.shrink) if shrink else (Phase.generate,)
    return settings(max_examples=max(1, examples), database=None, deadline=None, derandomize=False,
                    suppress_health_check=list(HealthCheck), phases=phases, report_multiple_bugs=False)


def find_counterexample(inv: Invariant | str, subject: Subject, examples: int = DEFAULT_EXAMPLES, seed: int = 0,
                        shrink: bool = True, on_example: Callable[[int], None] | None = None) -> Outcome:
    """Search one invariant; the shrunk counterexample if any case breaks it (``shrink=False``: the first found).
    ``on_example(n)`` after each case checked (progress)."""
    inv = invariant(inv) if isinstance(inv, str) else inv
    tried = [0, 0]  # cases checked, cases checked before the first failure

    def breaks(case: Case) -> bool:
        tried[0] += 1
        bad = inv.check(subject, case) is not None
        if on_example is not None:
            on_example(tried[0])
        if bad and not tried[1]:
            tried[1] = tried[0]
        return bad

    try:
        with warnings.catch_warnings():  # a long history has a long repr: hypothesis's size warning is noise here
            warnings.simplefilter("ignore", HypothesisWarning)
            case = find(inv.cases(subject), breaks, settings=search_settings(examples, shrink), random=random.Random(seed))
    except NoSuchExample:
        return Outcome(inv, tried[0])
    case = _cut(inv, subject, case) if shrink else case
    case = inv.narrow(subject, case) if inv.narrow is not None else case
    message = inv.check(subject, case)
    return Outcome(inv, tried[1] or tried[0], Counterexample(inv, message or "(no longer fails)", case, subject))


def _cut(inv: Invariant, subject: Subject, case: Case) -> Case:
    """The shortest prefix of a one-run case that still fails (bisection: for a prefix-closed invariant,
    failing is monotone in the length). Shrinking keeps a history's structure; this drops its tail."""
    if not inv.prefix_closed or len(case.runs) != 1:
        return case
    name, history = case.runs[0]

    def prefix(n: int) -> Case:
        return Case(((name, history[:n]),), case.note, case.params)

    lo, hi = 1, len(history)  # prefix(hi) fails
    while lo < hi:
        mid = (lo + hi) // 2
        if inv.check(subject, prefix(mid)) is not None:
            hi = mid
        else:
            lo = mid + 1
    return prefix(hi)


def verify(subject: Subject, examples: int = DEFAULT_EXAMPLES, seed: int = 0, only: Sequence[str] = (),
           on_outcome: Callable[[Outcome], None] | None = None,
           on_example: Callable[[Invariant, int], None] | None = None) -> list[Outcome]:
    """Search every invariant (or those in ``only``), in docs/architecture.md's order; ``on_example(invariant, n)`` after
    each case checked."""
    outcomes = []
    for inv in chosen(only):
        each = None if on_example is None else (lambda n, inv=inv: on_example(inv, n))
        outcome = find_counterexample(inv, subject, examples, seed, on_example=each)
        outcomes.append(outcome)
        if on_outcome is not None:
            on_outcome(outcome)
    return outcomes


def chosen(only: Sequence[str] = ()) -> list[Invariant]:
    """The invariants named in ``only`` by key or number (all when empty); an unknown name is a SetupError."""
    names = {n for inv in INVARIANTS for n in (inv.key, inv.number)}
    unknown = [k for k in only if k not in names]
    if unknown:
        raise SetupError(f"--only {','.join(unknown)}: no such invariant; known: {', '.join(inv.key for inv in INVARIANTS)} "
                         f"or their numbers 1-10")
    return [inv for inv in INVARIANTS if not only or inv.key in only or inv.number in only]


def _echo(line: str) -> None:
    """A line on stdout at once, also into a pipe or a CI log (where print is block-buffered)."""
    print(line, flush=True)


TITLE_WIDTH = max(len(inv.title) for inv in INVARIANTS)  # [chars] the table's invariant column: rows print as they finish


def table_header() -> str:
    return f"{'#':>2}  {'invariant':<{TITLE_WIDTH}}  {'examples':>8}  result"


def table_row(o: Outcome) -> str:
    return f"{o.invariant.number:>2}  {o.invariant.title:<{TITLE_WIDTH}}  {o.examples:>8}  {o.result}"


def table(outcomes: Sequence[Outcome]) -> str:
    """The verify table: number, invariant, examples tried, result."""
    return "\n".join([table_header(), *(table_row(o) for o in outcomes)])


def replay_counterexample(path: str | Path, rules: fg.RuleBase | str | None = None, vehicle: Any = None,
                          steer: Any = None, track: str | None = None) -> tuple[Invariant, str | None]:
    """Re-run a saved counterexample with the subject in its header (or the ones given): the checker's verdict."""
    header, case = load_case(path)
    inv = invariant(str(header.get("invariant", "limits_in_range")))
    if vehicle is None and isinstance(header.get("vehicle"), dict):
        from fearguard.testing.subject import vehicle_from_mapping

        vehicle = vehicle_from_mapping(dict(header["vehicle"]), f"{path}, header vehicle")
    steer_name = header.get("steer")
    if steer is None and isinstance(steer_name, str) and ":" in steer_name:
        steer = steer_name
    track = track if track is not None else header.get("track")
    subject = Subject.of(rules if rules is not None else header.get("rules"), vehicle, steer, track if isinstance(track, str) else None)
    return inv, inv.check(subject, case)


def supervisor_invariants(rules: fg.RuleBase | str | Path | None = None, vehicle: Any = None, steer: Any = None, *,
                          examples: int | None = None, seed: int = 0, only: Sequence[str] = (),
                          counterexamples: str | Path = "fearguard-counterexamples") -> Callable[..., None]:
    """A pytest test, parametrized over every invariant, for one car: rules file, vehicle, steering function.

        from fearguard.testing import supervisor_invariants
        test_my_car = supervisor_invariants(rules="rules/my_car.toml", vehicle=MY_CAR, steer=my_pilot)

    ``examples`` (cases per invariant) defaults to the active hypothesis profile's ``max_examples``. A failure
    shows the shrunk history and writes it to ``counterexamples/<invariant>.jsonl`` (replay it with
    ``fearguard verify --replay FILE``).
    """
    import pytest

    selected = chosen(only)
    state: dict[str, Subject] = {}

    @pytest.mark.parametrize("invariant_key", [inv.key for inv in selected], ids=[f"{inv.number}-{inv.key}" for inv in selected])
    def test_supervisor_invariant(invariant_key: str) -> None:
        if "subject" not in state:
            state["subject"] = Subject.of(rules, vehicle, steer)
        n = examples if examples is not None else settings.default.max_examples
        outcome = find_counterexample(invariant_key, state["subject"], n, seed)
        if outcome.counterexample is not None:
            path = outcome.counterexample.save(Path(counterexamples) / f"{invariant_key}.jsonl")
            pytest.fail(f"{outcome.counterexample.text()}\n(saved to {path}; replay: fearguard verify --replay {path})", pytrace=False)

    return test_supervisor_invariant


def verify_command(rules: str | None, vehicle: str | None, steer: str | None, examples: int, seed: int, out: str | Path,
                   only: Sequence[str] = (), replay: str | None = None, echo: Callable[[str], None] = _echo,
                   progress: Callable[[str], None] = lambda line: print(line, file=sys.stderr, flush=True),
                   track: str | None = None) -> int:
    """``fearguard verify``: the table, a shrunk counterexample file per failure; 0 all hold, 1 one fails.

    With ``replay``: re-run a saved counterexample; 1 if it still breaks its invariant, 0 if not.
    Bad files raise FearguardError (the CLI's exit 2).
    """
    if replay is not None:
        inv, message = replay_counterexample(replay, rules, vehicle, steer, track)
        verdict = f"still fails: {message}" if message else "holds now (the counterexample no longer breaks it)"
        echo(f"{replay}: invariant {inv.number} ({inv.title}) {verdict}")
        return 1 if message else 0
    subject = Subject.of(rules, vehicle, steer, track)
    with_track = f", track {track}" if track else ""
    echo(f"fearguard verify: rules {subject.rules.path} ({subject.rules.name!r}), vehicle {subject.vehicle_name}, "
         f"steer {subject.steer_name}{with_track}, up to {examples} examples per invariant, seed {seed}")
    echo(table_header())
    quarter = max(1, examples // 4)

    def examples_done(inv: Invariant, n: int) -> None:  # the search of one invariant can take a minute: say how far it is
        if n % quarter == 0 and n < examples:
            progress(f"verify: invariant {inv.number} ({inv.title}): {n}/{examples} examples")

    outcomes = verify(subject, examples, seed, only, on_outcome=lambda o: echo(table_row(o)), on_example=examples_done)
    failed = [o for o in outcomes if o.counterexample is not None]
    for o in failed:
        assert o.counterexample is not None
        path = o.counterexample.save(Path(out) / f"{o.invariant.key}.jsonl")
        echo("")
        echo(o.counterexample.text())
        echo(f"counterexample written to {path} (replay: fearguard verify --replay {path})")
    echo(f"{len(outcomes) - len(failed)} held, {len(failed)} failed")
    return 1 if failed else 0
