"""The baselines :class:`QLearning`, :class:`DynaQ` and :class:`Darling` on the shared
:class:`~gdq_pddl.learners.tabular.TabularLearner`; :func:`make_learner` (from
:mod:`gdq_pddl.learners.registry`, which declares every learner) by the names the command
line takes.
"""

from __future__ import annotations

import numpy as np

from gdq_pddl.errors import ConfigError
from gdq_pddl.learners import registry
from gdq_pddl.learners.config import DarlingConfig, DynaQConfig, QLearningConfig
from gdq_pddl.learners.context import TaskContext
from gdq_pddl.learners.gdq_learner import GDQ
from gdq_pddl.learners.registry import learner_class, make_learner
from gdq_pddl.learners.tables import KIND_DARLING, KIND_DYNAQ, KIND_QLEARNING
from gdq_pddl.learners.tabular import Learner, TabularLearner

__all__ = ["GDQ", "METHODS", "Darling", "DynaQ", "Learner", "QLearning", "TabularLearner",
           "learner_class", "make_learner"]


class QLearning(TabularLearner):
    """Epsilon-greedy Q-learning: the TD update on each real step, nothing else."""

    kind = KIND_QLEARNING
    config_type = QLearningConfig
    reads_knowledge = False


class DynaQ(TabularLearner):
    """Q-learning + the learned model + N expected backups per real step on uniformly
    random pairs tried more than m times (:mod:`gdq_pddl.learners.learned_model`)."""

    kind = KIND_DYNAQ
    config_type = DynaQConfig
    reads_knowledge = False


class Darling(TabularLearner):
    """Q-learning restricted, at every state, to the actions that start a plan within the
    length tolerance from it (every action where none does), when acting and in the max
    of the update. ``variant="code"``: as the GDQ authors' agent runs it (``docs/learners.md``)."""

    kind = KIND_DARLING
    config: DarlingConfig
    config_type = DarlingConfig

    def _plan_actions(self, context: TaskContext) -> np.ndarray:
        """Per state, the actions that start a plan within the tolerance (all actions
        where there is no plan)."""
        table = context.darling_plans
        if table is None:
            raise ConfigError("DARLING needs a task context with darling_plans")
        if context.darling_tolerance is not None and not np.isclose(
                context.darling_tolerance, self.config.tolerance):
            raise ConfigError(f"the context's DARLING plans use tolerance "
                              f"{context.darling_tolerance}, the config "
                              f"{self.config.tolerance}")
        return table.allowed_actions(context.live)

    def _allowed(self, context: TaskContext) -> np.ndarray:
        code = self.config.variant == "code"  # the max ranges over every action
        return super()._allowed(context) if code else self._plan_actions(context)

    def _guide(self, context: TaskContext, allowed: np.ndarray) -> np.ndarray:
        return self._plan_actions(context) if self.config.variant == "code" else allowed


METHODS: tuple[str, ...] = registry.built_in_names()
"""Every built-in learner by the name the command line takes (``--method``), from
:mod:`gdq_pddl.learners.registry` (which also holds those of other packages)."""
