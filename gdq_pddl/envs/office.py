"""The office world of the GDQ paper: one PDDL instance seen through the office's map.

A robot moves between named positions, some pairs of them the two sides of a door that
a person opens on request (building and dynamics: a world file, default ``office.toml``).
An :class:`OfficeInstance` is a task of a world as an instance of the one pipeline:
knowledge ``domains/office.pddl``, reality :meth:`~gdq_pddl.world_types.World.dynamics` and the
observation map O (:class:`~gdq_pddl.abstraction.OfficeAbstraction`). ``Office-v0``
(:func:`OfficeEnv`) is ``PDDLEnv`` on one; :class:`CompactEnv` suits large buildings.

- Actions: ``Discrete(5 * n_positions)`` (95), ``verb * n_positions + position`` for the
  verbs ``goto, approach, opendoor, gothrough, stay``; most do nothing but cost a step.
- Observations: ``Discrete(n_states)`` (31): the position, and whether its door is open.
- Rewards: ``+r_max`` at the goal, ``-r_max`` on getting stuck or on the last allowed
  action (truncated after ``step_limit``), else minus the action's cost.
- ``info``: ``action_mask``, ``plan_action`` (the first action of a shortest plan of the
  knowledge, -1: none), ``position``, ``area`` (0: none), ``cause`` (``""``,
  ``"goal"``, ``"stuck"``, ``"timeout"``), ``full_state`` (every door) and ``step``.
- Arguments: ``task`` (default ``"C"``) or ``start`` and ``goal``; ``world`` (a
  :class:`World`, a file or a built-in name); ``render_mode`` (``"ansi"``, ``"rgb_array"``).
  ``reset(options={"start": "p3", "goal": "p13"})`` moves one episode.
"""

from __future__ import annotations

import hashlib
from dataclasses import dataclass
from functools import cached_property
from pathlib import Path
from typing import Any

import numpy as np

from gdq_pddl.abstraction import OfficeAbstraction, PlanTable, build_plan_table
from gdq_pddl.abstraction.masks import knowledge_action_mask
from gdq_pddl.abstraction.prior import (
    PriorModel,
    first_plan_columns,
    prior_distances,
    prior_from_task,
)
from gdq_pddl.abstraction.routes import route_plan_table
from gdq_pddl.envs.base import CompiledEnv
from gdq_pddl.envs.compact import CompactModel, compact_step, compile_compact, observe_state
from gdq_pddl.envs.identity import world_entry
from gdq_pddl.envs.model import compile_model, full_state, per_object
from gdq_pddl.envs.pddl_env import PDDLEnv
from gdq_pddl.envs.render import Frame, MapPainter, ansi
from gdq_pddl.envs.solve import (
    expected_area_visits,
    goal_chances,
    relevant_areas,
    solve_task,
)
from gdq_pddl.envs.solve_compact import successor_capacity
from gdq_pddl.envs.step import ModelArrays
from gdq_pddl.errors import ConfigError, WorldError
from gdq_pddl.planning import get_planner
from gdq_pddl.planning.base import PlanningProblem
from gdq_pddl.resources import domain_text
from gdq_pddl.spaces import LearnerSpaces
from gdq_pddl.world import as_world, pick_task
from gdq_pddl.world_types import Task, World, office_problem


def _knowledge(world: World, task: Task | str) -> PlanningProblem:
    """The knowledge of ``world`` for ``task`` (a goal: any other position as start)."""
    if isinstance(task, str):
        task = Task("plan-table", next(p for p in world.positions if p != task), task)
    return PlanningProblem.from_texts(domain_text(), office_problem(world, task))


def _knowledge_key(world: World) -> tuple:
    """What the planner's knowledge depends on (of the dynamics: which doors can open)."""
    return (world.positions, world.edges,
            tuple((d.name, d.sides, d.success > 0) for d in world.doors))


TOLERANT_KINDS = ("all", "routes")
"""How a tolerant plan table is built: every loop-free plan within the tolerance, or
every shortest plan plus one per door route (:mod:`gdq_pddl.abstraction.routes`)."""

_TABLES: dict[tuple, PlanTable] = {}
_PRIORS: dict[tuple, PriorModel] = {}


