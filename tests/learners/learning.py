"""What the learner tests share (``test_optinit``, ``test_learned_model``,
``test_learners``): the office world and its variant without slips,
and a learner's expected backup of one pair on its own tables."""

from __future__ import annotations

from gdq_pddl.envs.variants import deterministic_world
from gdq_pddl.learners import learned_model
from gdq_pddl.world import load_world

WORLD = load_world()
DET = deterministic_world(WORLD)


def expected_backup(t, p, s, a, v):
    """learned_model.expected_value of ``(s, a)`` on a learner's tables."""
    return learned_model.expected_value(t.model, t.table.goal, t.plans.opt_r, p, s, a, v)
