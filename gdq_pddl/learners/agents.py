"""The learners by name: the baselines :class:`QLearning`, :class:`DynaQ` and
:class:`Darling` on the shared :class:`~gdq_pddl.learners.tabular.TabularLearner`, with
:class:`~gdq_pddl.learners.gdq_learner.GDQ`, and :func:`make_learner` by the names the
command line takes (:data:`METHODS`).
"""

from __future__ import annotations

import numpy as np

from gdq_pddl.errors import ConfigError
from gdq_pddl.learners.config import (
    DarlingConfig,
    DynaQConfig,
    GDQConfig,
    LearnerConfig,
    QLearningConfig,
)
from gdq_pddl.learners.context import TaskContext
from gdq_pddl.learners.gdq_learner import GDQ
from gdq_pddl.learners.tables import KIND_DARLING, KIND_DYNAQ, KIND_QLEARNING
from gdq_pddl.learners.tabular import Learner, TabularLearner

__all__ = ["GDQ", "METHODS", "Darling", "DynaQ", "Learner", "QLearning", "TabularLearner",
           "make_learner"]


class QLearning(TabularLearner):
    """Epsilon-greedy Q-learning: the TD update on each real step, nothing else."""

    kind = KIND_QLEARNING
    name = "Q-learning"
    config_type = QLearningConfig
    reads_knowledge = False


class DynaQ(TabularLearner):
    """Q-learning + the learned model + N expected backups per real step on uniformly
    random pairs tried more than m times (:mod:`gdq_pddl.learners.learned_model`)."""

    kind = KIND_DYNAQ
    name = "Dyna-Q"
    config_type = DynaQConfig
    reads_knowledge = False


class Darling(TabularLearner):
    """Q-learning restricted, at every state, to the actions that start a plan within the
    length tolerance from it (every action where none does), when acting and in the max
    of the update. ``variant="code"``: as the GDQ authors' agent runs it (``docs/learners.md``)."""

    kind = KIND_DARLING
    name = "DARLING"
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


METHODS: dict[str, tuple[type[TabularLearner], type[LearnerConfig], str | None]] = {
    "GDQ": (GDQ, GDQConfig, None),
    "GDQ-literal": (GDQ, GDQConfig, "literal"),
    "GDQ-code": (GDQ, GDQConfig, "code"),
    "DARLING": (Darling, DarlingConfig, None),
    "DARLING-code": (Darling, DarlingConfig, "code"),
    "Dyna-Q": (DynaQ, DynaQConfig, None),
    "Q-learning": (QLearning, QLearningConfig, None),
}
"""Every learner by the name the command line takes (``--method``): its class, its config
class and the variant the name stands for (None: the config's default)."""

_BY_KEY = {name.lower().replace("-", ""): name for name in METHODS}


def _method(method: str) -> tuple:
    """The :data:`METHODS` entry of a name in any case, with or without hyphens and
    underscores."""
    key = method.lower().replace("-", "").replace("_", "") if isinstance(method, str) else ""
    if key not in _BY_KEY:
        raise ConfigError(f"unknown method {method!r} (known: {', '.join(METHODS)})")
    return METHODS[_BY_KEY[key]]


def learner_class(method: str) -> type[TabularLearner]:
    """The class of the learner of ``method`` (as :func:`make_learner` takes it): what it
    reads of a problem explored online (:attr:`TabularLearner.reads_knowledge`,
    :attr:`TabularLearner.estimate_weight`)."""
    return _method(method)[0]


def make_learner(method: str, context: TaskContext, **config: object) -> TabularLearner:
    """A fresh learner by name for ``context``, with config overrides, e.g.
    ``make_learner("GDQ-code", ctx, alpha=0.2)``. ``method``: a name of :data:`METHODS`, in
    any case, with or without hyphens and underscores (``gdq``, ``dynaq``, ``q_learning``);
    a name without a variant takes ``variant=...`` among the overrides."""
    cls, config_type, variant = _method(method)
    if variant is not None and config.setdefault("variant", variant) != variant:
        raise ConfigError(f"method {method!r} is variant {variant!r}, and the overrides "
                          f"say variant={config['variant']!r}")
    try:
        settings = config_type(**config)  # type: ignore[arg-type]
    except TypeError as e:
        raise ConfigError(f"{method}: {e}".replace("__init__() ", "")) from None
    return cls(context, settings)
