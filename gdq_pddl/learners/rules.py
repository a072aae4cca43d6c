"""What a learner does after one real step: one compiled function per kind of learner
(:func:`observe_td`, :func:`observe_dyna`, :func:`observe_plans`, :func:`observe_gdq`),
and each kind's *rules class* (:data:`KIND_RULES`: its acting rule and this one;
``docs/learners.md`` has them as a table). A learner's ``act_rule`` and ``observe_rule``
are its kind's, which its methods call; the compiled episode loop has a copy per rules
class calling the same two functions, so each rule has one definition, the two loops
give the same bits (tested), and a loop holds the code of one kind only.
"""

from __future__ import annotations

from typing import Any, NamedTuple

import numba
import numpy as np

from gdq_pddl.learners.gdq import act as act_gdq
from gdq_pddl.learners.gdq import after_step
from gdq_pddl.learners.gdq_paper import backup_plans
from gdq_pddl.learners.learned_model import backup_known, record
from gdq_pddl.learners.tables import (
    KIND_DARLING,
    KIND_DYNAQ,
    KIND_GDQ,
    KIND_GDQ_PLANS,
    KIND_QLEARNING,
    Model,
    Params,
    Plans,
    Prior,
    QTable,
    Queue,
    act_plain,
    td_update,
)


@numba.njit(cache=True, inline="always")
def _td(table: QTable, p: Params, s: int, a: int, r: float, s2: int, terminated: bool,
        truncated: bool) -> None:
    """The TD update of a real step (target ``r`` alone at the end of an episode)."""
    target = r if (terminated or truncated) else r + p.gamma * table.v[s2]
    td_update(table, s, a, target, p.alpha)


@numba.njit(cache=True)
def observe_td(table: QTable, model: Model, plans: Plans, prior: Prior, queue: Queue,
               own: Any, p: Params, s: int, a: int, r: float, s2: int, terminated: bool,
               truncated: bool, rng: np.random.Generator) -> bool:
    """Q-learning and DARLING: the TD update. Always True."""
    _td(table, p, s, a, r, s2, terminated, truncated)
    return True


@numba.njit(cache=True)
def observe_dyna(table: QTable, model: Model, plans: Plans, prior: Prior, queue: Queue,
                 own: Any, p: Params, s: int, a: int, r: float, s2: int, terminated: bool,
                 truncated: bool, rng: np.random.Generator) -> bool:
    """Dyna-Q: the TD update, the step recorded, N backups of random known pairs. False
    when the learned model had no slot for the transition (no backups then)."""
    _td(table, p, s, a, r, s2, terminated, truncated)
    if not record(model, table.goal, p, s, a, r, s2, terminated, truncated):
        return False
    backup_known(table, model, plans.opt_r, p, rng)
    return True


@numba.njit(cache=True)
def observe_plans(table: QTable, model: Model, plans: Plans, prior: Prior, queue: Queue,
                  own: Any, p: Params, s: int, a: int, r: float, s2: int, terminated: bool,
                  truncated: bool, rng: np.random.Generator) -> bool:
    """GDQ-literal and GDQ-code: the TD update, the step recorded, N backups along the
    plans from ``s`` (Dyna-Q's where ``s`` has none). False as :func:`observe_dyna`."""
    _td(table, p, s, a, r, s2, terminated, truncated)
    if not record(model, table.goal, p, s, a, r, s2, terminated, truncated):
        return False
    if backup_plans(table, model, plans, p, s, rng):
        return True
    backup_known(table, model, plans.opt_r, p, rng)
    return True


@numba.njit(cache=True)
def observe_gdq(table: QTable, model: Model, plans: Plans, prior: Prior, queue: Queue,
                own: Any, p: Params, s: int, a: int, r: float, s2: int, terminated: bool,
                truncated: bool, rng: np.random.Generator) -> bool:
    """The default GDQ: the step recorded, its hybrid backup, prioritised sweeping (no TD
    update; :func:`gdq_pddl.learners.gdq.after_step`). False as :func:`observe_dyna`."""
    return after_step(table, model, prior, queue, p, s, a, r, s2, terminated, truncated)


class TDRules(NamedTuple):
    """Q-learning's and DARLING's rules: plain epsilon-greedy, the TD update. A rules class
    is a NamedTuple without fields whose ``act`` and ``observe`` are a learner's two rules:
    the compiled episode loop has one copy per rules class calling them
    (:func:`gdq_pddl.learners.episodes._loop_of`), so a loop holds one learner's code and
    numba caches it under the class's name."""

    act = act_plain
    observe = observe_td


class DynaRules(NamedTuple):
    """Dyna-Q's rules: plain epsilon-greedy, :func:`observe_dyna`."""

    act = act_plain
    observe = observe_dyna


class PlanRules(NamedTuple):
    """The paper's GDQs' rules (GDQ-literal, GDQ-code): plain epsilon-greedy,
    :func:`observe_plans`."""

    act = act_plain
    observe = observe_plans


class GDQRules(NamedTuple):
    """The default GDQ's rules: its own exploring (:func:`gdq_pddl.learners.gdq.act`),
    :func:`observe_gdq`."""

    act = act_gdq
    observe = observe_gdq


KIND_RULES = {KIND_QLEARNING: TDRules, KIND_DARLING: TDRules, KIND_DYNAQ: DynaRules,
              KIND_GDQ_PLANS: PlanRules, KIND_GDQ: GDQRules}
"""Each kind's rules class: its ``act`` and ``observe`` are a learner's ``act_rule`` and
``observe_rule``."""
