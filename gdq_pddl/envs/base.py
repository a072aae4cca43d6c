"""The one env base: an instance's episodes stepped through one compiled model.

:class:`CompiledEnv` implements ``reset`` (with its ``start``/``goal`` options),
``step``, ``action_masks()``, ``spec`` and the common ``info`` over four hooks. Its two
subclasses are the two representations of an instance's true model:
:class:`~gdq_pddl.envs.pddl_env.PDDLEnv` over full states (both env ids) and
:class:`~gdq_pddl.envs.office.CompactEnv` over an office instance's learner states.
"""

from __future__ import annotations

import operator
from collections.abc import Mapping
from dataclasses import replace
from typing import Any

import gymnasium as gym
import numpy as np
from gymnasium.envs.registration import EnvSpec
from gymnasium.error import ResetNeeded
from gymnasium.spaces import Discrete

from gdq_pddl.envs.step import CAUSES
from gdq_pddl.errors import ConfigError

RESET_OPTIONS = ("start", "goal")
"""The keys ``reset(options=...)`` takes (any other is refused)."""


class CompiledEnv(gym.Env[int, int]):
    """Base class: subclasses implement :meth:`_restart`, :meth:`_advance`,
    :meth:`_observe` and :meth:`_position`; what the instance says is reached through
    the named properties below, the rest through ``env.unwrapped.instance``."""

    model: tuple
    """The compiled true model (``ModelArrays``, for ``envs.solve.solve``, or ``CompactModel``)."""

    def __init__(self, instance: Any, model: tuple, render_mode: str | None = None) -> None:
        self.check_render_mode(render_mode)
        self.instance, self.model, self.render_mode = instance, model, render_mode
        self._given = instance  # what reset() without options goes back to
        self.observation_space = Discrete(instance.n_states)
        """One observation per learner state."""
        self.action_space = Discrete(instance.n_actions)
        """One action per learner action (the office: 95, verb-major)."""
        self._restart()
        self._t, self._cause, self._done = 0, "", True  # not started
        self._action = -1  # the last action taken; -1 before the first of an episode

    def check_render_mode(self, render_mode: str | None) -> None:
        """Refuse a render mode this env class cannot draw (a :class:`ConfigError`)."""
        modes = self.metadata["render_modes"]
        if render_mode is not None and render_mode not in modes:
            raise ConfigError(f"render_mode {render_mode!r}: this env draws only "
                              f"{', '.join(map(repr, modes)) or 'nothing'} (or None)")

    # What the instance says, named (the rest: ``env.unwrapped.instance``).
    mask_table = property(lambda self: self.instance.mask_table,
                          doc="``bool[n_states, n_actions]``: the learner actions that may "
                          "change each learner state (``action_masks`` reads its row).")
    atom_names = property(lambda self: self.instance.atom_names,
                          doc="The names of the ground atoms, in the order of ``facts()``.")
    world = property(lambda self: self.instance.world,
                     doc="Of an office task: its :class:`~gdq_pddl.world_types.World`.")
    task = property(lambda self: self.instance.task,
                    doc="Of an office task: its :class:`~gdq_pddl.world_types.Task`.")
    spaces = property(lambda self: self.instance.spaces,
                      doc="Of an office task: its learner spaces (positions and doors).")

    def action_name(self, a: int) -> str:
        """The name of learner action ``a``."""
        return self.instance.action_name(a)

    def decode(self, fs: int) -> tuple[str, frozenset[str]]:
        """Of an office task: full state ``fs`` as its position and its open doors."""
        return self.instance.decode(fs)

    def atoms(self, s: int) -> frozenset[str]:
        """The atoms true in state ``s`` of a PDDL problem."""
        return self.instance.atoms(s)

    def action_masks(self) -> np.ndarray:
        """``bool[n_actions]``: the current state's row of ``mask_table`` (for ``MaskablePPO``)."""
        return self.mask_table[self._observe()].astype(bool)

    @property
    def spec(self) -> EnvSpec | None:
        """``gymnasium.make``'s spec (or None), ``max_episode_steps`` the env's step limit."""
        spec = self.__dict__.get("_spec")
        return None if spec is None else replace(spec, max_episode_steps=int(self.model.step_limit))

    @spec.setter
    def spec(self, value: EnvSpec | None) -> None:
        self._spec = value

    def reset(self, *, seed: int | None = None,
              options: dict[str, Any] | None = None) -> tuple[int, dict[str, Any]]:
        """Start an episode, at ``options``' ``start``/``goal`` if given (see ``restarted``).
        Where the goal holds at the start the episode is already over: ``info["cause"]``
        is ``"goal"`` and :meth:`step` raises ``ResetNeeded``."""
        super().reset(seed=seed)
        if options is not None and not isinstance(options, Mapping):
            raise ConfigError(f"reset options: expected a dict such as {{\"start\": ...}}, got "
                              f"{type(options).__name__} {options!r}")
        unknown = [k for k in options or {} if k not in RESET_OPTIONS]
        if unknown:
            raise ConfigError(f"reset options: unknown key {unknown[0]!r} (known: "
                              f"{', '.join(RESET_OPTIONS)})")
        self.instance = self._given.restarted(**dict(options)) if options else self._given
        self._restart()
        # A start where the goal holds is over before its first action, as in mdpsim:
        # info's cause says "goal" and step() asks for a new reset.
        at_goal = self._position() == self.instance.goal_pos
        self._t, self._cause, self._done = 0, "goal" if at_goal else "", at_goal
        self._action = -1
        return self._observe(), self._info()

    def step(self, action: int) -> tuple[int, float, bool, bool, dict[str, Any]]:
        if self._done:
            raise ResetNeeded("the episode is over (or never began): call reset() first")
        try:  # an int or a numpy integer; 2.5 (or 2.0) is not an action
            a = operator.index(action) if not isinstance(action, bool) else None
        except TypeError:
            a = None
        if a is None or not 0 <= a < self.model.n_actions:
            raise ValueError(f"action must be an integer in [0, {self.model.n_actions}), "
                             f"got {action!r}")
        reward, terminated, truncated, cause = self._advance(a)
        self._t, self._cause, self._action = self._t + 1, CAUSES[cause], a
        self._done = bool(terminated or truncated)
        return self._observe(), float(reward), bool(terminated), bool(truncated), self._info()

    def _restart(self) -> None:
        """Put the hidden state back where an episode starts."""
        raise NotImplementedError

    def _advance(self, a: int) -> tuple[float, bool, bool, int]:
        """Take action ``a``; return ``(reward, terminated, truncated, cause code)``."""
        raise NotImplementedError

    def _observe(self) -> int:
        """The learner state of the hidden state."""
        raise NotImplementedError

    def _position(self) -> int:
        """The position index of the hidden state (into ``area_of_pos``)."""
        raise NotImplementedError

    def learner_state(self) -> int:
        """The current observation (a learner state): what the instance's
        ``goal_distance`` and ``plan_action`` read."""
        return self._observe()

    def facts(self) -> np.ndarray:
        """``int8[len(instance.atom_names)]``: 1 for each atom true in the hidden state."""
        raise NotImplementedError

    def _info(self) -> dict[str, Any]:
        """The instance's ``info``, ``action_mask`` (a copy), ``plan_action`` (the first
        action of a shortest plan of the knowledge from here, ``instance.plan_action``;
        -1: none), ``area``, ``cause``, ``step``."""
        pos, obs = self._position(), self._observe()
        return {**self.instance.info(pos),
                "action_mask": self.mask_table[obs].copy(),
                "plan_action": self.instance.plan_action(obs),
                "area": int(self.model.area_of_pos[pos]), "cause": self._cause, "step": self._t}
