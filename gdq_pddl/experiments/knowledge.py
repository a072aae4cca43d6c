"""What a world name of an experiment means, and the experiments where the robot's
knowledge (the PDDL) disagrees with reality (the world).

A world name is told apart by its form alone: ``office`` or ``office_robot`` (shipped);
``office:<variant>`` (derived from the office in memory, :data:`WORLDS`);
``building:<positions>:<seed>`` (a generated building, :func:`building_of`); anything
else is the path of a world file (:func:`world_name`). An experiment's ``knowledge``
world has the real world's positions and doors, so only the knowledge differs
(``docs/decisions.md``); :func:`case_truth` measures a case against the real world.
"""

from __future__ import annotations

from collections.abc import Callable, Mapping
from dataclasses import dataclass, fields, replace
from functools import cache
from pathlib import Path

import numpy as np

from gdq_pddl.buildings import building_world
from gdq_pddl.envs.evaluate import Route, RouteSummary, likeliest_next, optimal_route, policy_value
from gdq_pddl.envs.model import compile_model
from gdq_pddl.envs.pddl_env import PDDLInstance
from gdq_pddl.envs.solve import solve_task
from gdq_pddl.envs.variants import deterministic_world, with_door
from gdq_pddl.errors import GdqError
from gdq_pddl.experiments.protocol import Experiment, ProblemSpec
from gdq_pddl.learners import registry
from gdq_pddl.learners.context import office_task_context
from gdq_pddl.resources import data_file
from gdq_pddl.spaces import LearnerSpaces
from gdq_pddl.world import builtin_world, load_world
from gdq_pddl.world_types import Task, World

BUILTIN = ("office", "office_robot")
"""The names of the worlds shipped with the package."""

DERIVED_PREFIX = "office:"
"""How the names of in-memory worlds derived from the office begin."""

PASSAGE = ("p8", "p17")
"""The corridor that exists in reality but not in the knowledge (case ``passage``), and in
the knowledge but not in reality (case ``spurious-passage``)."""


BUILDING_PREFIX = "building:"
"""How the names of generated buildings begin (:func:`building_of`)."""


def is_file_name(name: str) -> bool:
    """Whether the world name ``name`` is the path of a world file (not built in)."""
    return name not in BUILTIN and not name.startswith((DERIVED_PREFIX, BUILDING_PREFIX))


def building_of(name: str) -> tuple[int, int]:
    """``(positions, seed)`` of the world name ``building:N:S``: the building of
    ``gdq-pddl building --positions N --seed S``."""
    positions, seed = name.removeprefix(BUILDING_PREFIX).split(":")
    return int(positions), int(seed)


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
    if name.startswith(BUILDING_PREFIX):
        return building_world(*building_of(name))
    return load_world(Path(name))


def load_pddl_instance(spec: ProblemSpec) -> PDDLInstance:
    """The PDDLInstance of ``spec``'s files and determinisation (its states enumerated
    where they are used; of a problem explored online, the base of its
    :class:`~gdq_pddl.envs.online.OnlineInstance`), loaded once per process."""
    return _pddl_instance(spec.domain, spec.problem, spec.dynamics, spec.determinisation)


@cache
def _pddl_instance(domain: str, problem: str, dynamics: str, determinisation: str
                   ) -> PDDLInstance:
    return PDDLInstance.from_files(domain, problem, dynamics or None,
                                   determinisation=determinisation)


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
    """One knowledge/reality disagreement. An office case names worlds; a PDDL case
    (``pddl`` given) has ``real`` = its ``pddl.domain`` (the reality domain file) and
    ``knowledge`` = the knowledge's domain file, which differs from reality in its
    probabilities only (:func:`knowledge_instance`); ``task`` is then the problem's name."""

    name: str  # also the experiment name prefix
    real: str  # the world the env simulates
    knowledge: str  # the world the knowledge (PDDL problem, plans) is built from
    task: str
    description: str
    pddl: ProblemSpec | None = None


def _shipped(*parts: str) -> str:
    return str(data_file(*parts))


KEYS_PDDL = ProblemSpec(_shipped("domains", "keys-ppddl.pddl"),
                        _shipped("problems", "keys-ppddl-1.pddl"),
                        _shipped("dynamics", "keys-ppddl.toml"), "most-likely")
