"""The learners' learned model: the known/unknown switch after m visits, goal-independent
counts, the sparse successor slots and their capacity, and terminal transitions that
never bootstrap (Q at goal-reaching pairs never above R_max)."""

from __future__ import annotations

from dataclasses import replace

import numpy as np
import pytest

from gdq_pddl.envs.office import OfficeEnv
from gdq_pddl.learners import (
    GDQ,
    Darling,
    DynaQ,
    DynaQConfig,
    GDQConfig,
    QLearning,
    learned_model,
    make_learner,
    office_task_context,
    tables,
)
from tests.helpers import Recording, run
from tests.learners.learning import DET, WORLD, expected_backup

# --- the model ----------------------------------------------------------------------------

def test_r_and_t_change_only_after_more_than_m_visits(ctx_c):
    m = 5
    learner = GDQ(ctx_c, GDQConfig(variant="literal", m=m, n_backups=0))
    t, p = learner.tables, learner.params
    s, a = next(zip(*np.nonzero(learner.optimistic_pairs), strict=True))
    s, a = int(s), int(a)
    s2 = int(np.flatnonzero(~ctx_c.goal & (np.arange(ctx_c.n_states) != ctx_c.s0))[0])
    v = np.full(ctx_c.n_states, 3.0)
    optimistic = ctx_c.r_max + p.gamma * v[ctx_c.s0]
    rng = np.random.default_rng(0)
    for k in range(m + 1):
        value = expected_backup(t, p, s, a, v)
        assert value == optimistic, f"changed after {k} visits"
        learner.observe(s, a, -1.0, s2, False, False, rng)
        # sample-based backups (the code variant) replay experience from the first trial
        assert learned_model.sample_outcome(t.model, ctx_c.goal, p, s, a, rng) == (-1.0, s2, False)
    # m + 1 visits: the learned model (always -1 to s2) takes over
    assert learner.visits[s, a] == m + 1
    assert expected_backup(t, p, s, a, v) == pytest.approx(-1.0 + p.gamma * 3.0)
    assert learned_model.sample_outcome(t.model, ctx_c.goal, p, s, a, rng) == (-1.0, s2, False)


def test_model_is_goal_independent_counts(ctx_c):
    learner = DynaQ(ctx_c, DynaQConfig(n_backups=0))
    rng = np.random.default_rng(0)
    goal = int(np.flatnonzero(ctx_c.goal)[0])
    learner.observe(3, 7, 20.0, goal, True, False, rng)  # reached the goal
    learner.observe(3, 7, -20.0, 3, True, False, rng)  # stuck
    learner.observe(3, 7, -20.0, 4, False, True, rng)  # timeout: transition counted
    learner.observe(3, 7, -2.0, 4, False, False, rng)  # ordinary step, cost 2
    t = learner.tables
    assert learner.successors(3, 7) == {4: 2, goal: 1} and t.model.stuck[3, 7] == 1
    assert learner.counts[3, 7, goal] == 1 and learner.counts[3, 7, 4] == 2
    assert learner.counts.sum() == 3
    assert t.model.visits[3, 7] == 4
    assert t.model.cost_n[3, 7] == 1 and t.model.cost_sum[3, 7] == 2.0


