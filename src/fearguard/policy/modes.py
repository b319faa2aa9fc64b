"""The mode machine: NORMAL / CAUTION / EMERGENCY with the enter counter, the hold (brake latch) and the causes latched."""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass

from fearguard.fear import Cause
from fearguard.policy.config import Mode, PolicyConfig

Latch = tuple[tuple[Cause, float | None], ...]  # (cause, since when its fear is below the exit threshold)


@dataclass(frozen=True)
class ModeState:
    """The mode machine's memory between frames."""

    mode: Mode = Mode.NORMAL
    frames_over: int = 0  # consecutive frames with fear ≥ enter threshold
    entered_s: float | None = None  # when EMERGENCY was entered
    below_since_s: float | None = None  # since when fear is below the exit threshold (in EMERGENCY)
    latched: Latch = ()  # causes that drove this EMERGENCY, each kept until hold_s below the exit threshold
    fault: bool = False  # a fault drove this EMERGENCY: stop until it is left


def _relatch(latched: Latch, over: frozenset[Cause], cause_fears: Mapping[Cause, float], t_s: float, cfg: PolicyConfig) -> Latch:
    """Add this frame's causes; drop a latched cause once its fear has stayed below exit for hold_s."""
    previous = dict(latched)
    out: list[tuple[Cause, float | None]] = []
    for cause in Cause:
        if cause in over or (cause in previous and cause_fears.get(cause, 0.0) >= cfg.emergency_exit_fear):
            out.append((cause, None))
        elif cause in previous:
            below = previous[cause]
            below = t_s if below is None else below
            if t_s - below < cfg.hold_s:
                out.append((cause, below))
    return tuple(out)


def next_mode(
    state: ModeState,
    fear: float,
    t_s: float,
    at_once: bool,
    cfg: PolicyConfig,
    cause_fears: Mapping[Cause, float] | None = None,
    over: frozenset[Cause] = frozenset(),
    fault: bool = False,
) -> tuple[ModeState, str]:
    """Advance the mode machine one frame; ``at_once`` (imminent collision, fault) enters immediately.

    ``over`` are this frame's causes that demand EMERGENCY (fear over the enter threshold, an imminent
    collision): they are latched, so the plan remembers why it braked during the hold.
    Returns the new state and what happened, for the reasons (empty when nothing changed).
    """
    fears = cause_fears or {}
    hot = fear >= cfg.emergency_enter_fear
    if state.mode is Mode.EMERGENCY:
        latched, faulted = _relatch(state.latched, over, fears, t_s, cfg), state.fault or fault
        if at_once or fear >= cfg.emergency_exit_fear:
            return ModeState(Mode.EMERGENCY, state.frames_over + hot, state.entered_s, None, latched, faulted), ""
        below = t_s if state.below_since_s is None else state.below_since_s
        if t_s - below >= cfg.hold_s:
            mode = Mode.CAUTION if fear >= cfg.caution_fear else Mode.NORMAL
            return ModeState(mode), f"left EMERGENCY after {t_s - below:.2f} s below fear {cfg.emergency_exit_fear:.2f}"
        return ModeState(Mode.EMERGENCY, 0, state.entered_s, below, latched, faulted), ""
    frames = state.frames_over + 1 if hot else 0
    if at_once or frames >= cfg.enter_frames:
        why = "at once" if at_once else f"after {frames} frames with fear >= {cfg.emergency_enter_fear:.2f}"
        latched = tuple((c, None) for c in Cause if c in over)
        return ModeState(Mode.EMERGENCY, frames, t_s, None, latched, fault), f"entered EMERGENCY {why}"
    mode = Mode.CAUTION if fear >= cfg.caution_fear else Mode.NORMAL
    return ModeState(mode, frames), ""


