"""What a learner does after one real step: one compiled function per kind of learner
(:func:`observe_td`, :func:`observe_dyna`, :func:`observe_plans`, :func:`observe_gdq`),
and :func:`observe`, which picks among them by ``kind`` (``docs/learners.md`` has it as a
table). A learner's ``observe_rule`` is its kind's function, which its methods call; the
compiled episode loop calls :func:`observe`, which picks the same function, so each rule
has one definition and the two loops give the same bits (tested).
"""

from __future__ import annotations

from typing import Any

import numba
import numpy as np

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


RULES = {KIND_QLEARNING: observe_td, KIND_DARLING: observe_td, KIND_DYNAQ: observe_dyna,
         KIND_GDQ_PLANS: observe_plans, KIND_GDQ: observe_gdq}
"""Each kind's rule after a real step (a learner's ``observe_rule``)."""


@numba.njit(cache=True)
def observe(table: QTable, model: Model, plans: Plans, prior: Prior, queue: Queue, own: Any,
            p: Params, s: int, a: int, r: float, s2: int, terminated: bool, truncated: bool,
            rng: np.random.Generator) -> bool:
    """Everything a learner of any kind does after one real step ``(s, a, r, s2)`` (its
    kind's rule, :data:`RULES`; ``own``: the learner's own arrays,
    :attr:`~gdq_pddl.learners.tables.Tables.own`, which these kinds have none of). False
    when the learned model had no slot for the transition (no backups then): the callers
    raise
    ValueError(:data:`gdq_pddl.learners.learned_model.OVERFLOW`)."""
    if p.kind == KIND_GDQ:
        return observe_gdq(table, model, plans, prior, queue, own, p, s, a, r, s2, terminated,
                           truncated, rng)
    if p.kind == KIND_QLEARNING or p.kind == KIND_DARLING:
        return observe_td(table, model, plans, prior, queue, own, p, s, a, r, s2, terminated,
                          truncated, rng)
    if p.kind == KIND_GDQ_PLANS:
        return observe_plans(table, model, plans, prior, queue, own, p, s, a, r, s2,
                             terminated, truncated, rng)
    return observe_dyna(table, model, plans, prior, queue, own, p, s, a, r, s2, terminated,
                        truncated, rng)
