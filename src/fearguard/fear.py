"""What the fuzzy rules say about one frame: the fear value, its level, and why."""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from enum import Enum, IntEnum


class FearLevel(IntEnum):
    """The five fear intensities of the affective model, in order."""

    VERY_LOW = 0
    LOW = 1
    MEDIUM = 2
    HIGH = 3
    VERY_HIGH = 4


LEVEL_NAMES: tuple[str, ...] = tuple(level.name.lower() for level in FearLevel)  # the rule files' fear terms
LEVEL_ORDER: tuple[str, ...] = tuple(level.name for level in FearLevel)  # as logs and tables name them, lowest first


class Cause(Enum):
    """Which kind of hazard a rule group grades; it picks the emergency strategy."""

    COLLISION = "collision"  # something ahead is close: brake
    ROAD = "road"  # the road picture cannot be trusted: follow the lead or stop
    LOCALISATION = "localisation"  # position fix is stale: crawl


@dataclass(frozen=True)
class FearResult:
    """Fear 0..1 with its level, each rule's firing strength, and the fear of each group and cause."""

    fear: float
    level: FearLevel
    activations: Mapping[str, float]
    group_fears: Mapping[str, float]
    cause_fears: Mapping[Cause, float]
    candidate_drivers: Sequence[tuple[str, int]] = ()  # (rule text, fear level) of the group setting the fear

    def top_rules(self, n: int = 3) -> list[tuple[str, float]]:
        """The n rules that drove the fear: fired rules of the group with the highest fear, worst level first."""
        fired = [(text, self.activations[text], level) for text, level in self.candidate_drivers if self.activations[text] > 0.0]
        fired.sort(key=lambda item: (-item[2], -item[1]))
        return [(text, strength) for text, strength, _ in fired[:n]]

    @property
    def dominant_cause(self) -> Cause:
        """The cause with the largest fear (ties: collision before road before localisation)."""
        order = list(Cause)
        return max(self.cause_fears, key=lambda c: (self.cause_fears[c], -order.index(c)))