"""Reality of case ``wrong-probabilities``: the shipped keys-ppddl-1, known by the
most-likely outcomes (under all outcomes no learner reads a probability: docs/decisions.md)."""
KEYS_SWAPPED = _shipped("knowledge", "keys-ppddl-swapped.pddl")
"""The knowledge of case ``wrong-probabilities``: keys-ppddl with the locks' chances swapped."""


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
    Case("spurious-passage", "office", "office:passage", "C",
         f"spurious effect: the knowledge has a corridor {PASSAGE[0]}-{PASSAGE[1]} that "
         f"reality lacks, so it believes goto {PASSAGE[1]} at {PASSAGE[0]} leads to "
         f"{PASSAGE[1]} (its shortest plans use it); in reality the robot stays at "
         f"{PASSAGE[0]}"),
    Case("no-difficulty", "office", "office:deterministic", "C",
         "control: the knowledge cannot express door difficulty (built from a world "
         "where every door always works, it equals the accurate knowledge)"),
    Case("wrong-probabilities", KEYS_PDDL.domain, KEYS_SWAPPED, "keys-ppddl-1",
         "PPDDL keys-ppddl-1 known by its most-likely outcomes; the knowledge's domain "
         "file believes the sound blue lock opens with probability 0.3 (reality 0.9) and "
         "the stiff red lock opens with 0.9 and jams with 0.05 (reality 0.5 and 0.3): its "
         "plans take the red door only, reality's both doors (8 actions each)",
         pddl=KEYS_PDDL),
)
"""The cases of ``gdq-pddl knowledge``."""

KNOWLEDGE_METHODS = tuple(e.name for e in registry.BUILT_IN if e.knowledge != "none")
"""What ``gdq-pddl knowledge`` compares unless told otherwise: every built-in learner that
reads the knowledge (the registry's entries whose ``knowledge`` is not ``none``)."""


def knowledge_experiments(episodes: int = 1500, runs: int = 10, seed: int = 0,
                          methods: tuple[str, ...] = KNOWLEDGE_METHODS,
                          cases: tuple[Case, ...] = CASES, planner: str = "graph"
                          ) -> list[Experiment]:
    """Per case two experiments on the case's real world: knowledge built from the real
    world (``<case>--accurate``) and from the case's knowledge world (``<case>--wrong``)."""
    out = []
    for c in cases:
        common = {"methods": tuple(methods) if c.pddl is None else
                  tuple(reading(m, c.pddl.determinisation) for m in methods),
                  "runs": runs, "seed": seed, "planner": planner,
                  "world": "pddl" if c.pddl else c.real, "pddl": c.pddl}
        out.append(Experiment(f"{c.name}--accurate", ((c.task, episodes),), **common))
        out.append(Experiment(f"{c.name}--wrong", ((c.task, episodes),), knowledge=c.knowledge,
                              **common))
    return out


def reading(method: str, determinisation: str) -> str:
    """``method`` set to read a PPDDL problem's knowledge by ``determinisation`` where its
    config has that setting and the method does not give it (FF-Replan refuses a problem
    determinised otherwise than it plans)."""
    parsed = registry.parse_method(method)
    names = {f.name for f in fields(parsed.entry.config)}
    if "determinisation" not in names or "determinisation" in parsed.settings or \
            parsed.entry.fixed.get("determinisation") is not None:
        return method
    default = next(f.default for f in fields(parsed.entry.config) if f.name == "determinisation")
    if default == determinisation:
        return method
    return f"{method}{',' if ':' in method else ':'}determinisation={determinisation}"


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


def knowledge_instance(real: PDDLInstance, spec: ProblemSpec, domain: str) -> PDDLInstance:
    """The PDDL instance to build the knowledge from: reality's problem, dynamics and
    determinisation (``spec``) with the knowledge's ``domain`` file, which must give the
    same reachable states and offered actions (other probabilities, the same outcomes)."""
    known = load_pddl_instance(replace(spec, domain=domain))
    if known.graph.states != real.graph.states or \
            not np.array_equal(known.columns, real.columns) or \
            not np.array_equal(known.model.ptr, real.model.ptr) or \
            not np.array_equal(known.model.next, real.model.next):
        raise GdqError(f"knowledge domain {domain} does not give the reachable states and "
                       f"actions of {spec.domain} on {real.name}: give it the same outcomes "
                       "(other probabilities only)")
    return known


@dataclass(frozen=True)
class RouteStep:
    """One step of the true optimal route: its optimal actions and whether one is allowed
    by DARLING, starts a shortest / tolerant plan, or applies in GDQ's prior model."""

    state: str
    optimal: tuple[str, ...]
    darling_allowed: bool
    in_shortest_plans: bool
    in_tolerant_plans: bool
    in_prior: bool = False


