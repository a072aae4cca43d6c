"""``FF-Replan``: follow the determinised knowledge's plan, replan when an outcome leaves it.

Source: Yoon, Fern and Givan, "FF-Replan: a baseline for probabilistic planning", ICAPS
2007. It learns nothing: it shows what the knowledge alone is worth, and what learning
adds. The rule, in three lines::

    plan: a shortest plan of the determinised knowledge from the current state
    act: the plan's next action
    after a step: if the outcome is not the state the plan expected, replan from it

Choices the source leaves open, or that differ here (``docs/decisions.md``, "FF-Replan"):

- *The planner*: breadth first on the knowledge (the context's plan lengths and prior
  model: the same knowledge GDQ reads), which finds shortest plans, where Yoon et al. use
  FF (a satisficing planner, so not always shortest).
- *Determinisation*: all-outcomes (every outcome of a probabilistic action is an action
  of its own; the plan picks the outcome it wants), as in the paper; most-likely as a
  setting, which needs the problem's knowledge read that way (``--determinisation
  most-likely``: the planner's determinisation is the problem's, so a method that asks
  for another one is refused, one line). On the office and STRIPS domains there is
  nothing to determinise.
- *Plan choice among equals*: the lowest column at every step (``plan_action`` of the
  instances and :func:`gdq_pddl.abstraction.prior.first_plan_columns`: the first action
  of a shortest plan, lowest index first). Then the plan from a state continues as the
  plan from its expected successor, so following the plan and replanning on a deviation
  is acting by the plan's first action in every state: :attr:`FFReplan.q` holds
  ``-(1 + d(s'))`` per pair (``s'`` the knowledge's successor, ``d`` its goal distance)
  and the greedy choice takes the lowest column of the best.
- *No plan* (the knowledge reaches no goal from here: a dead end, or wrong knowledge): a
  uniformly random allowed action, a replan after every step until a plan exists.
- *Epsilon* is 0 (its name fixes it): a replanner does not explore.
- The replans are counted (:attr:`FFReplan.replans`: steps whose outcome left the plan
  and did not end the episode).
"""

from __future__ import annotations

from typing import Any, NamedTuple

import numba
import numpy as np

from gdq_pddl.errors import ConfigError
from gdq_pddl.learners.config import FFReplanConfig
from gdq_pddl.learners.context import TaskContext
from gdq_pddl.learners.shaping import goal_distances
from gdq_pddl.learners.tables import KIND_QLEARNING, Model, Params, Prior, QTable, draw_guided
from gdq_pddl.learners.tabular import TabularLearner

__all__ = ["FFReplan", "FFReplanConfig", "NO_PLAN", "Expectation", "act", "observe"]

NO_PLAN = 1e9
"""The distance :attr:`FFReplan.q` gives a successor the knowledge reaches no goal from
(so a state with no plan has every column at ``-(1 + NO_PLAN)``)."""


class Expectation(NamedTuple):
    """FF-Replan's own group (:attr:`~gdq_pddl.learners.tables.Tables.own`)."""

    expected: np.ndarray  # int64[S, A]: the state the plan expects after (s, a)
    replans: np.ndarray  # int64[1]: steps whose outcome left the plan (episode going on)
    SPEC = {"expected": (np.dtype(np.int64), "S A", (0, "S")),
            "replans": (np.dtype(np.int64), "1", None)}


@numba.njit(cache=True)
def act(table: QTable, visits: np.ndarray, prior: Prior, p: Params, s: int,
        rng: np.random.Generator) -> int:
    """The plan's next action: the lowest allowed column of maximal ``q`` (a shortest
    plan's first action); where there is no plan, a uniformly random allowed one."""
    q, allowed = table.q, table.allowed
    best = table.v[s]
    if best <= -(1.0 + NO_PLAN):
        return draw_guided(table, s, rng)
    for a in range(q.shape[1]):
        if allowed[s, a] and q[s, a] == best:
            return a
    return 0


@numba.njit(cache=True)
def observe(table: QTable, model: Model, plans: Any, prior: Any, queue: Any,
            own: Expectation, p: Params, s: int, a: int, r: float, s2: int,
            terminated: bool, truncated: bool, rng: np.random.Generator) -> bool:
    """Learns nothing; counts a replan where the outcome is not the expected state and the
    episode goes on. Always True."""
    if not (terminated or truncated) and s2 != own.expected[s, a]:
        own.replans[0] += 1
    return True


class ReplanRules(NamedTuple):
    """FF-Replan's rules class (:mod:`gdq_pddl.learners.rules`): :func:`act`,
    :func:`observe`."""

    act = act
    observe = observe


class FFReplan(TabularLearner):
    """Acts by a shortest plan of the knowledge, replanning when an outcome leaves it."""

    kind = KIND_QLEARNING  # no learned model
    config: FFReplanConfig
    config_type = FFReplanConfig
    act_rule = staticmethod(act)
    observe_rule = staticmethod(observe)
    loop_rules = ReplanRules

    def _expected(self, context: TaskContext) -> np.ndarray:
        """int64[S, A]: the knowledge's successor of each pair (the state itself where it
        does nothing or the prior is absent)."""
        n_s, n_a = context.n_states, context.n_actions
        here = np.repeat(np.arange(n_s, dtype=np.int64)[:, None], n_a, axis=1)
        if context.prior is None:
            return here
        nxt = np.asarray(context.prior.next_state, dtype=np.int64)
        return np.where(nxt >= 0, nxt, here)

    def _own_arrays(self, context: TaskContext) -> Expectation:
        wanted = context.determinisation
        if wanted is not None and wanted != self.config.determinisation:
            raise ConfigError(f"FF-Replan:determinisation={self.config.determinisation} "
                              f"plans on knowledge read that way, and this problem's is "
                              f"{wanted} (give --determinisation "
                              f"{self.config.determinisation})")
        return Expectation(np.ascontiguousarray(self._expected(context)),
                           np.zeros(1, dtype=np.int64))

    def _plan_values(self) -> None:
        """``q[s, a] = -(1 + d(expected successor))``, :data:`NO_PLAN` where there is no
        plan; ``v`` its max."""
        d = goal_distances(self.context).astype(np.float64)
        d[np.asarray(self.context.plans.length) < 0] = NO_PLAN
        t = self.tables.table
        t.q[:] = np.where(t.allowed, -(1.0 + d[self.tables.own.expected]), 0.0)
        super()._revalue_rows(np.arange(len(t.q)))

    def _init_task(self) -> None:
        self._plan_values()

    def _revalue_rows(self, rows: np.ndarray) -> None:
        self.tables.own.expected[rows] = self._expected(self.context)[rows]
        self._plan_values()

    def prior_changed(self, rows: np.ndarray) -> None:
        """The knowledge's successors of some rows changed (online): plan again."""
        self._revalue_rows(rows)

    @property
    def replans(self) -> int:
        """Steps so far whose outcome left the plan while the episode went on."""
        return int(self.tables.own.replans[0])

    def plan(self, s: int, limit: int | None = None) -> list[int]:
        """The plan FF-Replan follows from learner state ``s`` if every outcome is the
        expected one: its env actions, until a goal (or no plan, or ``limit`` actions:
        the number of states by default)."""
        t, own = self.tables.table, self.tables.own
        out: list[int] = []
        for _ in range(len(t.q) if limit is None else limit):
            if t.goal[s] or t.v[s] <= -(1.0 + NO_PLAN):
                break
            column = int(np.flatnonzero(t.allowed[s] & (t.q[s] == t.v[s]))[0])
            out.append(self.context.action_of(s, column))
            s = int(own.expected[s, column])
        return out
