"""GDQ's default variant: the action knowledge as an optimistic prior model.

The semantics pinned here (issue 11): the prior's greedy policy is a shortest plan before
any step; a pair moves from the prior to the learned model after more than m visits; with
accurate knowledge and no slips the first greedy episode is a shortest plan; an action
the knowledge says does nothing is never valued above the best allowed one until tried;
same seed, same bits; and the same learner runs on PDDL problems and generated buildings.
"""

from __future__ import annotations

from dataclasses import replace

import numpy as np
import pytest

from gdq_pddl.abstraction.prior import NO_CHANGE, PriorModel
from gdq_pddl.envs.office import OfficeEnv
from gdq_pddl.envs.variants import deterministic_world
from gdq_pddl.learners import GDQ, GDQConfig, gdq, office_task_context, run_episodes, warm_start
from gdq_pddl.spaces import LearnerSpaces
from gdq_pddl.world import load_world
from tests.helpers import Recording, run

WORLD = load_world()
DET = deterministic_world(WORLD)
TASKS = list(WORLD.tasks)


def greedy_path(learner, ctx) -> list[tuple[int, int]]:
    """The greedy policy's pairs from the start, followed through the prior model (over
    the context's columns)."""
    policy, nxt = learner.greedy_policy(), ctx.prior.next_state
    s, path = ctx.s0, []
    while not ctx.goal[s] and len(path) <= ctx.n_states:
        a = int(policy[s])
        path.append((s, a))
        s = int(nxt[s, ctx.column_of(s, a)])
        assert s != NO_CHANGE, f"the greedy action {a} does nothing according to the prior"
    return path


# --- the prior model ----------------------------------------------------------------------

def known_pair(t, p, s, a):
    """Whether the pair is valued by the learned model (gdq.is_known on a learner's tables)."""
    return gdq.is_known(t.model.visits, t.prior.next_state, p.m, s, a)


def hybrid(t, p, s, a):
    """gdq.hybrid_backup on a learner's tables."""
    return gdq.hybrid_backup(t.table, t.model, t.prior.next_state, t.prior.reward, t.prior.dead,
                             p, s, a)


def test_the_office_prior_follows_the_knowledge(ctx_c):
    sp = LearnerSpaces(WORLD)
    prior = ctx_c.prior
    assert prior.next_state.shape == (ctx_c.n_states, ctx_c.n_actions)
    # every first action of a plan is applicable; moving through a closed door is not
    app = prior.applicable
    assert np.all(app[ctx_c.plans.first_actions])
    assert 0 < app.sum(axis=1).max() < ctx_c.n_actions
    ptr, pairs = prior.predecessors()
    assert ptr[-1] == app.sum() and np.all(np.diff(ptr) >= 0)
    for x in range(prior.n_states):
        for pair in pairs[ptr[x]:ptr[x + 1]]:
            assert prior.next_state.ravel()[pair] == x
    assert sp.n_states == prior.n_states


@pytest.mark.parametrize("task", TASKS)
def test_before_any_step_the_greedy_policy_follows_a_shortest_plan(task):
    ctx = office_task_context(WORLD, task)
    learner = GDQ(ctx)
    path = greedy_path(learner, ctx)
    assert len(path) == int(ctx.plans.length[ctx.s0])
    assert path in ctx.plans.plans_from(ctx.s0)


@pytest.mark.parametrize("task", TASKS)
def test_deterministic_world_first_greedy_episode_is_a_shortest_plan(task):
    """Accurate knowledge, every success probability 1: the first episode (no
    exploration) takes a shortest plan to the goal."""
    ctx = office_task_context(DET, task)
    rec = Recording(GDQ(ctx, GDQConfig(epsilon=0.0)))
    records = run(rec, OfficeEnv(task=task, world=DET), 1, 0)
    assert records.success[0]
    assert records.steps[0] == int(ctx.plans.length[ctx.s0])
    assert rec.pairs in ctx.plans.plans_from(ctx.s0)


