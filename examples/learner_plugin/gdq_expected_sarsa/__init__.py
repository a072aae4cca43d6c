"""Expected SARSA (van Seijen et al. 2009) for gdq_pddl: a learner from another package.

The TD target is the reward plus the discounted *expected* value of the next state under
the epsilon-greedy policy the learner acts by, instead of Q-learning's max:

    E[Q(s2, .)] = (1 - epsilon) * max_a Q(s2, a) + epsilon * mean_a Q(s2, a)

(over the actions allowed in ``s2``; the greedy actions share the max, so ties do not
change it). Everything else is gdq_pddl's: the arrays, epsilon-greedy acting, the episode
loop. The rule is a numba function, so the learner runs in gdq_pddl's compiled episode
loop, which numba compiles for this rule once per process (``docs/howto-add-learner.md``).
"""

from __future__ import annotations

from dataclasses import dataclass

import numba
import numpy as np

from gdq_pddl.learners.config import LearnerConfig, documented
from gdq_pddl.learners.registry import LearnerEntry
from gdq_pddl.learners.tables import KIND_QLEARNING, QTable, td_update
from gdq_pddl.learners.tabular import TabularLearner

__all__ = ["ENTRY", "ExpectedSarsa", "ExpectedSarsaConfig", "expected_value", "observe"]


@documented
@dataclass(frozen=True)
class ExpectedSarsaConfig(LearnerConfig):
    """Expected SARSA: the shared alpha, gamma and epsilon; epsilon is also the share of
    the expectation that is uniform over the allowed actions."""


@numba.njit(cache=True)
def expected_value(table: QTable, epsilon: float, s: int) -> float:
    """E[Q(s, .)] under epsilon-greedy over the actions allowed in ``s`` (0 at a goal)."""
    if table.goal[s]:
        return 0.0
    total, n = 0.0, 0
    for a in range(table.q.shape[1]):
        if table.allowed[s, a]:
            total += table.q[s, a]
            n += 1
    if n == 0:
        return 0.0
    return (1.0 - epsilon) * table.v[s] + epsilon * total / n


@numba.njit(cache=True)
def observe(table, model, plans, prior, queue, own, p, s: int, a: int, r: float, s2: int,
            terminated: bool, truncated: bool, rng: np.random.Generator) -> bool:
    """After a real step: the TD update towards the expected target (``r`` alone at the
    end of an episode, as every gdq_pddl learner). Always True (no learned model)."""
    target = r if (terminated or truncated) else r + p.gamma * expected_value(
        table, p.epsilon, s2)
    td_update(table, s, a, target, p.alpha)
    return True


class ExpectedSarsa(TabularLearner):
    """Expected SARSA on gdq_pddl's tables: epsilon-greedy acting (the shared rule), the
    expected update (:func:`observe`)."""

    kind = KIND_QLEARNING  # the arrays of a model-free learner: no learned model
    config_type = ExpectedSarsaConfig
    reads_knowledge = False
    observe_rule = staticmethod(observe)


ENTRY = LearnerEntry(
    name="Expected-SARSA",
    learner=ExpectedSarsa,
    config=ExpectedSarsaConfig,
    description="Expected SARSA: the TD target's max replaced by the epsilon-greedy "
                "expectation",
    knowledge="none",
    colour="#8c564b",  # brown
)
"""What ``gdq-pddl`` needs to know of the learner (the entry point names this object)."""
