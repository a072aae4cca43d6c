"""The fast episode loop over a :class:`~gdq_pddl.envs.compact.CompactEnv` (large worlds).

The compiled loop of :func:`gdq_pddl.learners.runner.run_episodes`' fast path (one
definition, compiled for the compact model), calling
:func:`gdq_pddl.envs.compact.compact_step` and the same :mod:`~gdq_pddl.learners.core`
rules in the same order, so on the office it consumes the same random numbers and gives
the same records as the full-state runner (tested).
"""

from __future__ import annotations

import numpy as np

from gdq_pddl.envs.compact import CompactEnv
from gdq_pddl.learners.agents import TabularLearner
from gdq_pddl.learners.runner import EpisodeRecords, run_compiled


def run_compact(learner: TabularLearner, env: CompactEnv, n_episodes: int,
                rng: np.random.Generator) -> EpisodeRecords:
    """Run ``n_episodes`` of ``learner`` in ``env`` (seed ``env`` with ``reset`` first)."""
    env = env.unwrapped
    return run_compiled(env.model, env.start_pos, env.goal_pos, env.doors, learner,
                        env.np_random, n_episodes, rng, max(1, int(env.model.area_of_pos.max())))
