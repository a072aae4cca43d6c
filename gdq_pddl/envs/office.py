"""The office world of the GDQ paper as a Gymnasium environment.

A robot moves between named positions of an office; some pairs of positions are the two
sides of a door, which a person opens on request and which the robot then crosses. The
building, its doors and their dynamics come from a world file (by default the shipped
``office.toml``); nothing here is specific to the office.

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

Every step goes through :func:`gdq_pddl.envs.model.env_step`, the one definition of the
dynamics, with randomness from ``self.np_random`` only.
"""

from __future__ import annotations

import weakref
from functools import cached_property
from pathlib import Path
from typing import Any

import gymnasium as gym
import numpy as np
from gymnasium.spaces import Discrete

from gdq_pddl.envs.base import ModelEnv
from gdq_pddl.envs.model import ModelArrays, compile_model, full_state
from gdq_pddl.envs.render import Frame, MapPainter, ansi
from gdq_pddl.errors import WorldError
from gdq_pddl.spaces import LearnerSpaces
from gdq_pddl.world import Task, World, builtin_world, load_world

DEFAULT_TASK = "C"


def as_world(world: str | Path | World | None) -> World:
    """A :class:`World` from a world, a file path, a built-in name, or ``None`` (office).

    A bare name without a suffix that is not an existing file (``"office"``) is a
    built-in world; anything else is read as a world file.
    """
    if world is None:
        return load_world(None)
    if isinstance(world, World):
        return world
    path = Path(world)
    if isinstance(world, str) and not path.suffix and path.name == world and not path.exists():
        try:
            return builtin_world(world)
        except OSError:
            raise WorldError(world, "", "no such world file or built-in world") from None
    return load_world(path)


def pick_task(world: World, task: str | None, start: str | None, goal: str | None) -> Task:
    """The task to run: by name, from start/goal, or the default.

    The default is task ``C`` when the world has one, else the world's first task.
    Raises :class:`WorldError` if start and goal are the same position.
    """
    if task is None and start is None and goal is None:
        if DEFAULT_TASK not in world.tasks and world.tasks:
            task = next(iter(world.tasks))
        else:
            task = DEFAULT_TASK
    chosen = world.resolve(task=task, start=start, goal=goal)
    if chosen.start == chosen.goal:
        raise WorldError(world.source, f"tasks.{chosen.name}" if task else "start/goal",
                         f"start and goal are the same position ({chosen.start}); "
                         "the episode would be over before it begins")
    return chosen


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
    from gdq_pddl.abstraction import OfficeAbstraction
    from gdq_pddl.abstraction.masks import knowledge_action_mask
    from gdq_pddl.planning.base import PlanningProblem
    from gdq_pddl.resources import domain_text
    from gdq_pddl.world import office_problem

    problem = PlanningProblem.from_texts(domain_text(), office_problem(world, task))
    masks = knowledge_action_mask(OfficeAbstraction(world), problem.task)
    _MASKS[key] = (weakref.ref(world), masks)
    return masks


_MASKS: dict[tuple[int, str], tuple[weakref.ref, np.ndarray]] = {}


class OfficeEnv(ModelEnv):
    """A robot in an office reaching a goal position (see the module docstring)."""

    metadata = {"render_modes": ["ansi", "rgb_array"], "render_fps": 4}

    def __init__(self, task: str | None = None, start: str | None = None,
                 goal: str | None = None, world: str | Path | World | None = None,
                 render_mode: str | None = None) -> None:
        if render_mode is not None and render_mode not in self.metadata["render_modes"]:
            raise ValueError(f"render_mode must be one of {self.metadata['render_modes']} "
                             f"or None, got {render_mode!r}")
        self.world: World = as_world(world)
        self.task: Task = pick_task(self.world, task, start, goal)
        self.spaces = LearnerSpaces(self.world)
        self.model: ModelArrays = compile_model(self.world)
        self.observation_space = Discrete(self.spaces.n_states)
        self.action_space = Discrete(self.spaces.n_actions)
        self.render_mode = render_mode
        self.goal_pos = self.world.index[self.task.goal]
        self.start_state = full_state(self.world, self.task.start)
        self._begin()
        self._painter: MapPainter | None = None

    @cached_property
    def action_masks(self) -> np.ndarray:
        return office_action_masks(self.world, self.task)

    def decode(self, fs: int) -> tuple[str, frozenset[str]]:
        """``(position name, names of the open doors)`` of a full state."""
        pos, mask = divmod(int(fs), 1 << self.model.n_doors)
        opened = frozenset(d.name for i, d in enumerate(self.world.doors) if mask >> i & 1)
        return self.world.positions[pos], opened

    def _info(self) -> dict[str, Any]:
        pos = int(self.model.pos_of[self._fs])
        return {"position": self.world.positions[pos], **super()._info()}

    def _frame(self) -> Frame:
        robot, opened = self.decode(self._fs)
        return Frame(self.world, self.task.name, robot, self.task.goal, opened, self._t,
                     self._cause)

    def render(self) -> str | np.ndarray | None:
        if self.render_mode is None:
            gym.logger.warn("render() called without a render_mode; pass render_mode="
                            "'ansi' or 'rgb_array' to gymnasium.make")
            return None
        if self.render_mode == "ansi":
            return ansi(self._frame())
        if self._painter is None:
            self._painter = MapPainter(self.world)
        return self._painter(self._frame())
