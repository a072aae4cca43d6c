"""Potential-based reward shaping from the knowledge: ``Q-shaping``, ``Dyna-Q-shaping`` and
``Plan-shaping``, and the potentials R-max-shaping reads (:mod:`gdq_pddl.learners.rmax`).

Sources: Ng, Harada and Russell, "Policy invariance under reward transformations: theory
and application to reward shaping", ICML 1999 (the shaping term); Grzes and Kudenko,
"Plan-based reward shaping for reinforcement learning", IEEE IS 2008 (the plan-step
potential). The rule, in three lines::

    F(s, s') = gamma * phi(s') - phi(s)         (phi(s') = 0 where the episode terminated)
    Q(s, a) += alpha * (r + F(s, s') + gamma * max_a' Q(s', a') - Q(s, a))
    Dyna-Q-shaping: the same F in each simulated backup; the model keeps unshaped rewards

The potentials (the same as :class:`gdq_pddl.wrappers.KnowledgeShaping`'s, so a deep-RL
agent behind that wrapper and these learners are shaped alike), with ``d(s)`` the
knowledge's goal distance (:func:`goal_distances`):

- ``distance`` (Q-shaping, Dyna-Q-shaping): ``phi(s) = -scale * d(s)``;
- ``plan-step`` (Plan-shaping): ``phi(s) = scale * w * max(0, L - d(s))``, ``L = d(s_0)``
  the length of a shortest plan from the task's start, ``w = R_max / L`` (``R_max`` the
  task's ``r_max``, 1 if that is 0): the step of that plan that ``s`` stands at, read
  as the knowledge's distance (a state as far from the goal as the plan's step ``k`` is at
  step ``k``; one farther than the start is at step 0); ``phi = 0`` where ``L`` is 0.

Choices the sources leave open (``docs/decisions.md``, "Shaping baselines"):

- *Scale and sign*: ``phi = -scale * d`` (a state nearer the goal is worth more), a
  setting (``Q-shaping:scale=0.5``): 2 by default for Q-shaping, 1 for Dyna-Q-shaping,
  each the best of those tried on tasks A-D (``docs/decisions.md``). Plan-shaping's
  ``scale`` multiplies Grzes and Kudenko's ``w`` (1, the default: their ``w = R_max /
  L``, also the best tried).
- *Where the knowledge reaches no goal* (a dead end, a state the knowledge cannot solve
  from, or a state of a problem explored online whose estimates reach no goal): ``d`` is
  the env's step limit (no goal within an episode; the number of states where the limit
  is unknown). So such states get the lowest distance potential and plan step 0.
- *Terminal states*: ``phi = 0`` where the episode terminated (the goal, or stuck), Ng et
  al.'s condition for an absorbing state; a truncated episode's last state keeps its
  ``phi`` (there is no bootstrap there, so it only shifts that step's reward).
- *Plan step* by distance rather than by matching the state against the plan's states:
  both agree on the plan's own states; the distance also gives the states of every other
  shortest plan their step, and is what the wrapper uses.
- On a problem explored online ``d`` is the estimates' distance GDQ reads there (the
  context's plan lengths), recomputed when the exploration finds rows.

Over any episode of ``T`` steps the shaping terms sum, discounted, to
``gamma^T phi(s_T) - phi(s_0)`` (``phi(s_T) = 0`` if it terminated): tested.
"""

from __future__ import annotations

from typing import Any, NamedTuple

import numba
import numpy as np

from gdq_pddl.learners.config import DynaQShapingConfig, PlanShapingConfig, ShapingConfig
from gdq_pddl.learners.context import TaskContext
from gdq_pddl.learners.learned_model import learned_value, record, slot_count, slot_successor
from gdq_pddl.learners.tables import (
    KIND_DYNAQ,
    KIND_QLEARNING,
    Model,
    Params,
    QTable,
    act_plain,
    set_q,
    td_update,
)
from gdq_pddl.learners.tabular import TabularLearner

__all__ = ["DynaQShaping", "DynaQShapingConfig", "PlanShaping", "Potential", "QShaping",
           "ShapingConfig", "distance_potential", "goal_distances", "plan_step_potential",
           "shaping_term"]


def goal_distances(context: TaskContext) -> np.ndarray:
    """int64[n_states]: the knowledge's fewest actions from each learner state to the goal
    (the context's shortest plan lengths: 0 at a goal), the env's step limit where the
    knowledge reaches no goal (:attr:`TaskContext.horizon`; the number of states where
    that is None)."""
    d = np.asarray(context.plans.length, dtype=np.int64).copy()
    far = context.horizon if context.horizon is not None else context.n_states
    d[d < 0] = far
    return d


def distance_potential(context: TaskContext, scale: float) -> np.ndarray:
    """float64[n_states]: ``phi(s) = -scale * d(s)`` (module doc)."""
    return -float(scale) * goal_distances(context).astype(np.float64)


def plan_step_potential(context: TaskContext, scale: float) -> np.ndarray:
    """float64[n_states]: ``phi(s) = scale * (R_max / L) * max(0, L - d(s))``, ``L`` the
    distance of the task's start (module doc); zeros where ``L`` is 0."""
    d = goal_distances(context)
    length = int(d[context.s0])
    if length <= 0:
        return np.zeros(len(d))
    w = (float(context.r_max) or 1.0) / length
    return float(scale) * w * np.maximum(0, length - d).astype(np.float64)


class Potential(NamedTuple):
    """The shaping learners' own group (:attr:`~gdq_pddl.learners.tables.Tables.own`)."""

    phi: np.ndarray  # float64[S]: the potential of each learner state (not terminal)
    SPEC = {"phi": (np.dtype(np.float64), "S", None)}


