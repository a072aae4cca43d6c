"""O for the office: PDDL atoms and actions <-> (position, door open) and verb x position."""

from __future__ import annotations

from collections.abc import Callable

from gdq_pddl.errors import AbstractionError
from gdq_pddl.planning.base import State
from gdq_pddl.spaces import Building, LearnerSpaces

# PDDL action -> (learner verb, index of the argument naming the learner position)
_ACTIONS = {"goto": ("goto", 1), "approach": ("approach", 1), "opendoor": ("opendoor", 0),
            "gothrough": ("gothrough", 1)}


class OfficeAbstraction:
    """O between ``domains/office.pddl`` and :class:`~gdq_pddl.spaces.LearnerSpaces`."""

    def __init__(self, world: Building) -> None:
        self.world = world
        self.spaces = LearnerSpaces(world)
        self.n_states = self.spaces.n_states
        self.n_actions = self.spaces.n_actions

    def learner_state(self, state: State) -> int:
        """The robot's position and whether the door there is open."""
        at = [a[4:-1] for a in state if a.startswith("(at ")]
        if len(at) != 1 or at[0] not in self.world.index:
            raise AbstractionError(f"planner state {sorted(state)} has no single known "
                                   "(at ?p) atom: cannot map it to a learner state")
        p = at[0]
        door = self.world.door_at.get(p)
        return self.spaces.state(p, door is not None and f"(open {door.name})" in state)

    def mask_reader(self, task) -> Callable[[int], int]:
        """:meth:`learner_state` of a state bitmask of ``task``, without building atoms."""
        at = {task.fact_index[f"(at {p})"]: p for p in self.world.positions
              if f"(at {p})" in task.fact_index}
        opened = {p: task.fact_index.get(f"(open {d.name})")
                  for p, d in self.world.door_at.items()}
        at_mask = sum(1 << bit for bit in at)
        state = self.spaces.state

        def read(mask: int) -> int:
            m = mask & at_mask
            if not m or m & (m - 1):
                raise AbstractionError(f"planner state {sorted(task.atoms(mask))} has no "
                                       "single known (at ?p) atom")
            p = at[m.bit_length() - 1]
            bit = opened.get(p)
            return state(p, bit is not None and bool(mask >> bit & 1))

        return read

    def learner_action(self, action: str) -> int:
        """``(approach p0 p2 d1)`` -> ``approach p2``, ``(opendoor p2 d1)`` -> ``opendoor p2``."""
        parts = action.strip("()").split()
        if not parts or parts[0] not in _ACTIONS:
            raise AbstractionError(f"planner action {action!r} has no learner counterpart "
                                   f"(known: {', '.join(_ACTIONS)})")
        verb, arg = _ACTIONS[parts[0]]
        if len(parts) <= arg + 1 or parts[arg + 1] not in self.world.index:
            raise AbstractionError(f"planner action {action!r}: expected a known position "
                                   f"as argument {arg + 1}")
        return self.spaces.action(verb, parts[arg + 1])

    def planner_state(self, state: int) -> State:
        """The robot at the state's position; its door as observed, every other door
        closed (plans then include every opendoor they might need)."""
        p, is_open = self.spaces.states[state]
        door = self.world.door_at.get(p)
        opened = door.name if door is not None and is_open else None
        atoms = {f"(at {p})"}
        for d in {d.name for d in self.world.door_at.values()}:
            atoms.add(f"({'open' if d == opened else 'closed'} {d})")
        return frozenset(atoms)

    def goal(self, position: str) -> State:
        """The goal ``(at p)`` for a position name."""
        if position not in self.world.index:
            raise AbstractionError(f"unknown goal position {position!r}")
        return frozenset({f"(at {position})"})