# --- prior -> learned ---------------------------------------------------------------------

@pytest.mark.parametrize("m", [0, 1, 3])
@pytest.mark.parametrize("w", [0.0, 1.0])
def test_a_pair_switches_from_prior_to_learned_after_more_than_m_visits(ctx_c, m, w):
    learner = GDQ(ctx_c, GDQConfig(m=m, n_backups=0, prior_weight=w))
    t, p = learner.tables, learner.params
    s = ctx_c.s0
    a = int(np.flatnonzero(ctx_c.plans.first_actions[s])[0])
    s_prior = int(ctx_c.prior.next_state[s, a])
    stuck_at = s  # real outcome: no progress at cost 3, unlike the prior's promise
    rng = np.random.default_rng(0)
    for k in range(m + 1):
        prior_value = -p.prior_cost + p.gamma * learner.v[s_prior]
        assert not known_pair(t, p, s, a)
        assert hybrid(t, p, s, a) == pytest.approx(prior_value), k
        learner.observe(s, a, -3.0, stuck_at, False, False, rng)
    assert known_pair(t, p, s, a) and learner.visits[s, a] == m + 1
    n, v = m + 1, learner.v
    learned = -3.0 + p.gamma * v[stuck_at]
    prior_value = -p.prior_cost + p.gamma * v[s_prior]
    expected = (n * learned + w * prior_value) / (n + w)  # the prior as w pseudo-trials
    assert hybrid(t, p, s, a) == pytest.approx(expected)
    assert learner.q[s, a] == pytest.approx(expected)  # the real step's pair is revalued


def test_an_inapplicable_action_is_known_after_its_first_trial(ctx_c):
    learner = GDQ(ctx_c, GDQConfig(n_backups=0, m=3))  # whatever m
    t, p = learner.tables, learner.params
    s = ctx_c.s0
    a = int(np.flatnonzero(~ctx_c.prior.applicable[s])[0])
    assert not learner.tables.table.allowed[s, a] and not known_pair(t, p, s, a)
    x = int(np.flatnonzero(ctx_c.prior.applicable[s])[0])
    s2 = int(ctx_c.prior.next_state[s, x])  # reality surprises: it does move
    learner.observe(s, a, -1.0, s2, False, False, np.random.default_rng(0))
    assert known_pair(t, p, s, a) and learner.tables.table.allowed[s, a]
    v, w = learner.v, p.prior_weight  # the prior, "no change", as w pseudo-trials
    expected = ((-1.0 + p.gamma * v[s2]) + w * (-p.prior_cost + p.gamma * v[s])) / (1 + w)
    assert learner.q[s, a] == pytest.approx(expected)


# --- optimism never favours what the knowledge rules out ----------------------------------

def _untried_inapplicable_below_v(learner) -> None:
    untried = ~learner.context.prior.applicable & (learner.visits == 0)
    untried[learner.context.goal] = False
    t = learner.tables
    assert not np.any(t.table.allowed & untried)
    # the learner's own values, before the Q property fills the untried no-ops in: v and
    # the greedy choice range over the allowed pairs only
    raw_best = np.where(t.table.allowed, t.table.q, -np.inf).max(axis=1)
    has = t.table.allowed.any(axis=1)
    assert np.array_equal(t.table.v[has], raw_best[has])
    policy = learner.greedy_policy()
    assert not untried[np.arange(len(policy)), policy].any(), "greedy picks an untried no-op"
    # and the Q table a user reads values them below v
    best = np.where(t.table.allowed, learner.q, -np.inf).max(axis=1)
    rows, cols = np.nonzero(untried)
    assert np.all(learner.q[rows, cols] <= best[rows]), "an untried no-op valued above v"