@numba.njit(cache=True, inline="always")
def shaping_term(phi: np.ndarray, gamma: float, s: int, s2: int, terminated: bool) -> float:
    """``F = gamma * phi(s2) - phi(s)``, with ``phi(s2) = 0`` where the episode terminated."""
    return (0.0 if terminated else gamma * phi[s2]) - phi[s]


@numba.njit(cache=True)
def observe_q(table: QTable, model: Model, plans: Any, prior: Any, queue: Any, own: Potential,
              p: Params, s: int, a: int, r: float, s2: int, terminated: bool, truncated: bool,
              rng: np.random.Generator) -> bool:
    """Q-shaping (and Plan-shaping) after a real step: the TD update on the shaped reward
    ``r + F`` (no bootstrap at an episode's end). Always True."""
    shaped = r + shaping_term(own.phi, p.gamma, s, s2, terminated)
    target = shaped if (terminated or truncated) else shaped + p.gamma * table.v[s2]
    td_update(table, s, a, target, p.alpha)
    return True


@numba.njit(cache=True, inline="always")
def shaped_value(table: QTable, model: Model, phi: np.ndarray, p: Params, s: int,
                 a: int) -> float:
    """The expected backup of a known pair under the learned model (unshaped rewards,
    :func:`~gdq_pddl.learners.learned_model.learned_value`) plus the expected shaping
    term: ``sum_s' T(s'|s,a) gamma phi(s')`` over the successors that do not end the
    episode (the goal's and stuck trials' ``phi`` is 0), less ``phi(s)``."""
    value = learned_value(model.slots, model.stuck, model.visits, model.cost_sum,
                          model.cost_n, model.cost_all, table.goal, table.v, p, s, a)
    slots = model.slots
    ahead = 0.0
    for j in range(slots.shape[2]):
        here = slots[s, a, j]
        if here == 0:
            break
        s2 = slot_successor(here)
        if not table.goal[s2]:
            ahead += slot_count(here) * p.gamma * phi[s2]
    return value + ahead / model.visits[s, a] - phi[s]


@numba.njit(cache=True)
def observe_dyna(table: QTable, model: Model, plans: Any, prior: Any, queue: Any,
                 own: Potential, p: Params, s: int, a: int, r: float, s2: int,
                 terminated: bool, truncated: bool, rng: np.random.Generator) -> bool:
    """Dyna-Q-shaping after a real step: the shaped TD update, the unshaped reward recorded
    in the model, then ``n_backups`` shaped expected backups (:func:`shaped_value`) of
    uniformly random known pairs, drawn as Dyna-Q draws them. False when the model had no
    slot for the transition."""
    shaped = r + shaping_term(own.phi, p.gamma, s, s2, terminated)
    target = shaped if (terminated or truncated) else shaped + p.gamma * table.v[s2]
    td_update(table, s, a, target, p.alpha)
    if not record(model, table.goal, p, s, a, r, s2, terminated, truncated):
        return False
    nk = model.n_known[0]
    if nk == 0:
        return True
    n_actions = model.visits.shape[1]
    for _ in range(p.n_backups):
        i = model.known[rng.integers(0, nk)]
        x, b = i // n_actions, i % n_actions
        set_q(table, x, b, shaped_value(table, model, own.phi, p, x, b))
    return True


class QShapingRules(NamedTuple):
    """Q-shaping's and Plan-shaping's rules class (:mod:`gdq_pddl.learners.rules`): plain
    epsilon-greedy, :func:`observe_q`."""

    act = act_plain
    observe = observe_q


class DynaShapingRules(NamedTuple):
    """Dyna-Q-shaping's rules class: plain epsilon-greedy, :func:`observe_dyna`."""

    act = act_plain
    observe = observe_dyna


class _Shaped(TabularLearner):
    """A learner whose rule reads a potential of the knowledge in its own group."""

    config: ShapingConfig

    def _potential(self, context: TaskContext) -> np.ndarray:
        return distance_potential(context, self.config.scale)

    def _own_arrays(self, context: TaskContext) -> Potential:
        return Potential(np.ascontiguousarray(self._potential(context), dtype=np.float64))

    def update_rows(self, rows: np.ndarray) -> None:
        """As the base class; then the potential again (the rows' distances changed)."""
        super().update_rows(rows)
        self.tables.own.phi[:] = self._potential(self.context)

    @property
    def phi(self) -> np.ndarray:
        """float64[n_states]: the potential of each learner state (before termination)."""
        return self.tables.own.phi


class QShaping(_Shaped):
    """Q-learning on ``r + gamma phi(s') - phi(s)``, ``phi = -scale * d(s)``."""

    kind = KIND_QLEARNING
    config_type = ShapingConfig
    observe_rule = staticmethod(observe_q)
    loop_rules = QShapingRules


class PlanShaping(_Shaped):
    """Q-learning shaped by Grzes and Kudenko's plan-step potential."""

    kind = KIND_QLEARNING
    config_type = PlanShapingConfig
    observe_rule = staticmethod(observe_q)
    loop_rules = QShapingRules

    def _potential(self, context: TaskContext) -> np.ndarray:
        return plan_step_potential(context, self.config.scale)


class DynaQShaping(_Shaped):
    """Dyna-Q whose real and simulated backups add ``gamma phi(s') - phi(s)``."""

    kind = KIND_DYNAQ
    config_type = DynaQShapingConfig
    observe_rule = staticmethod(observe_dyna)
    loop_rules = DynaShapingRules