def office_plan_table(world: World, goal: str, planner: str = "graph",
                      tolerance: float = 0.0, kind: str = "all") -> PlanTable:
    """Plans from every learner state to ``goal``, cached per (knowledge, goal, planner,
    tolerance, kind) for the life of the process; ``kind`` as in :data:`TOLERANT_KINDS`."""
    if kind not in TOLERANT_KINDS:
        raise ValueError(f"unknown plan table kind {kind!r} (known: {', '.join(TOLERANT_KINDS)})")
    if tolerance == 0:
        kind = "all"  # the shortest plans either way
    key = (_knowledge_key(world), goal, planner, float(tolerance), kind)
    table = _TABLES.get(key)
    if table is None:
        problem, abstraction = _knowledge(world, goal), OfficeAbstraction(world)
        if kind == "routes":
            crossings = {abstraction.spaces.action("gothrough", p) for p in world.door_at}
            table = route_plan_table(abstraction, problem,
                                     office_plan_table(world, goal, planner, 0.0),
                                     tolerance, crossings.__contains__)
        else:
            table = build_plan_table(abstraction, problem, get_planner(planner),
                                     abstraction.goal(goal), tolerance)
        _TABLES[key] = table
    return table


@dataclass(frozen=True, eq=False)
class OfficeInstance:
    """A task of a world as an instance of the one pipeline (see the module docstring)."""

    world: World
    """The world: its map, doors and their dynamics."""
    task: Task
    """The task: start, goal, name."""

    @classmethod
    def of(cls, task: str | None = None, start: str | None = None, goal: str | None = None,
           world: str | Path | World | None = None) -> OfficeInstance:
        """The instance of a task by name, or of a start and goal, in a world (or the office)."""
        chosen = as_world(world)
        return cls(chosen, pick_task(chosen, task, start, goal))

    @property
    def name(self) -> str:
        """The task's name, e.g. ``"C"``."""
        return self.task.name

    def identity(self) -> dict[str, str]:
        """What this task is, as learner and policy files record it
        (:mod:`~gdq_pddl.envs.identity`): its world (the file by its hash, as first
        asked), the task, and the learner's states and actions (a digest of their names:
        what the numbers mean)."""
        return dict(self._identity)

    @cached_property
    def _identity(self) -> dict[str, str]:
        sp = self.spaces
        names = [sp.state_name(s) for s in range(sp.n_states)] + \
            [sp.action_name(a) for a in range(sp.n_actions)]
        digest = hashlib.sha256("\n".join(names).encode()).hexdigest()
        return {"world": world_entry(self.world.source),
                "task": f"{self.task.name} ({self.task.start} -> {self.task.goal})",
                "learner states": f"{sp.n_states} states, {sp.n_actions} actions "
                                  f"sha256:{digest}"}

    @property
    def step_limit_key(self) -> tuple[str, str]:
        """The file and key that give the step limit."""
        return self.world.source, "world.step_limit"

    @cached_property
    def spaces(self) -> LearnerSpaces:
        """The learner's states and actions (the map's image)."""
        return LearnerSpaces(self.world)

    @property
    def model(self) -> ModelArrays:
        """The true model over full states (shared by every task of the world)."""
        return compile_model(self.world)

    @property
    def n_states(self) -> int:
        """How many learner states (the office: 31)."""
        return self.spaces.n_states

    @property
    def n_actions(self) -> int:
        """How many learner actions (the office: 95)."""
        return self.spaces.n_actions

    columns = None
    """Every learner action in every state (the paper's agent chooses among all 95)."""

    @cached_property
    def start_state(self) -> int:
        """The full state an episode starts in (robot at the start, doors closed)."""
        return full_state(self.world, self.task.start)

    @cached_property
    def start_pos(self) -> int:
        """The position index where an episode starts."""
        return self.world.index[self.task.start]

    @cached_property
    def goal_pos(self) -> int:
        """The goal's position index in the world."""
        return self.world.index[self.task.goal]

    @cached_property
    def mask_table(self) -> np.ndarray:
        """``int8[n_states, n_actions]``, read-only: 1 where the knowledge says the action
        can act; cached per (world, start)."""
        return per_object(self.world, ("masks", self.task.start), lambda: knowledge_action_mask(
            OfficeAbstraction(self.world), _knowledge(self.world, self.task).task))

    def restarted(self, start: str | None = None, goal: str | None = None) -> OfficeInstance:
        """The instance from ``start`` to ``goal`` (names; None: the task's), same world."""
        try:
            return OfficeInstance(self.world, pick_task(
                self.world, None, self.task.start if start is None else start,
                self.task.goal if goal is None else goal))
        except WorldError as exc:
            raise ConfigError(f"reset options: {exc.message}") from None

    @property
    def source(self) -> str:
        """The world file (or built-in name) errors name."""
        return self.world.source

    @cached_property
    def learner_start(self) -> int:
        """The learner state an episode starts in."""
        return self.spaces.state(self.task.start)

    @cached_property
    def learner_goal(self) -> np.ndarray:
        """``bool[n_states]``: the learner states at the goal."""
        return np.array([p == self.task.goal for p, _ in self.spaces.states], dtype=np.bool_)

    @property
    def r_max(self) -> float:
        """The success reward (failure: ``-r_max``)."""
        return float(self.world.r_max)

    @property
    def compact(self) -> CompactModel:
        """The true model per learner state (any size of world; :mod:`.compact`)."""
        return compile_compact(self.world)

    @property
    def max_successors(self) -> int:
        """:func:`~gdq_pddl.envs.solve_compact.successor_capacity` of the compact model."""
        return successor_capacity(self.compact)

    @property
    def prior(self) -> PriorModel:
        """The prior model of the world's knowledge (goal-independent; cached)."""
        key = _knowledge_key(self.world)
        if key not in _PRIORS:
            task = _knowledge(self.world, self.world.positions[-1]).task
            o = OfficeAbstraction(self.world)
            _PRIORS[key] = prior_from_task(o, task, o.mask_reader(task))
        return _PRIORS[key]

    @cached_property
    def _plan_knowledge(self) -> tuple[np.ndarray, np.ndarray]:
        distance = prior_distances(self.prior, self.learner_goal)
        return distance, first_plan_columns(self.prior, distance)

    def goal_distance(self, s: int) -> int:
        """The knowledge's fewest actions from learner state ``s`` to the goal, on the
        prior (:func:`~gdq_pddl.abstraction.prior.prior_distances`; the plan table's
        ``length[s]``): 0 at the goal, -1 where the knowledge reaches no goal."""
        return int(self._plan_knowledge[0][s])

    def plan_action(self, s: int) -> int:
        """The lowest learner action that starts a shortest plan of the knowledge from
        learner state ``s`` (one of ``plans.first_actions[s]``); -1 at the goal and where
        there is no plan."""
        return int(self._plan_knowledge[1][s])

    @cached_property
    def atom_names(self) -> tuple[str, ...]:
        """The true state's atoms: ``(at p)`` for every position, then ``(open d)`` for
        every door (a door not open is closed), in the world's order."""
        return tuple([f"(at {p})" for p in self.world.positions] +
                     [f"(open {d.name})" for d in self.world.doors])

    def facts(self, fs: int) -> np.ndarray:
        """``int8[len(atom_names)]``: the atoms true in full state ``fs``."""
        pos, mask = divmod(int(fs), 1 << len(self.world.doors))
        return self.facts_at(pos, [i for i in range(len(self.world.doors)) if mask >> i & 1])

    def facts_at(self, pos: int, open_doors: Any) -> np.ndarray:
        """:meth:`facts` of the robot at position index ``pos`` with the doors of indices
        ``open_doors`` open."""
        out = np.zeros(len(self.atom_names), dtype=np.int8)
        out[pos] = 1
        out[len(self.world.positions) + np.asarray(list(open_doors), dtype=np.int64)] = 1
        return out

    def plan_table(self, planner: str = "graph", tolerance: float = 0.0,
                   kind: str = "all") -> PlanTable:
        """The planner's plans to the task's goal (:func:`office_plan_table`)."""
        return office_plan_table(self.world, self.task.goal, planner, tolerance, kind)

    def optimal(self) -> dict[str, Any]:
        """The task's ground truth: V* with the goal probabilities that say what it means
        (:func:`~gdq_pddl.envs.solve.goal_chances`), the relevant areas (visited with
        probability >= 0.05 by the optimal policy), the paper's irrelevant ones, expected
        visits."""
        visits = expected_area_visits(self.world, self.task)
        model = self.model
        solution, start = solve_task(self.world, self.task, model)
        return {"start": self.task.start, "goal": self.task.goal,
                "v_star": float(solution.V[0, start]), "step_limit": model.step_limit,
                **goal_chances(model, solution.goal_pos, start, solution),
                "relevant_areas": list(relevant_areas(self.world, self.task, min_visits=0.05)),
                "irrelevant_areas_paper": list(self.task.irrelevant_areas),
                "expected_area_visits": {str(a): v for a, v in visits.items()}}

    def state_name(self, s: int) -> str:
        """Human name of learner state ``s``, e.g. ``"p2 (door open)"``."""
        return self.spaces.state_name(s)

    def action_name(self, a: int) -> str:
        """Human name of learner action ``a``, e.g. ``"approach p2"``."""
        return self.spaces.action_name(a)

    def decode(self, fs: int) -> tuple[str, frozenset[str]]:
        """``(position name, names of the open doors)`` of a full state."""
        pos, mask = divmod(int(fs), 1 << len(self.world.doors))
        opened = frozenset(d.name for i, d in enumerate(self.world.doors) if mask >> i & 1)
        return self.world.positions[pos], opened

    def info(self, pos: int) -> dict[str, Any]:
        """What ``info`` says beyond every env's keys: the ``position``'s name."""
        return {"position": self.world.positions[pos]}

    def render(self, mode: str, fs: int, step: int, cause: str, action: str = ""
               ) -> str | np.ndarray:
        """Full state ``fs`` drawn as text (``"ansi"``) or an RGB array (``"rgb_array"``:
        with the step, the ``action`` that led here and a legend)."""
        robot, opened = self.decode(fs)
        frame = Frame(self.world, self.task.name, robot, self.task.goal, opened, step, cause,
                      action)
        return ansi(frame) if mode == "ansi" else self._painter(frame)

    @cached_property
    def _painter(self) -> MapPainter:
        return MapPainter(self.world)


