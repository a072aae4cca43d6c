"""``R-max`` and ``R-max-shaping``: optimism in the face of the unknown, as a model.

Sources: Brafman and Tennenholtz, "R-MAX - a general polynomial time algorithm for
near-optimal reinforcement learning", JMLR 2002 (R-max); Asmuth, Littman and Zinkov,
"Potential-based shaping in model-based reinforcement learning", AAAI 2008 (an unknown
pair valued by a potential instead of ``R_max / (1 - gamma)``). The rule, in three lines::

    record (s, a, r, s'); (s, a) is known once tried m times
    Q(s, a) = sum_s' T(s'|s,a) [r(s,a,s') + gamma V(s')] if known, else U(s)
    after each newly known pair: value iteration on that model; act greedily

``U(s)`` is ``V_max`` for R-max and ``Phi(s)`` for R-max-shaping.

Choices the sources leave open (``docs/decisions.md``, "R-max baselines"):

- *m and the known-pair test*: a pair is known when its trials reach ``m`` (``visits >=
  m``, Brafman and Tennenholtz's "visited m times"), ``m`` 1 by default (the best of 1,
  2 and 5 on tasks A-D; a setting, ``R-max:m=3``). The model goes on counting after that (the
  learned model is shared with Dyna-Q and GDQ), but values are planned again only when a
  pair becomes known, as R-max plans.
- *V_max, the goal-scale R_max/(1-gamma)*: an episode's return here is at most
  ``r_max`` (the goal's reward, which ends it; every other step costs). So an unknown
  pair is worth ``V_max = r_max``: the most any policy could get from it. On a problem's
  own reward scale (an IPPC file's rewards) a step may pay, so ``V_max = r_max +
  max(0, largest reward of a step) / (1 - gamma)``.
- *R-max-shaping's potential*: Asmuth et al. need a value-scale ``Phi(s) >= V*(s)``
  (admissible). From the knowledge's distance ``d(s)`` (:func:`~gdq_pddl.learners.shaping.
  goal_distances`): ``Phi(s) = V_max - scale * max(0, d(s) - 1)``, i.e. ``V_max`` plus
  the distance potential ``-scale * d`` with the goal step free; ``scale`` 2 by default
  (the better of 1 and 2 on tasks A-D, with ``m`` 1). At ``scale`` 1 (the step cost) it
  is admissible where the knowledge's distance is a lower bound on
  the true one and within a few tens of steps of the goal (``docs/decisions.md`` has the
  bound); at the default 2 only within about 3 actions of the goal, so the default
  trades Asmuth et al.'s guarantee for what was measured; wrong knowledge (a missing
  action) can make any scale inadmissible, the case Asmuth et al. warn about. A state
  the knowledge reaches no goal from has ``d`` = the step limit.
- *Planning*: Gauss-Seidel value iteration over every state and allowed pair, from the
  current values, until no value changes by more than ``tolerance`` or ``max_sweeps``
  sweeps (Brafman and Tennenholtz solve the model exactly; this is that to a tolerance).
  It visits only the states with a known pair, the others being no-ops once a sweep has
  visited them (every state in the first sweep after the tables changed outside
  planning): the same values to the bit, at the known part's cost.
- *Acting*: greedy, ties broken uniformly at random (``epsilon`` is 0: R-max explores
  by optimism alone).
- *Terminal outcomes*: as every learned model here (:mod:`~gdq_pddl.learners.
  learned_model`): the goal pays ``r_max`` and ends, getting stuck pays ``-r_max`` and
  ends, a timeout is an ordinary transition.
"""

from __future__ import annotations

from typing import Any, NamedTuple

import numba
import numpy as np

from gdq_pddl.learners.config import RMaxConfig, RMaxShapingConfig
from gdq_pddl.learners.context import TaskContext
from gdq_pddl.learners.learned_model import learned_value, record
from gdq_pddl.learners.shaping import goal_distances
from gdq_pddl.learners.tables import KIND_DYNAQ, Model, Params, QTable, act_plain
from gdq_pddl.learners.tabular import TabularLearner

