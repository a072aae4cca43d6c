"""Learning on a problem explored online (:mod:`gdq_pddl.envs.online`).

The env adds rows as its episodes reach new states; :class:`Follower` keeps a learner's
tables in step after every real step, before the learner sees it: rows changed in place
are remade (:meth:`~gdq_pddl.learners.tabular.TabularLearner.update_rows`), and when the
instance's arrays were reallocated the learner takes the new context, keeping what it
learned (:meth:`~gdq_pddl.learners.tabular.TabularLearner.resize`). After an episode,
GDQ indexes the prior's new pairs for its sweeps.
"""

from __future__ import annotations

import numpy as np

from gdq_pddl.envs.online import OnlineInstance
from gdq_pddl.learners.context import TaskContext, task_context
from gdq_pddl.learners.tabular import TabularLearner


def online_context(instance: OnlineInstance, planner: str = "graph") -> TaskContext:
    """The learners' context of ``instance`` as its arrays stand (they change in place as
    states are found; a reallocation needs a new context)."""
    return task_context(instance, planner, instance.darling_tolerance)


class Follower:
    """Keeps ``learner`` in step with ``instance``: call it after every real step, and
    :meth:`episode_end` after every episode."""

    def __init__(self, learner: TabularLearner, instance: OnlineInstance,
                 planner: str = "graph") -> None:
        self.learner, self.instance, self.planner = learner, instance, planner
        self.revision, self.cursor = instance.revision, len(instance.log)
        if learner.q.shape != instance.columns.shape:
            self._resize()  # rows found since the learner's context was made
        self.changed = False

    def __call__(self) -> None:
        inst = self.instance
        if inst.revision != self.revision:
            self._resize()
        elif self.cursor < len(inst.log):
            rows = np.array(inst.log[self.cursor:], dtype=np.int64)
            self.cursor = len(inst.log)
            self.learner.update_rows(rows)
            self.changed = True

    def _resize(self) -> None:
        inst = self.instance
        self.learner.resize(online_context(inst, self.planner))
        self.revision, self.cursor = inst.revision, len(inst.log)

    def episode_end(self) -> None:
        refresh = getattr(self.learner, "refresh_predecessors", None)
        if self.changed and refresh is not None:
            refresh()
        self.changed = False
