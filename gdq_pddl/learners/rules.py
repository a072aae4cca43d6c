"""What a learner does after one real step: :func:`observe`, the one place that says
which rule of which module runs for which learner.

=============  ===========================================================================
learner        after a real step ``(s, a, r, s2)``
=============  ===========================================================================
Q-learning     the TD update (:func:`gdq_pddl.learners.tables.td_update`)
DARLING        the same (its restriction is in ``allowed`` and ``guide``)
Dyna-Q         TD update, record the step in the learned model, N backups of random known
               pairs (:mod:`gdq_pddl.learners.learned_model`)
GDQ-literal,   TD update, record, N backups along the plans from ``s``
GDQ-code       (:func:`gdq_pddl.learners.gdq_paper.backup_plans`; Dyna-Q's where ``s``
               has no plan)
GDQ            record, the hybrid backup of the pair, prioritised sweep; no TD update
               (:func:`gdq_pddl.learners.gdq.after_step`)
=============  ===========================================================================

The learners' methods (:mod:`gdq_pddl.learners.agents`) and the compiled episode loop
(:mod:`gdq_pddl.learners.episodes`) both call :func:`observe` and
:func:`gdq_pddl.learners.tables.act`, so each rule has one definition and the two loops
give the same bits (tested).
"""

from __future__ import annotations

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
def observe(table: QTable, model: Model, plans: Plans, prior: Prior, queue: Queue, p: Params,
            s: int, a: int, r: float, s2: int, terminated: bool, truncated: bool,
            rng: np.random.Generator) -> bool:
    """Everything a learner does after one real step ``(s, a, r, s2)`` (module table).

    The TD update's target is ``r`` alone for a terminated or truncated step. False when
    the learned model had no slot for the transition (no backups then): the callers
    raise ValueError(:data:`gdq_pddl.learners.learned_model.OVERFLOW`).
    """
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