__all__ = ["Optimism", "RMax", "RMaxConfig", "RMaxShaping", "RMaxShapingConfig",
           "now_known", "plan_known", "v_max"]


class Optimism(NamedTuple):
    """R-max's own group (:attr:`~gdq_pddl.learners.tables.Tables.own`)."""

    unknown: np.ndarray  # float64[S]: U(s), the value of an unknown pair of state s
    sweeps: np.ndarray  # int64[1]: value-iteration sweeps run so far
    known_states: np.ndarray  # int64[S]: its first ``planned[0]``: the states with a known
    # pair, ascending (those the sweeps after the first visit)
    planned: np.ndarray  # int64[2]: how many known_states; 1 while every other state is
    # as planning leaves it (its pairs at U(s), its value their maximum), else 0
    SPEC = {"unknown": (np.dtype(np.float64), "S", None),
            "sweeps": (np.dtype(np.int64), "1", None),
            "known_states": (np.dtype(np.int64), "S", None),
            "planned": (np.dtype(np.int64), "2", None)}


@numba.njit(cache=True)
def plan_known(table: QTable, model: Model, own: Optimism, p: Params, tolerance: float,
               max_sweeps: int) -> int:
    """Gauss-Seidel value iteration on the known model: every allowed pair of every
    non-goal state gets its known value, or ``own.unknown[s]``; until the largest change
    is at most ``tolerance`` or after ``max_sweeps`` sweeps. Returns the sweeps run.
    (``p.m`` is one less than R-max's m: known means ``visits > p.m``.)

    A state without a known pair is a no-op once a sweep has visited it (its pairs are
    ``own.unknown[s]``, which planning does not change, and its value their maximum). So
    the first sweep visits every state only when ``own.planned[1]`` is 0 (whatever
    changed the tables outside planning sets it so: a task, new rows, new ``U``), and
    every sweep else visits only ``own.known_states``, in the same order: the values,
    the changes and the sweeps are those of visiting every state each sweep, to the bit
    (``tests/learners/test_baselines.py``), at the cost of the known part of the model."""
    q, v, allowed, goal = table.q, table.v, table.allowed, table.goal
    n_states, n_actions = q.shape
    known_states = own.known_states
    full = own.planned[1] == 0
    n_visit = n_states if full else own.planned[0]
    done = 0
    for _ in range(max_sweeps):
        first = done == 0
        done += 1
        change = 0.0
        found = 0
        for i in range(n_visit):
            s = i if full else known_states[i]
            if goal[s]:
                continue
            best = -np.inf
            known = False
            for a in range(n_actions):
                if not allowed[s, a]:
                    continue
                if model.visits[s, a] > p.m:
                    known = True
                    x = learned_value(model.slots, model.stuck, model.visits, model.cost_sum,
                                      model.cost_n, model.cost_all, goal, v, p, s, a)
                else:
                    x = own.unknown[s]
                change = max(change, abs(x - q[s, a]))
                q[s, a] = x
                best = max(best, x)
            v[s] = best
            if full and known:
                known_states[found] = s
                found += 1
        if first and full:
            full = False
            n_visit = found
            own.planned[0] = found
            own.planned[1] = 1
        if change <= tolerance:
            break
    own.sweeps[0] += done
    return done


@numba.njit(cache=True)
def now_known(own: Optimism, s: int) -> None:
    """State ``s`` has a known pair: into ``own.known_states`` (ascending) if planning
    keeps that list (``own.planned[1]``; else the next plan makes it)."""
    if own.planned[1] == 0:
        return
    n = own.planned[0]
    lo, hi = 0, n
    while lo < hi:  # the first place holding a state >= s
        mid = (lo + hi) // 2
        if own.known_states[mid] < s:
            lo = mid + 1
        else:
            hi = mid
    if lo < n and own.known_states[lo] == s:
        return
    for i in range(n, lo, -1):
        own.known_states[i] = own.known_states[i - 1]
    own.known_states[lo] = s
    own.planned[0] = n + 1