def test_sparse_model_keeps_successors_sorted_and_matches_dense_counts(ctx_c):
    learner = DynaQ(ctx_c, DynaQConfig(n_backups=0))
    t, rng = learner.tables, np.random.default_rng(0)
    assert learner.max_successors == ctx_c.max_successors >= 4
    order = [9, 2, 30, 2, 0, 9, 2]  # four successors, recorded out of order
    for s2 in order:
        learner.observe(1, 5, -1.0, s2, False, False, rng)
    expected = {s2: order.count(s2) for s2 in sorted(set(order))}
    n = len(expected)
    slots = t.model.slots[1, 5]
    assert list(slots[:n] >> learned_model.SLOT_SHIFT) == sorted(expected)  # sorted, first slots
    assert list(slots[:n] & learned_model.COUNT_MASK) == [expected[s2] for s2 in sorted(expected)]
    assert np.all(slots[n:] == 0)
    assert learner.successors(1, 5) == expected
    dense = np.zeros((ctx_c.n_states, ctx_c.n_actions, ctx_c.n_states), dtype=np.int64)
    dense[1, 5, list(expected)] = list(expected.values())
    assert np.array_equal(learner.counts, dense)
    # the expected backup sums the successors in increasing order, as a dense loop does
    v = np.linspace(-3.0, 7.0, ctx_c.n_states)
    total = 0.0
    for s2 in range(ctx_c.n_states):
        if dense[1, 5, s2]:
            total += dense[1, 5, s2] * (learner.params.gamma * v[s2] - 1.0)
    learner.params = learner.params._replace(m=0)
    assert expected_backup(t, learner.params, 1, 5, v) == total / len(order)


def test_a_pair_beyond_the_models_capacity_fails_loudly(ctx_c):
    learner = DynaQ(replace(ctx_c, max_successors=2), DynaQConfig(n_backups=0))
    rng = np.random.default_rng(0)
    for s2 in (7, 3, 7):
        learner.observe(2, 4, -1.0, s2, False, False, rng)
    with pytest.raises(ValueError, match="more distinct successors"):
        learner.observe(2, 4, -1.0, 5, False, False, rng)
    assert learner.successors(2, 4) == {3: 1, 7: 2}  # untouched by the failed record
    assert learner.visits[2, 4] == 3
    learner.reserve_successors(3)  # more slots keep what was recorded
    assert learner.max_successors == 3 and learner.successors(2, 4) == {3: 1, 7: 2}
    learner.observe(2, 4, -1.0, 5, False, False, rng)
    assert learner.successors(2, 4) == {3: 1, 5: 1, 7: 2}


def test_both_episode_loops_stop_with_an_error_when_a_pair_overflows(ctx_c):
    from gdq_pddl.learners.episodes import _loop_of

    env = OfficeEnv(task="C")
    tight = replace(ctx_c, max_successors=1)
    learner = make_learner("dynaq", tight)
    with pytest.raises(ValueError, match="more distinct successors"):
        run(Recording(learner), env, 50, 0, fast=False)  # no TabularLearner: no reserve
    learner = make_learner("dynaq", tight)
    office = env.unwrapped
    env.reset(seed=0)
    n = 50
    records = (np.zeros(n), np.zeros(n, dtype=np.int64), np.zeros(n, dtype=np.bool_),
               np.zeros((n, 7), dtype=np.int64))
    assert _loop_of(learner)(office.model, int(office.instance.start_state),
                             int(office.instance.goal_pos), np.zeros(1, dtype=np.uint8),
                             learner.tables, learner.params, office.np_random,
                             np.random.default_rng(1), *records, 0, 0) == -1
    assert learner.visits.sum() == learner.counts.sum() + learner.tables.model.stuck.sum()


def test_model_free_learners_allocate_no_transition_slots(ctx_c):
    for learner in (QLearning(ctx_c), Darling(ctx_c)):
        assert learner.max_successors == 0 and learner.tables.model.slots.nbytes == 0
        learner.reserve_successors(10)
        assert learner.max_successors == 0
        run(learner, OfficeEnv(task="C"), 5, 0)
        assert not learner.counts.any()


def test_context_capacity_is_the_most_successors_of_any_pair(ctx_c):
    from gdq_pddl.envs.compact import compile_compact
    from gdq_pddl.envs.model import compile_model
    from gdq_pddl.envs.solve_compact import successor_capacity

    exact = successor_capacity(compile_model(WORLD))  # union over the full states
    assert exact == successor_capacity(compile_compact(WORLD)) == ctx_c.max_successors
    assert exact > int(np.diff(compile_compact(WORLD).ptr).max())  # > outcomes per pair
    learner = make_learner("dynaq", ctx_c)
    run(learner, OfficeEnv(task="C"), 300, 0)
    n_successors = (learner.tables.model.slots != 0).sum(axis=2)
    assert n_successors.max() <= exact


