"""The env of a PPDDL problem explored online (:mod:`gdq_pddl.envs.online`): each step
reads the current state's own true model and expands the state it reaches, so the
states are found as episodes reach them. It steps exactly as
:class:`~gdq_pddl.envs.pddl_env.PDDLEnv` does on the enumerated problem (the same
outcomes in the same order, the same draws: ``tests/envs/test_online.py``). A factored
ground action (:attr:`~gdq_pddl.pddl.grounding.GroundOp.parts`), whose outcomes are too
many to list, is stepped by drawing one outcome of each part
(:meth:`~gdq_pddl.pddl.lazy.LazyGraph.draw`), then its cost and reward as any step's."""

from __future__ import annotations

from typing import Any

import numpy as np

from gdq_pddl.envs.base import CompiledEnv
from gdq_pddl.envs.online import OnlineInstance
from gdq_pddl.envs.pddl_env import GOAL_POS
from gdq_pddl.envs.step import env_act, file_step, finish_step


class OnlineEnv(CompiledEnv):
    """The env of an :class:`OnlineInstance`: each step expands the state it reaches."""

    metadata = {"render_modes": ["ansi"], "render_fps": 4}

    def __init__(self, instance: OnlineInstance, render_mode: str | None = None) -> None:
        super().__init__(instance, instance.model, render_mode)

    def _restart(self) -> None:
        self._x = 0

    def _advance(self, a: int) -> tuple[float, bool, bool, int]:
        inst = self.instance
        graph = inst.graph
        if a < inst.n_ops and graph.factored[a] and (graph.offered(self._x) == a).any():
            # a factored action: its outcome drawn part by part (one uniform a part),
            # then the cost and the reward as every step has them
            y, stuck, gain = graph.draw(self._x, a, self.np_random)
            m, at_goal = inst.model, bool(graph.is_goal[y])
            if m.own_scale:
                _, reward, terminated, truncated, cause = file_step(
                    m, a, gain, 0, stuck, at_goal, self._t, self.np_random)
            else:
                _, reward, terminated, truncated, cause = finish_step(
                    m, a, 0, stuck, at_goal, self._t, self.np_random, gain)
            self._x = y
            inst.visit(y)
            self.observation_space.n = inst.n_states
            return reward, terminated, truncated, cause
        model, states = inst.step_model(self._x)
        fs, reward, terminated, truncated, cause = env_act(
            model, 0, a, self._t, GOAL_POS, self.np_random)
        self._x = int(states[fs])
        inst.visit(self._x)
        self.observation_space.n = inst.n_states
        return reward, terminated, truncated, cause

    def _observe(self) -> int:
        return int(self.instance.row_of_state[self._x])

    def _position(self) -> int:
        return GOAL_POS if self.instance.graph.is_goal[self._x] else 0

    def facts(self) -> np.ndarray:
        """The true state's atoms (``instance.atom_names``) as ``int8`` 0/1."""
        return self.instance.facts(self._observe())

    def _info(self) -> dict[str, Any]:
        return {**super()._info(), "full_state": self._observe()}

    def render(self) -> str | None:
        if self.render_mode is None:
            return None
        why = f" ({self._cause})" if self._cause else ""
        return f"step {self._t}{why}: " + " ".join(sorted(self.instance.graph.atoms(self._x)))
