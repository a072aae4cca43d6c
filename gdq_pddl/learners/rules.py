"""What a learner does after one real step: :func:`observe`, the one place that says
which rule of which module runs for which learner (``docs/learners.md`` has it as a
table). The learners' methods and the compiled episode loop both call it, so each rule
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


@numba.njit(cache=True)
def observe(table: QTable, model: Model, plans: Plans, prior: Prior, queue: Queue, own: Any,
            p: Params, s: int, a: int, r: float, s2: int, terminated: bool, truncated: bool,
            rng: np.random.Generator) -> bool:
    """Everything a learner does after one real step ``(s, a, r, s2)`` (``own``: the
    learner's own arrays, :attr:`~gdq_pddl.learners.tables.Tables.own`, which the
    built-in learners here have none of). False when the
    learned model had no slot for the transition (no backups then): the callers raise
    ValueError(:data:`gdq_pddl.learners.learned_model.OVERFLOW`)."""
    if p.kind == KIND_GDQ:
        return after_step(table, model, prior, queue, p, s, a, r, s2, terminated, truncated)
    target = r if (terminated or truncated) else r + p.gamma * table.v[s2]
    td_update(table, s, a, target, p.alpha)
    if p.kind == KIND_QLEARNING or p.kind == KIND_DARLING:
        return True
    if not record(model, table.goal, p, s, a, r, s2, terminated, truncated):
        return False
    if p.kind == KIND_GDQ_PLANS and backup_plans(table, model, plans, p, s, rng):
        return True
    backup_known(table, model, plans.opt_r, p, rng)
    return True