@pytest.mark.parametrize("fast", [True, False])
def test_runners_give_the_learner_the_slots_its_env_needs(ctx_c, fast):
    told = office_task_context(DET, "C")  # no slips: fewer successors than the office
    assert told.max_successors < ctx_c.max_successors
    small = make_learner("gdq", told, variant="code")
    assert small.max_successors == told.max_successors
    reference = make_learner("gdq", replace(told, max_successors=None), variant="code")
    env = OfficeEnv(task="C")
    a = run(small, env, 60, 3, fast=fast)
    b = run(reference, env, 60, 3, fast=fast)
    assert small.max_successors == ctx_c.max_successors
    assert np.array_equal(a.returns, b.returns) and np.array_equal(small.q, reference.q)
    assert np.array_equal(small.counts, reference.counts)


# --- terminal transitions -----------------------------------------------------------------

def test_backups_never_bootstrap_through_a_terminal_transition(ctx_c):
    learner = DynaQ(ctx_c, DynaQConfig(n_backups=0))
    t, p = learner.tables, learner.params
    rng = np.random.default_rng(0)
    goal = int(np.flatnonzero(ctx_c.goal)[0])
    v = np.full(ctx_c.n_states, 1000.0)  # absurdly high values everywhere
    for _ in range(3):
        learner.observe(5, 9, 20.0, goal, True, False, rng)
    assert expected_backup(t, p, 5, 9, v) == ctx_c.r_max
    for _ in range(2):
        learner.observe(6, 9, -20.0, 6, True, False, rng)
    assert expected_backup(t, p, 6, 9, v) == -ctx_c.r_max
    outcome = learned_model.sample_outcome
    assert outcome(t.model, ctx_c.goal, p, 5, 9, rng) == (ctx_c.r_max, goal, True)
    assert outcome(t.model, ctx_c.goal, p, 6, 9, rng) == (-ctx_c.r_max, 6, True)
    # the sample-based backup with inflated V must not exceed R_max either
    t.table.q[:, :] = 1000.0
    tables.recompute_all_v(t.table)
    t.table.q[5, 9] = 0.0
    sample = tables.Params(**{**p._asdict(), "backup": tables.BACKUP_SAMPLE, "alpha": 1.0})
    learned_model.model_backup(t.table, t.model, t.plans.opt_r, sample, 5, 9, rng)
    assert t.table.q[5, 9] == ctx_c.r_max


def test_real_terminal_and_truncated_steps_do_not_bootstrap(ctx_c):
    learner = QLearning(ctx_c)
    t = learner.tables
    t.table.q[:, :] = 500.0
    tables.recompute_all_v(t.table)
    rng = np.random.default_rng(0)
    t.table.q[1, 2] = 0.0
    learner.observe(1, 2, -20.0, 4, False, True, rng)  # timeout
    assert t.table.q[1, 2] == pytest.approx(learner.config.alpha * -20.0)
    t.table.q[1, 3] = 0.0
    learner.observe(1, 3, 20.0, 4, True, False, rng)  # goal
    assert t.table.q[1, 3] == pytest.approx(learner.config.alpha * 20.0)


@pytest.mark.parametrize("method", ["dynaq", "gdq"])
def test_q_at_goal_reaching_pairs_never_exceeds_r_max(method):
    ctx = office_task_context(DET, "C")
    env = OfficeEnv(task="C", world=DET)
    learner = make_learner(method, ctx, m=0) if method == "gdq" else make_learner(method, ctx)
    run(learner, env, 300, 3)
    goal_pairs = learner.counts[:, :, ctx.goal].sum(axis=2) > 0
    assert goal_pairs.any()
    # once known (m = 0: after one visit), a goal-reaching pair's backup is exactly R_max
    assert np.all(learner.q[goal_pairs] <= ctx.r_max + 1e-9)
    if method == "dynaq":
        assert learner.q.max() <= ctx.r_max + 1e-9
