"""The fast episode loop over a :class:`~gdq_pddl.envs.compact.CompactEnv` (large worlds).

The same loop as :func:`gdq_pddl.learners.runner.run_episodes`' compiled path, calling
:func:`gdq_pddl.envs.compact.compact_step` and the same :mod:`~gdq_pddl.learners.core`
rules in the same order, so on the office it consumes the same random numbers and gives
the same records as the full-state runner (tested).
"""

from __future__ import annotations

import numba
import numpy as np

from gdq_pddl.envs.compact import CompactEnv, CompactModel, compact_step, observe_state
from gdq_pddl.envs.model import CAUSE_GOAL
from gdq_pddl.learners import core
from gdq_pddl.learners.agents import TabularLearner
from gdq_pddl.learners.runner import EpisodeRecords


def run_compact(learner: TabularLearner, env: CompactEnv, n_episodes: int,
                rng: np.random.Generator) -> EpisodeRecords:
    """Run ``n_episodes`` of ``learner`` in ``env`` (seed ``env`` with ``reset`` first)."""
    env = env.unwrapped
    n_areas = max(1, int(env.model.area_of_pos.max()))
    returns = np.zeros(n_episodes)
    steps = np.zeros(n_episodes, dtype=np.int64)
    success = np.zeros(n_episodes, dtype=np.bool_)
    areas = np.zeros((n_episodes, n_areas), dtype=np.int64)
    _episodes(env.model, env.start_pos, env.goal_pos, env.doors, learner.tables,
              learner.params, env.np_random, rng, returns, steps, success, areas)
    return EpisodeRecords(returns, steps, success, areas)


@numba.njit(cache=True)
def _episodes(m: CompactModel, start: int, goal_pos: int, doors: np.ndarray, t: core.Tables,
              p: core.Params, env_rng: np.random.Generator, rng: np.random.Generator,
              returns: np.ndarray, steps: np.ndarray, success: np.ndarray,
              areas: np.ndarray) -> None:
    for ep in range(len(returns)):
        pos = start
        doors[:] = 0
        s = observe_state(m, pos, doors)
        step = 0
        while True:
            a = core.act(t, p, s, rng)
            pos, r, terminated, truncated, cause = compact_step(m, pos, doors, a, step,
                                                                goal_pos, env_rng)
            s2 = observe_state(m, pos, doors)
            core.observe(t, p, s, a, r, s2, terminated, truncated, rng)
            step += 1
            returns[ep] += r
            area = m.area_of_pos[pos]
            if area > 0:
                areas[ep, area - 1] += 1
            if terminated or truncated:
                success[ep] = cause == CAUSE_GOAL
                break
            s = s2
        steps[ep] = step
