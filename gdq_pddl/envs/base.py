"""What every env of this package shares: episodes stepped through one compiled model.

An env holds :class:`~gdq_pddl.envs.model.ModelArrays` (``model``), the hidden state an
episode starts in (``start_state``) and the ``goal_pos`` that :func:`env_step`'s goal
test compares with. :class:`ModelEnv` implements ``reset`` and ``step`` once from those
three, so the office and a PDDL domain step through the same code, and the fast episode
runner (:mod:`gdq_pddl.learners.runner`) accepts any subclass.
"""

from __future__ import annotations

from typing import Any

import gymnasium as gym
from gymnasium.error import ResetNeeded

from gdq_pddl.envs.model import CAUSES, ModelArrays, env_step


class ModelEnv(gym.Env[int, int]):
    """Base class: subclasses set ``model``, ``start_state``, ``goal_pos`` and the spaces,
    and may extend :meth:`_info`."""

    model: ModelArrays
    start_state: int
    goal_pos: int

    def _begin(self) -> None:
        """Mark the env as not started (call at the end of ``__init__``)."""
        self._fs, self._t, self._cause, self._done = self.start_state, 0, "", True

    def transition_arrays(self) -> ModelArrays:
        """The true model (CSR outcomes over full states) for value iteration.

        Pair with ``goal_pos``: ``gdq_pddl.envs.solve.solve(env.transition_arrays(),
        env.goal_pos)``. The arrays are shared with the env: do not modify them.
        """
        return self.model

    def reset(self, *, seed: int | None = None,
              options: dict[str, Any] | None = None) -> tuple[int, dict[str, Any]]:
        super().reset(seed=seed)
        self._fs, self._t, self._cause, self._done = self.start_state, 0, "", False
        return int(self.model.obs_of[self._fs]), self._info()

    def step(self, action: int) -> tuple[int, float, bool, bool, dict[str, Any]]:
        if self._done:
            raise ResetNeeded("the episode is over (or never began): call reset() first")
        a = int(action)
        if not 0 <= a < self.model.n_actions:
            raise ValueError(f"action must be in [0, {self.model.n_actions}), got {action!r}")
        fs, reward, terminated, truncated, cause = env_step(
            self.model, self._fs, a, self._t, self.goal_pos, self.np_random)
        self._fs, self._t, self._cause = int(fs), self._t + 1, CAUSES[cause]
        self._done = bool(terminated or truncated)
        return (int(self.model.obs_of[self._fs]), float(reward), bool(terminated),
                bool(truncated), self._info())

    def _info(self) -> dict[str, Any]:
        """``area`` (0: none), ``cause``, ``full_state`` and ``step``."""
        pos = int(self.model.pos_of[self._fs])
        return {
            "area": int(self.model.area_of_pos[pos]),
            "cause": self._cause,
            "full_state": self._fs,
            "step": self._t,
        }
