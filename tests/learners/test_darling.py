"""DARLING's restriction to plan actions: the paper's (it explores and maximises over
the allowed set only) and the authors' code (it executes plan actions, maximises and
bootstraps over all), and no restriction where there is no plan."""

from __future__ import annotations

from dataclasses import replace

import numpy as np
import pytest

from gdq_pddl.envs.office import OfficeEnv
from gdq_pddl.learners import (
    Darling,
    DarlingConfig,
    empty_plan_table,
    tables,
)
from tests.helpers import Recording, run

# --- DARLING ------------------------------------------------------------------------------

def test_darling_never_leaves_its_allowed_set(ctx_c):
    learner = Darling(ctx_c, DarlingConfig(epsilon=1.0))
    allowed = ctx_c.darling_plans.first_actions
    rng = np.random.default_rng(0)
    for s in range(ctx_c.n_states):
        if not allowed[s].any():
            continue
        picks = {learner.act(s, rng) for _ in range(300)}
        assert all(allowed[s, a] for a in picks)
        assert picks == set(np.flatnonzero(allowed[s]).tolist())  # exploration spans the set
    rec = Recording(Darling(ctx_c))
    run(rec, OfficeEnv(task="C"), 100, 0, fast=False)
    for s, a in zip(rec.states, rec.actions, strict=True):
        assert allowed[s, a] or not allowed[s].any()


def test_darling_maximises_over_allowed_actions_only(ctx_c):
    learner = Darling(ctx_c)
    s = ctx_c.s0
    banned = int(np.flatnonzero(~learner.tables.table.allowed[s])[0])
    tables.set_q(learner.tables.table, s, banned, 99.0)
    assert learner.v[s] == 0.0
    assert learner.greedy_policy()[s] != banned


def test_darling_code_executes_only_plan_actions_but_maximises_over_all(ctx_c):
    """The GDQ authors' DARLING: its max ranges over every action, yet what it executes
    (greedy or exploring) is always a plan action."""
    plan = ctx_c.darling_plans.first_actions
    s = ctx_c.s0
    learner = Darling(ctx_c, DarlingConfig(variant="code", epsilon=0.0))
    banned = int(np.flatnonzero(~plan[s])[0])
    tables.set_q(learner.tables.table, s, banned, 99.0)
    assert learner.v[s] == 99.0  # the update's target sees the non-plan action
    rng = np.random.default_rng(0)
    picks = {learner.act(s, rng) for _ in range(500)}  # greedy is banned: replaced
    assert picks == set(np.flatnonzero(plan[s]).tolist())
    assert plan[s, learner.greedy_policy()[s]]
    paper = Darling(ctx_c)
    tables.set_q(paper.tables.table, s, banned, 99.0)
    assert paper.v[s] == 0.0
    rec = Recording(Darling(ctx_c, DarlingConfig(variant="code")))
    run(rec, OfficeEnv(task="C"), 100, 0, fast=False)
    assert all(plan[s, a] or not plan[s].any() for s, a in zip(rec.states, rec.actions,
                                                               strict=True))


def test_darling_code_bootstraps_from_non_plan_actions(ctx_c):
    """One real step: the TD target uses max over all actions for "code", over the plan
    actions for "paper"."""
    plan = ctx_c.darling_plans.first_actions
    s = ctx_c.s0
    a = int(np.flatnonzero(plan[s])[0])
    s2 = next(x for x in range(ctx_c.n_states) if plan[x].any() and not plan[x].all()
              and not ctx_c.goal[x] and x != s)
    banned = int(np.flatnonzero(~plan[s2])[0])
    rng = np.random.default_rng(0)
    for variant, expected in (("code", 0.1 * (-1.0 + 0.95 * 10.0)), ("paper", 0.1 * -1.0)):
        learner = Darling(ctx_c, DarlingConfig(variant=variant))
        tables.set_q(learner.tables.table, s2, banned, 10.0)
        learner.observe(s, a, -1.0, s2, False, False, rng)
        assert learner.q[s, a] == pytest.approx(expected)


def test_darling_allows_everything_where_there_is_no_plan(ctx_c):
    empty = empty_plan_table(ctx_c.n_states, ctx_c.n_actions)
    learner = Darling(replace(ctx_c, darling_plans=empty))
    assert learner.tables.table.allowed.all()
