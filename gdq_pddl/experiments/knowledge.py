"""What a world name of an experiment means, and the experiments where the robot's
knowledge (the PDDL) disagrees with reality (the world).

A world name is told apart by its form alone: ``office`` or ``office_robot`` (shipped);
``office:<variant>`` (derived from the office in memory, :data:`WORLDS`); anything else
is the path of a world file (:func:`world_name`). An experiment's ``knowledge`` world has
the real world's positions and doors, so only the knowledge differs
(``docs/decisions.md``).
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass, replace
from functools import cache
from pathlib import Path

from gdq_pddl.envs.variants import deterministic_world, with_door
from gdq_pddl.errors import GdqError
from gdq_pddl.experiments.protocol import Experiment
from gdq_pddl.spaces import LearnerSpaces
from gdq_pddl.world import World, builtin_world, load_world

BUILTIN = ("office", "office_robot")
"""The names of the worlds shipped with the package."""

DERIVED_PREFIX = "office:"
"""How the names of in-memory worlds derived from the office begin."""

PASSAGE = ("p8", "p17")
"""The corridor that exists in reality but not in the knowledge (case ``passage``)."""


def is_file_name(name: str) -> bool:
    """Whether the world name ``name`` is the path of a world file (not built in)."""
    return name not in BUILTIN and not name.startswith(DERIVED_PREFIX)


def world_name(path: Path | None) -> str:
    """The name an experiment records for ``--world``: ``office``, or the absolute path."""
    return "office" if path is None else str(Path(path).absolute())


@cache
def load_world_named(name: str) -> World:
    """The world ``name`` means (see the module docstring), loaded once per process."""
    if name in BUILTIN:
        return builtin_world(name)
    if name.startswith(DERIVED_PREFIX):
        return derived_world(name)
    return load_world(Path(name))


def with_edge(world: World, a: str, b: str) -> World:
    """``world`` with an extra walkway ``a``-``b`` (both must be existing positions)."""
    for p in (a, b):
        world.position(p)  # raises WorldError for an unknown position
    if frozenset((a, b)) in {frozenset(e) for e in world.edges}:
        raise GdqError(f"{world.name} already has the edge {a}-{b}")
    return replace(world, edges=(*world.edges, (a, b)))


def _locked(door: str) -> World:
    return replace(with_door(builtin_world("office"), door, success=0.0, stuck=0.0),
                   name=f"office-locked-{door}")


WORLDS: dict[str, Callable[[], World]] = {
    "office:locked-d1": lambda: _locked("d1"),
    "office:locked-d3": lambda: _locked("d3"),
    "office:passage": lambda: replace(with_edge(builtin_world("office"), *PASSAGE),
                                      name="office-passage"),
    "office:deterministic": lambda: deterministic_world(builtin_world("office")),
}
"""In-memory derived worlds by name (resolved by :func:`load_world_named`)."""


@cache
def derived_world(name: str) -> World:
    """The derived world ``name`` (a key of :data:`WORLDS`), built once per process."""
    try:
        return WORLDS[name]()
    except KeyError:
        raise GdqError(f"unknown derived world {name!r} (known: {', '.join(WORLDS)})") from None


@dataclass(frozen=True)
class Case:
    """One knowledge/reality disagreement."""

    name: str  # also the experiment name prefix
    real: str  # the world the env simulates
    knowledge: str  # the world the knowledge (PDDL problem, plans) is built from
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
    """The world to build the knowledge from: ``real``, or the named one (same spaces)."""
    if knowledge is None:
        return real
    world = load_world_named(knowledge)
    a, b = LearnerSpaces(real), LearnerSpaces(world)
    if a.states != b.states or a.n_actions != b.n_actions:
        raise GdqError(f"knowledge world {knowledge!r} does not have the real world's "
                       f"positions and door sides ({real.name}): the learner spaces differ")
    return world
