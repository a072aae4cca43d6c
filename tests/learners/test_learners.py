"""The learners: OptInit, the model's known/unknown switch, DARLING's restriction,
terminal handling, determinism, fast path == Python path and task switches."""

from __future__ import annotations

import pickle
from dataclasses import replace

import numpy as np
import pytest

from gdq_pddl.envs.office import OfficeEnv
from gdq_pddl.envs.variants import deterministic_world
from gdq_pddl.learners import (
    GDQ,
    Darling,
    DarlingConfig,
    DynaQ,
    DynaQConfig,
    GDQConfig,
    QLearning,
    empty_plan_table,
    learned_model,
    make_learner,
    office_task_context,
    run_episodes,
    tables,
)
from gdq_pddl.spaces import LearnerSpaces
from gdq_pddl.world import load_world
from gdq_pddl.world_types import Task
from tests.helpers import Recording, run

WORLD = load_world()
DET = deterministic_world(WORLD)
LITERAL = GDQConfig(variant="literal")

ALL = [("qlearning", {}), ("dynaq", {}), ("darling", {}), ("darling", {"variant": "code"}),
       ("gdq", {}), ("gdq", {"variant": "literal"}), ("gdq", {"variant": "code"})]


# --- OptInit ------------------------------------------------------------------------------

def greedy_walk(learner, world, task: str, limit: int) -> tuple[list[tuple[int, int]], str]:
    """The (state, action) pairs of the greedy policy from the start, and how it ended."""
    policy = learner.greedy_policy()
    env = OfficeEnv(task=task, world=world)
    s, _ = env.reset(seed=0)
    taken, info = [], {"cause": ""}
    for _ in range(limit):
        a = int(policy[s])
        taken.append((s, a))
        s, _, terminated, truncated, info = env.step(a)
        if terminated or truncated:
            break
    return taken, info["cause"]


def expected_backup(t, p, s, a, v):
    """learned_model.expected_value of ``(s, a)`` on a learner's tables."""
    return learned_model.expected_value(t.model, t.table.goal, t.plans.opt_r, p, s, a, v)


@pytest.mark.parametrize("config", [GDQConfig(variant="literal"),
                                    GDQConfig(variant="code", plan_tolerance=0.0)])
def test_optinit_greedy_policy_follows_a_shortest_plan(config):
    ctx = office_task_context(DET, "C")
    learner = GDQ(ctx, config)
    plans = ctx.plans.plans_from(ctx.s0)
    shortest = int(ctx.plans.length[ctx.s0])
    assert shortest == 8 and plans
    taken, cause = greedy_walk(learner, DET, "C", shortest)
    assert cause == "goal"
    assert taken in plans, "the greedy path must be one of the planner's shortest plans"


def test_code_variant_plans_within_the_authors_tolerance():
    """GDQ-code's H holds plans up to 1.3 x the shortest: the 9-step easy-door route too."""
    ctx = office_task_context(DET, "C")
    code, literal = GDQ(ctx, GDQConfig(variant="code")), GDQ(ctx, LITERAL)
    assert code.config.plan_tolerance == pytest.approx(0.3)
    assert literal.config.plan_tolerance == 0.0
    sp = LearnerSpaces(DET)
    p8_to_p5 = (sp.state("p8"), sp.action("goto", "p5"))  # only on the 1->3->2->6 route
    assert code.optimistic_pairs[p8_to_p5] and not literal.optimistic_pairs[p8_to_p5]
    # every pair the greedy policy takes is on some plan (ties between plans may cycle
    # in a memoryless policy: only real experience breaks them)
    taken, _ = greedy_walk(code, DET, "C", 10)
    assert all(code.optimistic_pairs[s, a] for s, a in taken)
    firsts = {plan[0][1] for plan in ctx.darling_plans.plans_from(ctx.s0)}
    assert taken[0][1] in firsts
    with pytest.raises(ValueError, match="plan_tolerance 0.5"):
        GDQ(ctx, GDQConfig(variant="code", plan_tolerance=0.5))