@numba.njit(cache=True)
def observe(table: QTable, model: Model, plans: Any, prior: Any, queue: Any, own: Optimism,
            p: Params, s: int, a: int, r: float, s2: int, terminated: bool, truncated: bool,
            rng: np.random.Generator) -> bool:
    """After a real step: record it; if ``(s, a)`` just became known, plan
    (:func:`plan_known`, tolerance ``p.sweep_threshold``, at most ``p.n_backups``
    sweeps). False when the model had no slot for the transition."""
    if not record(model, table.goal, p, s, a, r, s2, terminated, truncated):
        return False
    if model.visits[s, a] == p.m + 1:
        now_known(own, s)
        plan_known(table, model, own, p, p.sweep_threshold, p.n_backups)
    return True


def v_max(context: TaskContext, gamma: float) -> float:
    """The goal-scale ``R_max / (1 - gamma)``: ``r_max``, the most an episode can pay; on a
    problem's own scale, plus what paying steps could add forever (module doc)."""
    top = float(context.r_max)
    if context.own_scale and context.prior_reward is not None and context.prior_reward.size:
        top += max(0.0, float(context.prior_reward.max())) / (1.0 - gamma)
    return top


class RMaxRules(NamedTuple):
    """R-max's rules class (:mod:`gdq_pddl.learners.rules`): epsilon-greedy (its epsilon
    is 0), :func:`observe`."""

    act = act_plain
    observe = observe


class RMax(TabularLearner):
    """R-max: unknown pairs worth ``V_max``, value iteration on the known model after each
    newly known pair, greedy acting."""

    kind = KIND_DYNAQ  # the arrays of a learner with a learned model
    config: RMaxConfig
    config_type = RMaxConfig
    reads_knowledge = False
    observe_rule = staticmethod(observe)
    loop_rules = RMaxRules

    def _unknown(self, context: TaskContext) -> np.ndarray:
        """U(s) per learner state."""
        return np.full(context.n_states, v_max(context, self.config.gamma))

    def _own_arrays(self, context: TaskContext) -> Optimism:
        return Optimism(np.ascontiguousarray(self._unknown(context), dtype=np.float64),
                        np.zeros(1, dtype=np.int64),
                        np.zeros(context.n_states, dtype=np.int64), np.zeros(2, dtype=np.int64))

    def _build(self, context: TaskContext) -> Any:
        tables, params = super()._build(context)
        c = self.config  # R-max's m is "tried m times": the model's test is visits > m
        return tables, params._replace(m=c.m - 1, n_backups=c.max_sweeps,
                                       sweep_threshold=c.tolerance)

    def _init_task(self) -> None:
        """Every pair's value from the model as it stands (all unknown at first)."""
        t = self.tables
        self._revalue_rows(np.arange(len(self.q)))
        plan_known(t.table, t.model, t.own, self.params, self.config.tolerance,
                   self.config.max_sweeps)

    def _revalue_rows(self, rows: np.ndarray) -> None:
        self.tables.own.planned[1] = 0  # rows changed outside planning: a full sweep next
        t = self.tables.table
        t.q[rows] = np.where(t.allowed[rows], self.tables.own.unknown[rows, None], 0.0)
        super()._revalue_rows(rows)

    def update_rows(self, rows: np.ndarray) -> None:
        """As the base class, with ``U`` again for the rows' distances first."""
        self.tables.own.unknown[:] = self._unknown(self.context)
        self.tables.own.planned[1] = 0  # every state's U may have changed
        super().update_rows(rows)

    @property
    def sweeps(self) -> int:
        """Value-iteration sweeps run so far."""
        return int(self.tables.own.sweeps[0])


class RMaxShaping(RMax):
    """R-max whose unknown pairs are worth ``Phi(s) = V_max - scale * max(0, d(s) - 1)``."""

    config: RMaxShapingConfig
    config_type = RMaxShapingConfig
    reads_knowledge = True

    def _unknown(self, context: TaskContext) -> np.ndarray:
        d = goal_distances(context)
        top = v_max(context, self.config.gamma)
        return top - self.config.scale * np.maximum(0, d - 1).astype(np.float64)
