"""Learning on a problem explored online (:mod:`gdq_pddl.envs.online`).

The env adds rows as its episodes reach new states; :class:`Follower` keeps a learner's
tables in step after every real step, before the learner sees it: new rows are made
(:meth:`~gdq_pddl.learners.tabular.TabularLearner.update_rows`), rows whose prior
successor now has its own row are revalued
(:meth:`~gdq_pddl.learners.tabular.TabularLearner.prior_changed`), and when the
instance's arrays were reallocated the learner takes the new context, keeping what it
learned (:meth:`~gdq_pddl.learners.tabular.TabularLearner.resize`). After an episode,
GDQ indexes the prior's new pairs for its sweeps and revalues the episode's rows.
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
        self.retargeted = len(instance.retargeted)
        if learner.q.shape != instance.columns.shape:
            self._resize()  # rows found since the learner's context was made
        self.touched: set[int] = set()

    def __call__(self) -> None:
        inst = self.instance
        if inst.revision != self.revision:
            self._resize()
            return
        if self.cursor < len(inst.log):
            rows = np.array(inst.log[self.cursor:], dtype=np.int64)
            self.cursor = len(inst.log)
            self.learner.update_rows(rows)
            self.touched.update(rows.tolist())
        if self.retargeted < len(inst.retargeted):
            rows = np.unique(np.array(inst.retargeted[self.retargeted:], dtype=np.int64))
            self.retargeted = len(inst.retargeted)
            self.learner.prior_changed(rows)
            self.touched.update(rows.tolist())

    def _resize(self) -> None:
        inst = self.instance
        self.learner.resize(online_context(inst, self.planner))
        self.revision, self.cursor = inst.revision, len(inst.log)
        self.retargeted = len(inst.retargeted)

    def episode_end(self) -> None:
        """GDQ's index of prior predecessors made again with the episode's new pairs, and
        the rows made or changed during the episode revalued: within it, sweeps could
        not reach their pairs from the states they lead to."""
        refresh = getattr(self.learner, "refresh_predecessors", None)
        if self.touched and refresh is not None:
            refresh()
            self.learner.prior_changed(np.array(sorted(self.touched), dtype=np.int64))
        self.touched = set()