def test_optinit_policy_iteration_values_of_the_optimistic_model(ctx_c):
    learner = GDQ(ctx_c, LITERAL)
    r_max, gamma = ctx_c.r_max, learner.config.gamma
    top = r_max / (1 - gamma)  # optimistic pairs loop back to s0 without ending
    opt = learner.optimistic_pairs
    assert opt.any()
    not_goal = ~ctx_c.goal
    assert np.allclose(learner.q[opt], top, atol=1e-6)
    rest = ~opt & not_goal[:, None]
    assert np.allclose(learner.q[rest], gamma * top, atol=1e-6)
    assert np.all(learner.q[ctx_c.goal] == 0.0)


def test_code_variant_sets_r_max_on_plan_pairs_only(ctx_c):
    learner = GDQ(ctx_c, GDQConfig(variant="code"))
    opt = learner.optimistic_pairs
    assert np.all(learner.q[opt] == ctx_c.r_max)
    assert np.all(learner.q[~opt] == 0.0)
    assert learner.params.backup == tables.BACKUP_SAMPLE


def test_code_variant_backups_replay_experience_and_skip_untried_pairs(ctx_c):
    learner = GDQ(ctx_c, GDQConfig(variant="code", n_backups=0))
    t, p = learner.tables, learner.params
    rng = np.random.default_rng(0)
    s, a = (int(x[0]) for x in np.nonzero(learner.optimistic_pairs))
    t.table.q[:, :] = 50.0  # a backup through the optimistic model would move Q(s, a)
    tables.recompute_all_v(t.table)
    learned_model.model_backup(t.table, t.model, t.plans.opt_r, p, s, a, rng)
    assert t.table.q[s, a] == 50.0  # never tried: left alone
    s2 = int(np.flatnonzero(~ctx_c.goal & (np.arange(ctx_c.n_states) != s))[0])
    # one ordinary step to s2 at cost 2
    learned_model.record(t.model, t.table.goal, p, s, a, -2.0, s2, False, False)
    assert learner.successors(s, a) == {s2: 1} and t.model.visits[s, a] == 1
    t.table.q[s2, :] = 10.0
    tables.recompute_all_v(t.table)
    learned_model.model_backup(t.table, t.model, t.plans.opt_r, p, s, a, rng)
    target = -2.0 + p.gamma * 10.0
    assert t.table.q[s, a] == pytest.approx(50.0 + p.alpha * (target - 50.0))


def test_code_variant_task_switch_keeps_the_model_and_reseeds_q(ctx_c):
    learner = GDQ(ctx_c, GDQConfig(variant="code"))
    env = OfficeEnv(task="C")
    env.reset(seed=0)
    run_episodes(learner, env, 200, np.random.default_rng(0))
    visits = learner.visits.copy()
    learner.start_task(office_task_context(WORLD, "D"))
    assert np.array_equal(learner.visits, visits) and visits.sum() > 0
    opt = learner.optimistic_pairs
    assert np.all(learner.q[opt] == ctx_c.r_max) and np.all(learner.q[~opt] == 0.0)


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
    from gdq_pddl.learners.episodes import _episodes

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
    assert _episodes(office.model, int(office.start_state), int(office.goal_pos),
                     np.zeros(1, dtype=np.uint8), learner.tables, learner.params,
                     office.np_random, np.random.default_rng(1), *records, 0, 0) == -1
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


# --- equivalences and determinism ---------------------------------------------------------

def test_dynaq_without_backups_acts_exactly_like_qlearning(ctx_c):
    env = OfficeEnv(task="C")
    a = Recording(DynaQ(ctx_c, DynaQConfig(n_backups=0)))
    b = Recording(QLearning(ctx_c))
    run(a, env, 60, 11, fast=False)
    run(b, env, 60, 11, fast=False)
    assert a.actions == b.actions
    assert np.array_equal(a.q, b.q)