CHECKS = {"darling_allowed": "DARLING allows an optimal action", "in_prior": "an optimal "
          "action is applicable in the prior model (GDQ)", "in_shortest_plans": "... starts "
          "a shortest plan (GDQ-literal)", "in_tolerant_plans": "... a plan within 1.3x "
          "(GDQ-code)"}


def route_check(real: World, knowledge: World, task: Task) -> list[RouteStep]:
    """:class:`RouteStep` s along the likeliest optimal route in ``real``."""
    ctx = office_task_context(knowledge, task)
    tables = (ctx.darling_plans.allowed_actions(), ctx.plans.first_actions,
              ctx.darling_plans.first_actions, ctx.prior.applicable)
    model = compile_model(real)
    solution, fs = solve_task(real, task, model)
    spaces = LearnerSpaces(real)
    out: list[RouteStep] = []
    for t in range(model.step_limit):
        obs, q = int(model.obs_of[fs]), solution.Q[t, fs]
        best = np.flatnonzero(q >= q.max() - 1e-9)
        out.append(RouteStep(spaces.state_name(obs),
                             tuple(spaces.action_name(int(a)) for a in best),
                             *(bool(table[obs, best].any()) for table in tables)))
        nxt = likeliest_next(model, fs, int(solution.policy[t, fs]))
        if nxt is None or model.pos_of[nxt] == solution.goal_pos:
            break
        fs = nxt
    return out


ACCURATE, WRONG = "accurate", "wrong"


@dataclass(frozen=True)
class CaseTruth:
    """A case's task in its real world: V*, the likeliest optimal route and, per knowledge
    (:data:`ACCURATE` / :data:`WRONG`), the :func:`route_check` along it."""

    real: World
    task: Task
    v_star: float
    route: Route
    checks: dict[str, list[RouteStep]]

    def measure(self, policies: Mapping[int, Mapping[int, int]]
                ) -> tuple[int, list[float], list[tuple[int, ...]]]:
        """Of per-run final policies (empty ones skipped): the runs following the optimal
        area route to the goal, each policy's exact value and area route (``()``: no goal)."""
        summary = RouteSummary.of(self.real, self.task, policies)
        if summary is None:
            return 0, [], []
        return (summary.on_route(self.real, self.route.areas(self.real)),
                [policy_value(self.real, self.task, p) for p in policies.values() if p],
                [r.areas(self.real) if r.reached_goal else () for r in summary.routes.values()])


def case_truth(wrong: Mapping) -> CaseTruth:
    """The :class:`CaseTruth` of a case from its ``--wrong`` experiment (``config.json``)."""
    real = load_world_named(wrong["world"])
    task = real.task(wrong["schedule"][0][0])
    solution, s0 = solve_task(real, task, compile_model(real))
    knowledge = knowledge_world(real, wrong.get("knowledge"))
    return CaseTruth(real, task, float(solution.V[0, s0]), optimal_route(real, task),
                     {ACCURATE: route_check(real, real, task),
                      WRONG: route_check(real, knowledge, task)})


@dataclass(frozen=True)
class ProblemTask:
    """A PDDL case's task as the report names it."""

    name: str
    start: str = "initial state"
    goal: str = "goal"


@dataclass(frozen=True)
class ProblemTruth:
    """A PDDL case's ground truth: V* of reality, the V* the knowledge believes (its own
    probabilities), and the first actions of the shortest plans from the start by
    knowledge (:data:`ACCURATE` / :data:`WRONG`)."""

    task: ProblemTask
    v_star: float
    believed_v_star: float
    first_actions: dict[str, tuple[str, ...]]

    def measure(self, policies: Mapping[int, Mapping[int, int]]
                ) -> tuple[int, list[float], list[tuple[int, ...]]]:
        """No route measure on a PDDL problem: ``(0, [], [])``."""
        return 0, [], []


def problem_truth(wrong: Mapping) -> ProblemTruth:
    """The :class:`ProblemTruth` of a PDDL case from its ``--wrong`` experiment."""
    spec = ProblemSpec.from_record(wrong["pddl"])
    real = load_pddl_instance(spec)
    known = knowledge_instance(real, spec, wrong["knowledge"])

    def starts(instance: PDDLInstance) -> tuple[str, ...]:
        s, table = instance.learner_start, instance.plan_table("graph", 0.0)
        return tuple(instance.action_name(int(a))
                     for a in instance.columns[s][table.first_actions[s]])

    return ProblemTruth(ProblemTask(real.name), float(real.optimal()["v_star"]),
                        float(known.optimal()["v_star"]),
                        {ACCURATE: starts(real), WRONG: starts(known)})
