"""The learner's vocabulary for an office world: state and action indices.

A state is ``(position, is the door here open)``: one per open-floor position, two per
door side, in position order (office: 31). An action is a verb and a position,
verb-major (office: 5 x 19 = 95): the position moved to (``goto``, ``approach``,
``gothrough``) or stood at (``opendoor``, ``stay``).
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass
from functools import cached_property
from typing import Protocol

VERBS: tuple[str, ...] = ("goto", "approach", "opendoor", "gothrough", "stay")
"""The action verbs, in the order of the learner's action index (verb-major)."""


class Building(Protocol):
    """What the learner's vocabulary reads of a building (a World has it)."""

    @property
    def positions(self) -> tuple[str, ...]: ...

    @property
    def index(self) -> Mapping[str, int]: ...

    @property
    def door_at(self) -> Mapping[str, object]: ...


@dataclass(frozen=True)
class LearnerSpaces:
    """State and action indices of the learner for one building."""

    world: Building

    @cached_property
    def states(self) -> tuple[tuple[str, bool], ...]:
        """Learner states as ``(position, door open)``, in index order."""
        out: list[tuple[str, bool]] = []
        for p in self.world.positions:
            out.append((p, False))
            if p in self.world.door_at:
                out.append((p, True))
        return tuple(out)

    @cached_property
    def state_index(self) -> dict[tuple[str, bool], int]:
        """``(position, door open)`` -> state index."""
        return {s: i for i, s in enumerate(self.states)}

    @property
    def n_states(self) -> int:
        return len(self.states)

    @property
    def n_actions(self) -> int:
        return len(VERBS) * len(self.world.positions)

    def state(self, position: str, door_open: bool = False) -> int:
        """Index of the learner state; ``door_open`` is ignored where there is no door."""
        return self.state_index[(position, door_open and position in self.world.door_at)]

    def action(self, verb: str, position: str) -> int:
        """Index of the learner action ``verb position``."""
        return VERBS.index(verb) * len(self.world.positions) + self.world.index[position]

    def action_parts(self, index: int) -> tuple[str, str]:
        """``(verb, position)`` of an action index."""
        n = len(self.world.positions)
        return VERBS[index // n], self.world.positions[index % n]

    def action_name(self, index: int) -> str:
        """Human name of an action, e.g. ``"approach p2"``."""
        return " ".join(self.action_parts(index))

    def state_name(self, index: int) -> str:
        """Human name of a state, e.g. ``"p2"`` or ``"p2 (door open)"``."""
        p, is_open = self.states[index]
        if p not in self.world.door_at:
            return p
        return f"{p} (door {'open' if is_open else 'closed'})"