@pytest.mark.parametrize(("method", "kw"), ALL)
def test_same_seed_same_results_bit_for_bit(ctx_c, method, kw):
    env = OfficeEnv(task="C")
    out = []
    for _ in range(2):
        learner = make_learner(method, ctx_c, **kw)
        rec = run(learner, env, 80, 5)
        out.append((rec, learner.q.copy()))
    (r1, q1), (r2, q2) = out
    for f in ("returns", "steps", "success", "area_visits"):
        assert np.array_equal(getattr(r1, f), getattr(r2, f))
    assert np.array_equal(q1, q2)


@pytest.mark.parametrize(("method", "kw"), ALL)
def test_fast_path_equals_python_path(ctx_c, method, kw):
    env = OfficeEnv(task="C")
    fast, slow = make_learner(method, ctx_c, **kw), make_learner(method, ctx_c, **kw)
    rf = run(fast, env, 40, 7, fast=True)
    rs = run(slow, env, 40, 7, fast=False)
    for f in ("returns", "steps", "success", "area_visits"):
        assert np.array_equal(getattr(rf, f), getattr(rs, f)), f
    assert np.array_equal(fast.q, slow.q)
    assert np.array_equal(fast.tables.model.slots, slow.tables.model.slots)  # the same slots, too
    assert np.array_equal(fast.counts, slow.counts)
    assert rf.area_visits.sum() == rf.steps.sum()  # every office position has an area
    assert rf.area_visits.shape == (40, 7)


def test_runner_works_through_gymnasium_make(ctx_c):
    import gymnasium

    env = gymnasium.make("gdq_pddl/Office-v0", task="C")
    learner = QLearning(ctx_c)
    rec_fast = run(learner, env, 20, 1)
    learner2 = QLearning(ctx_c)
    rec_slow = run(learner2, env, 20, 1, fast=False)
    assert np.array_equal(rec_fast.returns, rec_slow.returns)


# --- no plans, task switch ----------------------------------------------------------------

@pytest.mark.parametrize("variant", ["literal", "code"])
def test_gdq_without_any_plan_runs_and_learns(variant):
    """The plan-based variants with an empty H: Dyna-Q with extra steps, still learning.
    (The default variant plans on its prior model, not on H: tests/learners/test_gdq_model.py.)"""
    task = Task("near", "p0", "p2")
    ctx = office_task_context(DET, task)
    empty = empty_plan_table(ctx.n_states, ctx.n_actions)
    ctx = replace(ctx, plans=empty, darling_plans=empty)
    learner = GDQ(ctx, GDQConfig(variant=variant))
    assert not learner.optimistic_pairs.any()
    env = OfficeEnv(start="p0", goal="p2", world=DET)
    rec = run(learner, env, 150, 2)
    assert rec.success[-50:].mean() > 0.8
    assert rec.success[-50:].mean() > rec.success[:50].mean()
    assert learner.visits.sum() == rec.steps.sum()


def test_task_switch_keeps_the_model_and_reruns_optinit(ctx_c):
    learner = GDQ(ctx_c)
    env = OfficeEnv(task="C")
    run(learner, env, 30, 4)
    counts, visits = learner.counts.copy(), learner.visits.copy()
    assert visits.sum() > 0
    ctx_e = office_task_context(WORLD, "E")
    learner.start_task(ctx_e)
    assert np.array_equal(learner.counts, counts)
    assert np.array_equal(learner.visits, visits)
    assert learner.params.s0 == ctx_e.s0
    assert np.array_equal(learner.tables.table.goal, ctx_e.goal)
    # OptInit for E: the plan pairs from E's start are the optimistic ones, and the
    # greedy action at E's start begins one of its plans (unknown pairs dominate there)
    firsts = {p[0][1] for p in ctx_e.plans.plans_from(ctx_e.s0)}
    assert learner.greedy_policy()[ctx_e.s0] in firsts
    # the learned model is what the known pairs' backups use after the switch
    known = np.argwhere(visits > learner.params.m)
    assert len(known)
    s, a = map(int, known[0])
    assert expected_backup(learner.tables, learner.params, s, a, learner.v) == \
        pytest.approx(learner.q[s, a], abs=1e-6)
    run(learner, OfficeEnv(task="E"), 10, 5)  # keeps learning on the new task
    assert learner.visits.sum() > visits.sum()