def OfficeEnv(task: str | None = None, start: str | None = None,  # noqa: N802 (an env id's
              goal: str | None = None, world: str | Path | World | None = None,  # class name)
              render_mode: str | None = None) -> PDDLEnv:
    """``gdq_pddl/Office-v0``: ``PDDLEnv`` on the :class:`OfficeInstance` of a task (a
    function: test ``isinstance(env.unwrapped.instance, OfficeInstance)``)."""
    return PDDLEnv(instance=OfficeInstance.of(task, start, goal, world),
                   render_mode=render_mode)


OfficeEnv.metadata = PDDLEnv.metadata  # what gymnasium.make reads of an entry point


class CompactEnv(CompiledEnv):
    """``OfficeEnv`` over the compact model (:mod:`.compact`; large buildings): no
    rendering; ``info`` has ``open_doors`` (door indices) instead of ``full_state``."""

    def __init__(self, task: str | None = None, start: str | None = None,
                 goal: str | None = None, world: str | Path | World | None = None) -> None:
        instance = OfficeInstance.of(task, start, goal, world)
        self.doors = np.zeros(max(1, len(instance.world.doors)), dtype=np.uint8)
        """``uint8[n_doors]``: 1 for each door now open."""
        super().__init__(instance, instance.compact)

    def _restart(self) -> None:
        self.doors[:] = 0
        self._pos = self.instance.start_pos

    def _advance(self, a: int) -> tuple[float, bool, bool, int]:
        pos, reward, terminated, truncated, cause = compact_step(
            self.model, self._pos, self.doors, a, self._t, self.instance.goal_pos,
            self.np_random)
        self._pos = int(pos)
        return reward, terminated, truncated, cause

    def _observe(self) -> int:
        return int(observe_state(self.model, self._pos, self.doors))

    def _position(self) -> int:
        return self._pos

    def facts(self) -> np.ndarray:
        """The true state's atoms (``instance.atom_names``) as ``int8`` 0/1."""
        return self.instance.facts_at(self._pos, np.flatnonzero(self.doors[:len(
            self.instance.world.doors)]))

    def _info(self) -> dict[str, Any]:
        return {**super()._info(), "open_doors": tuple(np.flatnonzero(self.doors).tolist())}