@pytest.mark.parametrize("task", ["C", "E"])
def test_an_inapplicable_action_is_never_valued_above_the_best_allowed_one(task):
    ctx = office_task_context(WORLD, task)
    learner = GDQ(ctx, GDQConfig(explore_all=0.5))
    _untried_inapplicable_below_v(learner)
    env = OfficeEnv(task=task)
    env.reset(seed=3)
    rng = np.random.default_rng(4)
    for _ in range(20):
        run_episodes(learner, env, 10, rng)
        _untried_inapplicable_below_v(learner)
    assert (learner.visits[~ctx.prior.applicable] > 0).any()  # some were tried


def test_q_is_the_hybrid_backup_of_every_pair_after_optinit(ctx_c):
    learner = GDQ(ctx_c)
    run(learner, OfficeEnv(task="C"), 50, 1)
    learner.start_task(ctx_c)  # OptInit again, on the learned model now
    t, p = learner.tables, learner.params
    for s in np.flatnonzero(~ctx_c.goal):
        for a in range(ctx_c.n_actions):
            assert learner.q[s, a] == pytest.approx(hybrid(t, p, s, a), abs=1e-6)


# --- determinism, both loops, growth --------------------------------------------------------

def test_same_seed_same_bits_and_fast_equals_python(ctx_c):
    env = OfficeEnv(task="C")
    a, b, c = (GDQ(ctx_c) for _ in range(3))
    ra, rb = run(a, env, 60, 7), run(b, env, 60, 7)
    rc = run(c, env, 60, 7, fast=False)
    for r in (rb, rc):
        assert np.array_equal(ra.returns, r.returns) and np.array_equal(ra.steps, r.steps)
    assert np.array_equal(a.q, b.q) and np.array_equal(a.q, c.q)
    assert np.array_equal(a.counts, c.counts)


def _indexed(t, x: int) -> set[int]:
    out, e = set(), t.prior.rev_head[x]
    while e >= 0:
        out.add(int(t.prior.rev_pair[e]))
        e = t.prior.rev_next[e]
    return out


@pytest.mark.parametrize("fast", [True, False])
def test_the_reverse_index_grows_and_holds_every_state_a_known_backup_reads(ctx_c, fast):
    learner = GDQ(ctx_c, GDQConfig(epsilon=1.0, explore_all=1.0))
    start = len(learner.tables.prior.rev_pair)
    run(learner, OfficeEnv(task="C"), 300, 2, fast=fast)
    if not fast:  # the Python loop grows it only when full: make it grow once
        before = [_indexed(learner.tables, x) for x in range(ctx_c.n_states)]
        learner.reserve_reverse(len(learner.tables.prior.rev_pair))
        assert [_indexed(learner.tables, x) for x in range(ctx_c.n_states)] == before
        run(learner, OfficeEnv(task="C"), 100, 3, fast=fast)
    t, n_a = learner.tables, ctx_c.n_actions
    assert len(t.prior.rev_pair) > start  # grew (the fast loop keeps an episode's worth free)
    index = [_indexed(t, x) for x in range(ctx_c.n_states)]
    known = 0
    for s, a in zip(*np.nonzero(learner.visits), strict=True):
        assert known_pair(t, learner.params, s, a)  # m = 0: one trial
        known += 1
        prior = int(ctx_c.prior.next_state[s, a])
        reads = {*learner.successors(s, a), s if prior == NO_CHANGE else prior}
        for x in reads:
            if not ctx_c.goal[x]:
                assert s * n_a + a in index[x], (s, a, x)
    assert known > 200
    # and nothing else: every entry is a known pair whose backup reads that state
    for x in range(ctx_c.n_states):
        for pair in index[x]:
            s, a = divmod(pair, n_a)
            prior = int(ctx_c.prior.next_state[s, a])
            assert x in learner.successors(s, a) or x == (s if prior == NO_CHANGE else prior)


def test_a_context_without_prior_is_refused(ctx_c):
    with pytest.raises(ValueError, match="prior"):
        GDQ(replace(ctx_c, prior=None))
    wrong = PriorModel(np.zeros((3, 3), dtype=np.int64))
    with pytest.raises(ValueError, match="prior"):
        GDQ(replace(ctx_c, prior=wrong))