def test_dynaq_task_switch_keeps_model_and_q(ctx_c):
    learner = DynaQ(ctx_c)
    run(learner, OfficeEnv(task="C"), 20, 4)
    q, counts = learner.q.copy(), learner.counts.copy()
    learner.start_task(office_task_context(WORLD, "D"))
    assert np.array_equal(learner.q, q) and np.array_equal(learner.counts, counts)


def test_make_learner_rejects_unknown_methods_and_bad_configs(ctx_c):
    with pytest.raises(ValueError):
        make_learner("sarsa", ctx_c)
    with pytest.raises(ValueError):
        GDQConfig(variant="other")  # type: ignore[arg-type]
    with pytest.raises(ValueError):
        Darling(ctx_c, DarlingConfig(tolerance=0.5))


def test_terminal_optimism_bounds_optinit_values_by_r_max(ctx_c):
    learner = GDQ(ctx_c, GDQConfig(variant="literal", optimistic_successor="terminal"))
    opt = learner.optimistic_pairs
    assert np.allclose(learner.q[opt], ctx_c.r_max)
    assert np.all(learner.q[~opt] == 0.0)
    t, p = learner.tables, learner.params
    s, a = (int(x[0]) for x in np.nonzero(opt))
    high = np.full(ctx_c.n_states, 100.0)
    assert expected_backup(t, p, s, a, high) == ctx_c.r_max  # no continuation


def test_numba_cache_is_dropped_when_a_compiled_module_changes(tmp_path):
    """The fast loop's cache bakes in the rules it calls from other files; an edit of
    any of them must drop the whole cache (gdq_pddl/_jit_cache.py)."""
    from gdq_pddl import _jit_cache

    for folder in _jit_cache.JIT_FOLDERS:
        (tmp_path / folder / "__pycache__").mkdir(parents=True)
        (tmp_path / folder / "mod.py").write_text("x = 1\n")
    cached = tmp_path / "learners" / "__pycache__" / "runner._episodes-1.py311.nbi"
    cached.write_text("stale")
    assert _jit_cache.refresh(tmp_path)  # no stamp yet: dropped, stamp written
    assert not cached.exists()
    # a whole .nbi file is two pickles (the index); a damaged one is dropped on its own
    cached.write_bytes(pickle.dumps("index") + pickle.dumps("entries"))
    assert not _jit_cache.refresh(tmp_path) and cached.exists()  # nothing changed
    (tmp_path / "learners" / "mod.py").write_text("x = 2\n")  # a callee changes
    assert _jit_cache.refresh(tmp_path) and not cached.exists()


def test_learner_tables_are_refused_past_the_machines_memory(monkeypatch):
    from gdq_pddl.envs.pddl_env import load_instance
    from gdq_pddl.errors import PlanningError
    from gdq_pddl.learners import context
    from gdq_pddl.learners.tables import table_bytes

    inst = load_instance("courier", "courier-1")
    need = table_bytes(inst.n_states, inst.columns.shape[1], inst.max_successors)
    assert context.MAX_TABLE_BYTES is None  # the default: what the machine has
    monkeypatch.setenv("GDQ_PDDL_MEMORY", str(need))
    assert context.task_context(inst).columns is inst.columns  # fits exactly
    monkeypatch.setenv("GDQ_PDDL_MEMORY", str(need - 1))
    with pytest.raises(PlanningError, match=r"courier-1.pddl: .*learners' tables would need "
                       r".*this machine's memory, or .*MAX_TABLE_BYTES"):
        context.task_context(inst)
    monkeypatch.setattr(context, "MAX_TABLE_BYTES", need)  # a figure of one's own wins
    assert context.task_context(inst).columns is inst.columns
