"""Tabular learners: Q-learning, Dyna-Q, DARLING and Guided Dyna-Q (GDQ).

::

    import gymnasium, numpy as np, gdq_pddl
    from gdq_pddl.learners import GDQ, office_task_context, run_episodes
    env = gymnasium.make("gdq_pddl/Office-v0", task="C")
    ctx = office_task_context(env.unwrapped.world, env.unwrapped.task)
    learner = GDQ(ctx)
    env.reset(seed=0)
    records = run_episodes(learner, env, 300, np.random.default_rng(1))

The shared base class is in :mod:`~gdq_pddl.learners.tabular`, the GDQ classes (the
default :class:`GDQ`, the paper's :class:`PaperGDQ`) in
:mod:`~gdq_pddl.learners.gdq_learner` (the default GDQ's rules in
:mod:`~gdq_pddl.learners.gdq`), the baselines and :func:`make_learner` in
:mod:`~gdq_pddl.learners.agents`; ``docs/learners.md`` says where everything else is,
compares the variants and records the decisions behind them.
"""

from gdq_pddl.learners.agents import METHODS, Darling, DynaQ, QLearning, make_learner
from gdq_pddl.learners.config import (
    DarlingConfig,
    DynaQConfig,
    GDQConfig,
    LearnerConfig,
    QLearningConfig,
)
from gdq_pddl.learners.context import (
    TaskContext,
    empty_plan_table,
    office_task_context,
    pddl_task_context,
)
from gdq_pddl.learners.episodes import (
    EpisodeRecords,
    evaluate_policy,
    run_compact,
    run_episodes,
)
from gdq_pddl.learners.gdq_learner import GDQ, PaperGDQ
from gdq_pddl.learners.saving import GreedyPolicy, load_generators, load_learner, save_learner
from gdq_pddl.learners.tabular import Learner, TabularLearner

__all__ = [
    "GDQ", "METHODS", "Darling", "DarlingConfig", "DynaQ", "DynaQConfig", "EpisodeRecords",
    "GDQConfig", "GreedyPolicy", "Learner", "LearnerConfig", "PaperGDQ", "QLearning",
    "QLearningConfig", "TabularLearner",
    "TaskContext", "empty_plan_table", "make_learner", "office_task_context", "pddl_task_context",
    "run_compact", "run_episodes", "evaluate_policy", "load_generators", "load_learner",
    "save_learner",
]
