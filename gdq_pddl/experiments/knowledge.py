"""Experiments where the robot's knowledge (the PDDL) disagrees with reality (the world).

The learners' knowledge is built from a *knowledge world* (the PDDL problem is generated
from it and planned with, :func:`gdq_pddl.learners.office_task_context`); the env
simulates a *real world*. Both have the same positions and doors, so the learner's state
and action spaces are identical and only what the knowledge says differs. An
:class:`~gdq_pddl.experiments.protocol.Experiment` names the real world in ``world`` and
the knowledge world in ``knowledge`` (None: the real world itself, accurate knowledge).

The derived worlds are built in memory and named ``office:<variant>``;
:func:`load_world_named` resolves those names through
:data:`WORLDS`.

The cases (all on Task C, p0 -> p17; every case also runs with accurate knowledge, the
same real world with knowledge built from it, as the reference):

- ``locked-d3`` / ``locked-d1``: a door the knowledge believes usable is locked in
  reality (success 0, stuck 0: opening it never works, but is harmless).
- ``passage``: reality has a corridor p8-p17 that the knowledge lacks; it makes a much
  shorter route (through d1 only) that no plan contains.
- ``no-difficulty``: the control. The PDDL has no notion of a door's difficulty (the
  planner ignores success/stuck probabilities), so knowledge built from a world in which
  every door always works (:func:`~gdq_pddl.envs.variants.deterministic_world`) is the
  same knowledge as the accurate one: the paper's own Task C situation. Its "extra
  episodes" measure the noise of the comparison (different seeds, same information).
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass, replace
from functools import cache
from pathlib import Path

from gdq_pddl.errors import GdqError
from gdq_pddl.spaces import LearnerSpaces
from gdq_pddl.world import World, builtin_world, load_world

PASSAGE = ("p8", "p17")
"""The corridor that exists in reality but not in the knowledge (case ``passage``)."""


def with_edge(world: World, a: str, b: str) -> World:
    """``world`` with an extra walkway ``a``-``b`` (both must be existing positions)."""
    for p in (a, b):
        world.position(p)  # raises WorldError for an unknown position
    if frozenset((a, b)) in {frozenset(e) for e in world.edges}:
        raise GdqError(f"{world.name} already has the edge {a}-{b}")
    return replace(world, edges=(*world.edges, (a, b)))


def _office() -> World:
    return builtin_world("office")


def _locked(door: str) -> Callable[[], World]:
    def build() -> World:
        from gdq_pddl.envs.variants import with_door

        return replace(with_door(_office(), door, success=0.0, stuck=0.0),
                       name=f"office-locked-{door}")
    return build


def _passage() -> World:
    return replace(with_edge(_office(), *PASSAGE), name="office-passage")


def _deterministic() -> World:
    from gdq_pddl.envs.variants import deterministic_world

    return deterministic_world(_office())


WORLDS: dict[str, Callable[[], World]] = {
    "office:locked-d1": _locked("d1"),
    "office:locked-d3": _locked("d3"),
    "office:passage": _passage,
    "office:deterministic": _deterministic,
}
"""In-memory derived worlds by name (resolved by ``load_world_named``)."""


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


def accurate_name(case: Case) -> str:
    return f"{case.name}--accurate"


def wrong_name(case: Case) -> str:
    return f"{case.name}--wrong"


def knowledge_experiments(episodes: int = 1500, runs: int = 10, seed: int = 0,
                          methods: tuple[str, ...] = KNOWLEDGE_METHODS,
                          cases: tuple[Case, ...] = CASES, planner: str = "graph") -> list:
    """Per case two experiments on the case's real world: knowledge built from the real
    world (``<case>--accurate``) and from the case's knowledge world (``<case>--wrong``)."""
    from gdq_pddl.experiments.protocol import Experiment

    out = []
    for c in cases:
        common = {"methods": methods, "runs": runs, "seed": seed, "planner": planner,
                  "world": c.real}
        out.append(Experiment(accurate_name(c), ((c.task, episodes),), **common))
        out.append(Experiment(wrong_name(c), ((c.task, episodes),), knowledge=c.knowledge,
                              **common))
    return out


@cache
def load_world_named(name: str) -> World:
    """``office`` / ``office_robot`` (built in), a derived world ``office:<variant>``
    (:data:`WORLDS`), or a world file path."""
    if name in ("office", "office_robot"):
        return builtin_world(name)
    if name.startswith("office:"):
        return derived_world(name)
    return load_world(Path(name))


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