# --- runs unchanged elsewhere -------------------------------------------------------------

@pytest.mark.parametrize("problem", ["keys-1", "delivery-1"])
def test_gdq_learns_on_a_shipped_pddl_problem(problem):
    from gdq_pddl.envs.pddl_env import PDDLEnv, PDDLInstance
    from gdq_pddl.learners import make_learner, pddl_task_context
    from gdq_pddl.resources import data_file

    domain = problem.split("-")[0]
    inst = PDDLInstance.from_files(*(str(data_file(*p)) for p in (
        ("domains", f"{domain}.pddl"), ("problems", f"{problem}.pddl"),
        ("dynamics", f"{domain}.toml"))))
    ctx = pddl_task_context(inst)
    assert ctx.prior is not None and ctx.prior.n_states == inst.n_states
    learner = make_learner("gdq", ctx)
    env = PDDLEnv(instance=inst)
    path = greedy_path(learner, ctx)
    assert len(path) == int(inst.graph.distances[0])  # the prior's shortest plan
    rec = run(learner, env, 150, 0)
    assert rec.success[-50:].mean() > 0.8


def test_gdq_runs_on_a_generated_building():
    from gdq_pddl.buildings import building_world
    from gdq_pddl.envs.office import CompactEnv
    from gdq_pddl.learners.episodes import run_compact

    world = building_world(100, seed=1)
    ctx = office_task_context(world, "A")
    learner = GDQ(ctx, GDQConfig(gamma=1 - 1 / world.step_limit))  # as gdq-pddl scale
    assert len(greedy_path(learner, ctx)) == int(ctx.plans.length[ctx.s0])
    env = CompactEnv(task="A", world=world)
    env.reset(seed=0)
    rec = run_compact(learner, env, 300, np.random.default_rng(1))
    assert rec.success[-50:].mean() > 0.8


def test_the_prior_of_an_action_with_several_outcomes_is_the_one_closest_to_the_goal():
    """A PPDDL domain's all-outcomes determinisation gives one ground action several
    planner edges; the optimistic prior takes the best of them."""
    from gdq_pddl.abstraction.prior import prior_from_graph
    from tests.pddl.hike import hike

    graph = hike("all-outcomes").graph
    prior = prior_from_graph(graph).next_state
    dist = np.where(graph.distances < 0, np.inf, graph.distances)
    several = 0
    for s in range(graph.n_states):
        outcomes: dict[int, list[int]] = {}
        for op, nxt in graph.edges(s):
            outcomes.setdefault(op, []).append(nxt)
        for op, nexts in outcomes.items():
            several += len(nexts) > 1
            best = min(nexts, key=lambda x: (dist[x], x))
            column = int(np.flatnonzero(graph.offered[s] == op)[0])  # s offers op
            assert prior[s, column] == best
        assert (prior[s] != NO_CHANGE).sum() == len(outcomes)
    assert several > 0


def test_optinit_starts_from_the_prior_values_and_needs_one_sweep_on_a_first_task(ctx_c):
    """The closed form from the goal distances is the prior's fixed point."""
    learner = GDQ(ctx_c)
    t, p = learner.tables, learner.params
    init = warm_start.prior_values(t.table, t.prior, p)
    assert np.allclose(init, learner.v, atol=1e-9)
    assert gdq.value_iteration(t.table, t.model, t.prior, t.queue, p, 1e-9, 1000) == 1
    # a state that cannot reach the goal by the knowledge's actions: -c / (1 - gamma)
    dead = PriorModel(np.where(np.arange(ctx_c.n_states)[:, None] == ctx_c.s0, NO_CHANGE,
                               ctx_c.prior.next_state))
    cut = GDQ(replace(ctx_c, prior=dead))
    assert cut.v[ctx_c.s0] == pytest.approx(-p.prior_cost / (1 - p.gamma))
