"""The office world of the GDQ paper: one PDDL instance seen through the office's map.

A robot moves between named positions of an office; some pairs of positions are the two
sides of a door, which a person opens on request and which the robot then crosses. The
building, its doors and their dynamics come from a world file (by default the shipped
``office.toml``); nothing here is specific to the office.

An :class:`OfficeInstance` is the instance a world file produces: the knowledge
``domains/office.pddl`` with the world's problem, the world's reality
(:meth:`~gdq_pddl.world.World.dynamics`, compiled through the same
:func:`~gdq_pddl.envs.model.compile_true_model` as any PDDL problem) and the office's
observation map O (:class:`~gdq_pddl.abstraction.OfficeAbstraction`). ``OfficeEnv(...)``
(``gdq_pddl/Office-v0``) is the one env class of the package,
:class:`~gdq_pddl.envs.pddl_env.PDDLEnv`, on such an instance.

## Action space
``Discrete(5 * n_positions)`` (95 for the office), verb-major: action
``verb * n_positions + position`` with verbs ``goto, approach, opendoor, gothrough,
stay``. Most actions are inapplicable in a given state: they cost a step and change
nothing. See :mod:`gdq_pddl.spaces` for names (``env.unwrapped.spaces.action_name(a)``).

## Observation space
``Discrete(n_states)`` (31 for the office): the learner's state (position, is the door
at this position open); one state per open-floor position, two per door-side position.
The full simulator state (which doors are open anywhere) is in ``info["full_state"]``.

## Starting state
The task's start position, every door closed.

## Rewards
``+r_max`` on reaching the goal, ``-r_max`` on failure (stuck at a door, or the last
allowed action taken without reaching the goal), otherwise minus the action's cost
(1 per action in the office; a world file may give cost distributions).

## Episode end
Terminated on reaching the goal or getting stuck. Truncated after ``step_limit``
actions (20 for the office) with reward ``-r_max``: the env counts its own steps, so no
``TimeLimit`` wrapper is needed (or registered).

## Information
``info`` holds ``action_mask``, ``position`` (name), ``area`` (int, 0 if none),
``cause`` (``""``, ``"goal"``, ``"stuck"`` or ``"timeout"``), ``full_state`` (int) and
``step`` (actions taken so far). ``action_mask`` (``int8[n_actions]``, as in
Gymnasium's Taxi) is 1 for the actions the robot's PDDL knowledge says can do something
in the observed state: a ground action applicable there maps to it. ``stay`` is never 1
(the knowledge has no such action). Use it as
``env.action_space.sample(mask=info["action_mask"])``.

## Arguments
``task`` (a task name of the world, default ``"C"``) or ``start`` and ``goal``
(position or landmark names); ``world`` (a :class:`World`, a world file path or a
built-in world name; default the office); ``render_mode`` (``"ansi"`` or
``"rgb_array"``).

Every step goes through :func:`gdq_pddl.envs.model.env_step`, the one definition of a
step, with randomness from ``self.np_random`` only. ``env.unwrapped.world``, ``.task``,
``.spaces`` and ``.decode(full_state)`` are the instance's.
"""

from __future__ import annotations

import weakref
from dataclasses import dataclass
from functools import cached_property
from pathlib import Path
from typing import Any

import numpy as np

from gdq_pddl.abstraction import OfficeAbstraction
from gdq_pddl.abstraction.masks import knowledge_action_mask
from gdq_pddl.envs.model import ModelArrays, compile_model, full_state
from gdq_pddl.envs.pddl_env import PDDLEnv
from gdq_pddl.envs.render import Frame, MapPainter, ansi
from gdq_pddl.envs.solve import expected_area_visits, optimal_value, relevant_areas
from gdq_pddl.planning.base import PlanningProblem
from gdq_pddl.resources import domain_text
from gdq_pddl.spaces import LearnerSpaces
from gdq_pddl.world import Task, World, as_world, office_problem, pick_task


def office_action_masks(world: World, task: Task) -> np.ndarray:
    """``int8[n_states, n_actions]``, read-only: the actions the office's knowledge
    (``domains/office.pddl`` on ``world``'s problem for ``task``) says can do something
    in each learner state, through O (:mod:`gdq_pddl.abstraction.masks`). Cached per
    (world object, start): an experiment makes an env per run, and grounding the
    knowledge costs milliseconds."""
    key = (id(world), task.start)
    hit = _MASKS.get(key)
    if hit is not None and hit[0]() is world:
        return hit[1]
    problem = PlanningProblem.from_texts(domain_text(), office_problem(world, task))
    masks = knowledge_action_mask(OfficeAbstraction(world), problem.task)
    _MASKS[key] = (weakref.ref(world), masks)
    return masks


_MASKS: dict[tuple[int, str], tuple[weakref.ref, np.ndarray]] = {}


@dataclass(frozen=True, eq=False)
class OfficeInstance:
    """A task of a world as an instance of the one pipeline (see the module docstring)."""

    world: World
    task: Task
    render_modes = ("ansi", "rgb_array")

    @classmethod
    def of(cls, task: str | None = None, start: str | None = None, goal: str | None = None,
           world: str | Path | World | None = None) -> OfficeInstance:
        """The instance of a task by name, or of a start and goal, in a world (a
        :class:`World`, a world file, a built-in name; default the office)."""
        chosen = as_world(world)
        return cls(chosen, pick_task(chosen, task, start, goal))

    @property
    def name(self) -> str:
        return self.task.name

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
        return self.spaces.n_states

    @property
    def n_actions(self) -> int:
        return self.spaces.n_actions

    @cached_property
    def start_state(self) -> int:
        return full_state(self.world, self.task.start)

    @cached_property
    def goal_pos(self) -> int:
        return self.world.index[self.task.goal]

    @cached_property
    def action_masks(self) -> np.ndarray:
        return office_action_masks(self.world, self.task)

    def optimal(self) -> dict[str, Any]:
        """The ground truth of the task: start, goal, V*, the relevant areas (visited
        with probability >= 0.05 by the optimal policy), the paper's irrelevant ones
        and the expected visits to each area."""
        visits = expected_area_visits(self.world, self.task)
        return {"start": self.task.start, "goal": self.task.goal,
                "v_star": optimal_value(self.world, self.task),
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

    def info(self, fs: int) -> dict[str, Any]:
        """What ``info`` says beyond every env's keys: the ``position``'s name."""
        return {"position": self.world.positions[int(self.model.pos_of[fs])]}

    def render(self, mode: str, fs: int, step: int, cause: str) -> str | np.ndarray:
        robot, opened = self.decode(fs)
        frame = Frame(self.world, self.task.name, robot, self.task.goal, opened, step, cause)
        return ansi(frame) if mode == "ansi" else self._painter(frame)

    @cached_property
    def _painter(self) -> MapPainter:
        return MapPainter(self.world)


def OfficeEnv(task: str | None = None, start: str | None = None,  # noqa: N802 (an env id's
              goal: str | None = None, world: str | Path | World | None = None,  # class name)
              render_mode: str | None = None) -> PDDLEnv:
    """``gdq_pddl/Office-v0``: the env on the :class:`OfficeInstance` of a task (see the
    module docstring for the arguments)."""
    PDDLEnv.check_render_mode(render_mode, OfficeInstance.render_modes)
    return PDDLEnv(instance=OfficeInstance.of(task, start, goal, world),
                   render_mode=render_mode)


OfficeEnv.metadata = {"render_modes": list(OfficeInstance.render_modes),  # what
                      "render_fps": 4}  # gymnasium.make reads of an entry point
