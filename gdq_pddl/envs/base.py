"""What every env of this package shares: episodes stepped through one compiled model.

:class:`CompiledEnv` holds the episode bookkeeping of both model kinds (step count,
end cause, the reset-before-step and action-range checks) and implements ``reset`` and
``step`` once over three hooks: restart the hidden state, advance it by one compiled
step, and observe it.

:class:`ModelEnv` fills them in for :class:`~gdq_pddl.envs.model.ModelArrays`
(``model``), the hidden full state an episode starts in (``start_state``) and the
``goal_pos`` that :func:`env_step`'s goal test compares with, so the office and a PDDL
domain step through the same code, and the fast episode runner
(:mod:`gdq_pddl.learners.episodes`) accepts any subclass; the package's one subclass is
:class:`~gdq_pddl.envs.pddl_env.PDDLEnv`, on any instance.
:class:`~gdq_pddl.envs.compact.CompactEnv` fills them in for the compact model of an
office instance (large buildings); it is not a :class:`ModelEnv`.
"""

from __future__ import annotations

import operator
from typing import Any

import gymnasium as gym
import numpy as np
from gymnasium.error import ResetNeeded

from gdq_pddl.envs.model import CAUSES, ModelArrays, env_step


class CompiledEnv(gym.Env[int, int]):
    """Base class: subclasses set ``model`` and the spaces, call :meth:`_begin` at the
    end of ``__init__`` and implement :meth:`_restart`, :meth:`_advance`,
    :meth:`_observe` and :meth:`_info`."""

    model: tuple
    """The compiled model: :class:`ModelArrays`, or the compact model of
    :mod:`gdq_pddl.envs.compact` (both are named tuples of arrays)."""

    def _begin(self) -> None:
        """Mark the env as not started (call at the end of ``__init__``)."""
        self._restart()
        self._t, self._cause, self._done = 0, "", True

    def reset(self, *, seed: int | None = None,
              options: dict[str, Any] | None = None) -> tuple[int, dict[str, Any]]:
        super().reset(seed=seed)
        self._restart()
        self._t, self._cause, self._done = 0, "", False
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
        self._t, self._cause = self._t + 1, CAUSES[cause]
        self._done = bool(terminated or truncated)
        return self._observe(), float(reward), bool(terminated), bool(truncated), self._info()

    def _restart(self) -> None:
        """Put the hidden state back where an episode starts."""
        raise NotImplementedError

    def _advance(self, a: int) -> tuple[float, bool, bool, int]:
        """Take action ``a`` at step ``self._t`` with the compiled step, move the hidden
        state on and return ``(reward, terminated, truncated, cause code)``."""
        raise NotImplementedError

    def _observe(self) -> int:
        """The learner state of the hidden state."""
        raise NotImplementedError

    def _info(self) -> dict[str, Any]:
        raise NotImplementedError


class ModelEnv(CompiledEnv):
    """Base class of the envs over :class:`ModelArrays`: subclasses set ``model``,
    ``start_state``, ``goal_pos`` and the spaces, implement :attr:`action_masks`, and
    may extend :meth:`_info`."""

    model: ModelArrays
    start_state: int
    goal_pos: int

    @property
    def action_masks(self) -> np.ndarray:
        """``int8[n_states, n_actions]``, read-only: 1 where the knowledge says the action
        can do something in the learner state (:mod:`gdq_pddl.abstraction.masks`); row
        ``obs`` is ``info["action_mask"]``."""
        raise NotImplementedError

    def transition_arrays(self) -> ModelArrays:
        """The true model (CSR outcomes over full states) for value iteration.

        Pair with ``goal_pos``: ``gdq_pddl.envs.solve.solve(env.transition_arrays(),
        env.goal_pos)``. The arrays are shared with the env: do not modify them.
        """
        return self.model

    def _restart(self) -> None:
        self._fs = self.start_state

    def _advance(self, a: int) -> tuple[float, bool, bool, int]:
        fs, reward, terminated, truncated, cause = env_step(
            self.model, self._fs, a, self._t, self.goal_pos, self.np_random)
        self._fs = int(fs)
        return reward, terminated, truncated, cause

    def _observe(self) -> int:
        return int(self.model.obs_of[self._fs])

    def _info(self) -> dict[str, Any]:
        """``action_mask`` (a copy of the state's row of :attr:`action_masks`: info must be
        new data on every call), ``area`` (0: none), ``cause``, ``full_state`` and
        ``step``."""
        pos = int(self.model.pos_of[self._fs])
        return {
            "action_mask": self.action_masks[self.model.obs_of[self._fs]].copy(),
            "area": int(self.model.area_of_pos[pos]),
            "cause": self._cause,
            "full_state": self._fs,
            "step": self._t,
        }
