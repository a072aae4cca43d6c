"""Experiments where the robot's knowledge (the PDDL) disagrees with reality (the world).

An :class:`~gdq_pddl.experiments.protocol.Experiment` names the real world the env
simulates in ``world`` and the world the knowledge is built from in ``knowledge`` (None:
the real world itself). Both have the same positions and doors, so the learner spaces are
the same and only the knowledge differs. The derived worlds (``office:<variant>``) are
built in memory by :mod:`gdq_pddl.experiments.worlds`; the :data:`CASES` all use Task C,
each also run with accurate knowledge as its reference (``docs/decisions.md``).
"""

from __future__ import annotations

from dataclasses import dataclass

from gdq_pddl.errors import GdqError
from gdq_pddl.experiments.protocol import Experiment
from gdq_pddl.experiments.worlds import (
    PASSAGE,
    WORLDS,
    derived_world,
    load_world_named,
    with_edge,
)
from gdq_pddl.spaces import LearnerSpaces
from gdq_pddl.world import World

__all__ = ["CASES", "KNOWLEDGE_METHODS", "PASSAGE", "WORLDS", "Case", "derived_world",
           "knowledge_experiments", "knowledge_world", "with_edge"]


@dataclass(frozen=True)
class Case:
    """One knowledge/reality disagreement."""

    name: str
    """Short label, also the experiment name prefix."""
    real: str
    """The world the env simulates."""
    knowledge: str
    """The world the knowledge (PDDL problem, plans) is built from."""
    task: str
    description: str


CASES: tuple[Case, ...] = (
    Case("locked-d3", "office:locked-d3", "office", "C",
         "d3 (the easiest door, on the best route 1-3-2-6) is locked in reality; "
         "the knowledge believes it usable"),
    Case("locked-d1", "office:locked-d1", "office", "C",
         "d1 (easy, on the best route 1-3-2-6) is locked in reality; "
         "the knowledge believes it usable"),
    Case("passage", "office:passage", "office", "C",
         f"reality has a corridor {PASSAGE[0]}-{PASSAGE[1]} that the knowledge lacks "
         "(a shorter route through d1 only)"),
    Case("no-difficulty", "office", "office:deterministic", "C",
         "control: the knowledge cannot express door difficulty (built from a world "
         "where every door always works, it equals the accurate knowledge)"),
)
"""The cases of ``gdq-pddl knowledge``."""

KNOWLEDGE_METHODS = ("GDQ", "GDQ-code", "DARLING", "Dyna-Q", "Q-learning")


def knowledge_experiments(episodes: int = 1500, runs: int = 10, seed: int = 0,
                          methods: tuple[str, ...] = KNOWLEDGE_METHODS,
                          cases: tuple[Case, ...] = CASES, planner: str = "graph"
                          ) -> list[Experiment]:
    """Per case two experiments on the case's real world: knowledge built from the real
    world (``<case>--accurate``) and from the case's knowledge world (``<case>--wrong``)."""
    out = []
    for c in cases:
        common = {"methods": methods, "runs": runs, "seed": seed, "planner": planner,
                  "world": c.real}
        out.append(Experiment(f"{c.name}--accurate", ((c.task, episodes),), **common))
        out.append(Experiment(f"{c.name}--wrong", ((c.task, episodes),), knowledge=c.knowledge,
                              **common))
    return out


def knowledge_world(real: World, knowledge: str | None) -> World:
    """The world to build the knowledge from: ``real`` when ``knowledge`` is None, else the
    named world, which must give the learner the same states and actions as ``real``."""
    if knowledge is None:
        return real
    world = load_world_named(knowledge)
    a, b = LearnerSpaces(real), LearnerSpaces(world)
    if a.states != b.states or a.n_actions != b.n_actions:
        raise GdqError(f"knowledge world {knowledge!r} does not have the real world's "
                       f"positions and door sides ({real.name}): the learner spaces differ")
    return world
