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
from gdq_pddl.errors import ConfigError
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
    return gdq.hybrid_backup(t.table, t.model, t.prior.next_state, t.prior.reward, p, s, a)


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


def test_exploration_of_every_action_tries_the_untried_ones_first(ctx_c):
    """``explore_all`` draws an action never tried in the state while there is one."""
    learner = GDQ(ctx_c, GDQConfig(epsilon=1.0, explore_all=1.0, n_backups=0))
    rng, s = np.random.default_rng(5), ctx_c.s0
    seen = []
    for _ in range(ctx_c.n_actions):
        a = learner.act(s, rng)
        seen.append(a)
        learner.observe(s, a, -1.0, s, False, False, rng)  # pretend nothing happens
    assert sorted(seen) == list(range(ctx_c.n_actions))
    again = {learner.act(s, rng) for _ in range(400)}  # all tried: uniform over all
    assert len(again) > ctx_c.n_actions // 2


def test_exploring_steps_draw_the_actions_near_the_best_value(ctx_c):
    """``explore="values"`` (the default): an exploring step draws every allowed action
    whose Q is within ``plan_tolerance`` of the state's value (``v - 0.3 (r_max - v)``),
    and none below; an action whose value falls below leaves the set."""
    learner = GDQ(ctx_c, GDQConfig(epsilon=1.0, explore_all=0.0, n_backups=0))
    t, p, s = learner.tables.table, learner.params, ctx_c.s0
    assert p.explore_band == 0.3

    def near():
        floor = t.v[s] - 0.3 * max(0.0, p.r_max - t.v[s])
        return {int(a) for a in np.flatnonzero(t.allowed[s]) if t.q[s, a] >= floor}

    rng = np.random.default_rng(0)
    first = near()
    assert len(first) > 1 and {learner.act(s, rng) for _ in range(2000)} == first
    worse = min(first, key=lambda a: (t.q[s, a], a))  # another action keeps v at its max
    t.q[s, worse] = t.v[s] - p.r_max  # learned to be bad
    assert near() == first - {worse}
    assert {learner.act(s, rng) for _ in range(2000)} == first - {worse}
    plans = GDQ(ctx_c, GDQConfig(explore="plans")).params
    assert plans.explore_band < 0  # the former rule: the plans' first actions (guide)


def _two_step_loops(learner) -> set[tuple[int, int]]:
    """The pairs within the exploring band, not greedy, whose prior successor has a greedy
    action the prior leads straight back (computed here with numpy, not the kernel)."""
    t, p, leads = learner.tables.table, learner.params, learner.tables.prior.next_state
    out = set()
    for s in np.flatnonzero(~t.goal):
        floor = t.v[s] - p.explore_band * max(0.0, p.r_max - t.v[s])
        for a in np.flatnonzero(t.allowed[s] & (t.q[s] >= floor) & (t.q[s] < t.v[s])):
            x = leads[s, a]
            if x >= 0 and x != s and (leads[x, t.allowed[x] & (t.q[x] >= t.v[x])] == s).any():
                out.add((int(s), int(a)))
    return out


def test_exploring_steps_leave_out_a_move_the_next_greedy_step_undoes(ctx_c):
    """``explore_loops=False`` (the default): a move within the band whose prior successor's
    greedy step leads straight back is never drawn; ``True`` draws it as before."""
    config = {"epsilon": 1.0, "explore_all": 0.0, "n_backups": 0}
    default = GDQ(ctx_c, GDQConfig(**config))
    looping = GDQ(ctx_c, GDQConfig(**config, explore_loops=True))
    assert not default.config.explore_loops and default.params.explore_loops == 0.0
    pairs = _two_step_loops(default)
    assert pairs and pairs == _two_step_loops(looping)  # after OptInit on task C: 2 pairs
    rng = np.random.default_rng(0)
    for s in {s for s, _ in pairs}:
        loops = {a for x, a in pairs if x == s}
        drawn = {default.act(s, rng) for _ in range(2000)}
        drawn_too = {looping.act(s, rng) for _ in range(2000)}
        assert drawn_too - drawn == loops and not drawn & loops


def test_a_move_into_the_goal_is_never_taken_for_a_loop(ctx_c):
    """The episode ends in a goal, so a move into it is drawn even where the goal state
    has an action the prior leads straight back (goal rows keep Q = V = 0, so every
    action there counts as greedy)."""
    learner = GDQ(ctx_c, GDQConfig(epsilon=1.0, explore_all=0.0, n_backups=0))
    t, leads = learner.tables.table, learner.tables.prior.next_state
    goal = int(np.flatnonzero(t.goal)[0])
    s, a = next((s, int(a)) for s in range(len(t.v)) for a in np.flatnonzero(leads[s] == goal)
                if (leads[goal] == s).any() and t.allowed[s].sum() > 1)
    other = int(next(b for b in np.flatnonzero(t.allowed[s]) if b != a))
    t.q[s, t.allowed[s]] = 0.0
    t.q[s, a], t.q[s, other], t.v[s] = 15.0, 16.0, 16.0  # a: not greedy, within the band
    rng = np.random.default_rng(0)
    assert {learner.act(s, rng) for _ in range(500)} == {a, other}


@pytest.mark.parametrize(("domain", "problem", "dynamics", "exact"), [
    ("keys", "keys-1", "keys", False),  # STRIPS + a dynamics file: reality may differ
    ("keys-ppddl", "keys-ppddl-2", None, True),  # PPDDL: the actions and outcomes are reality's
])
def test_untried_actions_are_explored_only_where_the_knowledge_may_lack_them(
        ctx_c, domain, problem, dynamics, exact):
    from gdq_pddl.envs.pddl_env import load_instance
    from gdq_pddl.learners import make_learner, pddl_task_context

    ctx = pddl_task_context(load_instance(domain, problem, dynamics))
    assert ctx.exact_knowledge is exact
    assert make_learner("GDQ", ctx).params.explore_all == (0.0 if exact else 0.1)
    assert make_learner("GDQ", ctx, explore_all=0.25).params.explore_all == 0.25
    assert not ctx_c.exact_knowledge and GDQ(ctx_c).params.explore_all == 0.1  # the office


def test_exploration_of_every_action_can_spare_the_last_step(ctx_c):
    """With ``explore_all_last_step=False`` a state the knowledge takes to the goal in one
    action explores only the plans' first actions; a state farther away still tries
    untried actions."""
    nxt = ctx_c.prior.next_state
    reaches = (nxt != NO_CHANGE) & ctx_c.goal[np.where(nxt == NO_CHANGE, 0, nxt)]
    last = [s for s in range(ctx_c.n_states) if reaches[s].any() and not ctx_c.goal[s]]
    far = ctx_c.s0
    assert last and not reaches[far].any()
    config = GDQConfig(epsilon=1.0, explore_all=1.0, n_backups=0, explore_all_last_step=False)
    learner = GDQ(ctx_c, config)
    guide = ctx_c.darling_plans.allowed_actions()  # what exploration draws from

    def explored(agent, s):
        return {agent.act(s, rng) for _ in range(50)}

    rng = np.random.default_rng(3)
    for s in last:
        assert explored(learner, s) <= set(np.flatnonzero(guide[s]))
    assert not explored(learner, far) <= set(np.flatnonzero(guide[far]))
    both = GDQ(ctx_c, replace(config, explore_all_last_step=True))
    assert not explored(both, last[0]) <= set(np.flatnonzero(guide[last[0]]))
    with pytest.raises(ValueError, match="explore_all_last_step"):
        GDQConfig(explore_all_last_step=0)


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
    from tests.pddl.test_ppddl import hike

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


# --- the problem's own reward scale ------------------------------------------------------

@pytest.mark.parametrize("own", [False, True])
def test_the_learned_model_pays_ending_steps_as_the_env_does(own):
    """On the problem's own scale (IPPC rewards) a stuck end pays the step's cost and no
    -r_max, and the goal step its cost besides r_max; on the goal scale -r_max and r_max."""
    from gdq_pddl.learners.learned_model import (
        learned_value,
        new_model,
        record,
        sample_outcome,
    )
    from gdq_pddl.learners.tables import Params

    p = Params(kind=4, alpha=0.1, gamma=1.0, epsilon=0.1, r_max=20.0, n_backups=0, m=0,
               backup=0, s0=0, own_scale=float(own))
    goal = np.array([False, False, True])
    model = new_model(3, 1, 3)
    assert record(model, goal, p, 0, 0, -3.0, 1, False, False)  # an ordinary step, cost 3
    assert record(model, goal, p, 0, 0, -3.0, 0, True, False)  # stuck
    assert record(model, goal, p, 0, 0, 17.0, 2, True, False)  # the goal
    v = np.array([0.0, 5.0, 0.0])
    value = learned_value(model.slots, model.stuck, model.visits, model.cost_sum,
                          model.cost_n, model.cost_all, goal, v, p, 0, 0)
    stuck, reached = (-3.0, 20.0 - 3.0) if own else (-20.0, 20.0)
    assert value == pytest.approx((stuck + (5.0 - 3.0) + reached) / 3)
    rng = np.random.default_rng(0)
    seen = {sample_outcome(model, goal, p, 0, 0, rng) for _ in range(60)}
    assert seen == {(stuck, 0, True), (-3.0, 1, False), (reached, 2, True)}


def test_the_learned_model_keeps_what_an_ending_step_itself_pays_on_own_scale():
    """An ending step's own reward is learned from the ending steps themselves: a goal step
    that pays 25 besides the goal reward (the courier's on-time delivery) is worth 45, a
    stuck step that cost 7 is worth -7, whatever the pair's or other pairs' ordinary steps
    cost."""
    from gdq_pddl.learners.learned_model import learned_value, new_model, record
    from gdq_pddl.learners.tables import Params

    p = Params(kind=4, alpha=0.1, gamma=1.0, epsilon=0.1, r_max=20.0, n_backups=0, m=0,
               backup=0, s0=0, own_scale=1.0)
    goal = np.array([False, False, True])
    model = new_model(3, 2, 3)
    assert record(model, goal, p, 1, 0, -1.0, 0, False, False)  # an ordinary step elsewhere
    assert record(model, goal, p, 0, 0, 45.0, 2, True, False)  # the goal, 25 over r_max
    assert record(model, goal, p, 0, 1, -7.0, 0, True, False)  # stuck after paying 7
    v = np.zeros(3)
    args = (model.slots, model.stuck, model.visits, model.cost_sum, model.cost_n,
            model.cost_all, goal, v, p, 0)
    assert learned_value(*args, 0) == pytest.approx(45.0)
    assert learned_value(*args, 1) == pytest.approx(-7.0)


def test_a_problem_on_its_own_scale_tells_the_learners():
    from gdq_pddl.envs.pddl_env import load_instance
    from gdq_pddl.learners import make_learner, pddl_task_context

    for problem, own in (("courier-1", True), ("lift-1", False)):
        ctx = pddl_task_context(load_instance(problem.split("-")[0], problem))
        assert ctx.own_scale is own
        assert make_learner("GDQ", ctx).params.own_scale == float(own)


def test_the_prior_step_cost_keeps_every_plan_within_the_limit_worth_doing_on_own_scale():
    """On a problem's own scale a step may cost nothing: the prior's step cost is capped
    at r_max / step_limit there (unchanged on the goal scale), with or without the file's
    rewards."""
    from dataclasses import replace

    from gdq_pddl.envs.pddl_env import load_instance
    from gdq_pddl.learners import make_learner, pddl_task_context
    from gdq_pddl.learners.gdq_learner import prior_step_cost

    ctx = pddl_task_context(load_instance("courier", "courier-2"))
    assert ctx.own_scale and ctx.step_limit == 20 and ctx.r_max == 20.0
    assert prior_step_cost(1.0, ctx) == 1.0
    assert prior_step_cost(1.0, replace(ctx, prior_reward=None)) == 1.0
    small = replace(ctx, r_max=1.0)  # an IPPC goal reward of 1
    assert prior_step_cost(1.0, small) == pytest.approx(1.0 / 20)
    assert make_learner("GDQ", small).params.prior_cost == pytest.approx(1.0 / 20)
    goal_scale = pddl_task_context(load_instance("lift", "lift-2"))
    assert prior_step_cost(1.0, replace(goal_scale, r_max=1.0)) == 1.0


TOLL = """(define (domain toll) (:requirements :typing :rewards :probabilistic-effects)
  (:types site)
  (:predicates (at ?s - site) (link ?x ?y - site) (bus ?x ?y - site) (dash ?x ?y - site))
  (:functions (fee ?x ?y - site) (bonus ?x ?y - site))
  (:action go :parameters (?x ?y - site) :precondition (and (at ?x) (link ?x ?y))
    :effect (and (decrease (reward) (fee ?x ?y))
                 (probabilistic 1/2 (and (at ?y) (not (at ?x))))))
  (:action dash :parameters (?x ?y - site) :precondition (and (at ?x) (dash ?x ?y))
    :effect (probabilistic 1/2 (and (at ?y) (not (at ?x)) (decrease (reward) 5))
                           1/2 (increase (reward) 2)))
  (:action ride :parameters (?x ?y - site) :precondition (and (at ?x) (bus ?x ?y))
    :effect (and (at ?y) (not (at ?x)) (increase (reward) (bonus ?x ?y)))))
"""


def _toll(tmp_path, back: int | None):
    """A toll problem: from a, walk to the goal g for 3 (half the time nothing happens),
    or ride to b, paid 4, then walk for 1, or dash (reaching g costs 5, failing pays 2);
    ``back``: a bus from b to a paying that."""
    from gdq_pddl.envs.pddl_env import PDDLInstance
    from gdq_pddl.learners import pddl_task_context

    extra = "" if back is None else f"(bus b a) (= (bonus b a) {back})"
    (tmp_path / "toll.pddl").write_text(TOLL)
    (tmp_path / "p.pddl").write_text(f"""(define (problem p) (:domain toll)
      (:objects a b g - site)
      (:init (at a) (link a g) (bus a b) (link b g) (dash b g) {extra}
             (= (fee a g) 3) (= (fee b g) 1) (= (bonus a b) 4))
      (:goal (at g)) (:goal-reward 10) (:metric maximize (reward)))""")
    inst = PDDLInstance.from_files(tmp_path / "toll.pddl", tmp_path / "p.pddl")
    ctx = pddl_task_context(inst)
    at = {x: s for s in range(ctx.n_states) for x in "abg" if f"at {x}" in inst.state_name(s)}
    return ctx, at


@pytest.mark.parametrize("back", [None, 1])
def test_the_prior_on_the_own_scale_pays_the_files_rewards(tmp_path, back):
    """Hand-derived (gamma 0.95, goal reward 10, the flat cost c = min(1, 10 / step
    limit) besides): the prior pays each pair the most any of its outcomes pays, and
    reaches the successor closest to the goal. From b: walk -1, dash 2 (its outcome that
    reaches g pays -5: the prior is optimistic in both), so V(b) = 2 - c + 10; from a:
    V(a) = max(-3 - c + 10, 4 - c + 0.95 V(b)) (the flat cost alone would prefer
    walking). A bus back paying 1 makes a loop that pays more: with x = 4 - c and
    y = 1 - c, V(a) = (x + 0.95 y) / (1 - 0.95**2), V(b) = max(12 - c, y + 0.95 V(a)).
    OptInit starts from them (one sweep)."""
    ctx, at = _toll(tmp_path, back)
    assert ctx.own_scale and ctx.prior_reward is not None
    learner = GDQ(ctx)
    t, p = learner.tables, learner.params
    c = min(1.0, 10.0 / ctx.step_limit)
    assert p.prior_cost == c and t.prior.reward.shape == (ctx.n_states, ctx.n_actions)
    a, b = at["a"], at["b"]
    assert sorted(t.prior.reward[a][ctx.live[a]]) == [-3.0, 4.0]
    assert sorted(t.prior.reward[b][ctx.live[b]]) == ([-1.0, 2.0] if back is None
                                                      else [-1.0, 1.0, 2.0])
    if back is None:
        want_b = 12 - c
        want_a = max(7 - c, 4 - c + 0.95 * want_b)
    else:
        x, y = 4 - c, 1 - c
        want_a = (x + 0.95 * y) / (1 - 0.95 ** 2)
        want_b = y + 0.95 * want_a
        assert want_b > 12 - c
    assert learner.v[a] == pytest.approx(want_a, abs=1e-9)
    assert learner.v[b] == pytest.approx(want_b, abs=1e-9)
    init = warm_start.prior_values(t.table, t.prior, p)
    assert init[a] == pytest.approx(want_a, abs=1e-9) and init[at["g"]] == 0.0
    assert gdq.value_iteration(t.table, t.model, t.prior, t.queue, p, 1e-9, 1000) == 1
    walk = int(np.flatnonzero(t.prior.reward[a] == -3.0)[0])
    assert learner.q[a, walk] == pytest.approx(7.0 - c)  # -3 - c + 10: the goal pays besides


def test_a_goal_scale_learner_keeps_the_flat_prior():
    """Without the file's rewards the prior is the flat cost's: no reward array, and
    OptInit's values the closed form by goal distance, R_max at one step."""
    from gdq_pddl.envs.pddl_env import load_instance
    from gdq_pddl.learners import pddl_task_context

    inst = load_instance("lift", "lift-1")
    ctx = pddl_task_context(inst)
    assert not ctx.own_scale and ctx.prior_reward is None
    learner = GDQ(ctx)
    t, p = learner.tables, learner.params
    assert t.prior.reward.shape == (0, 0) and p.prior_cost == 1.0
    d = inst.graph.distances
    want = np.where(d == 0, 0.0, np.where(d < 0, -1.0 / (1 - p.gamma), 0.0))
    for s in np.flatnonzero(d > 0):
        x = p.r_max
        for _ in range(d[s] - 1):
            x = -1.0 + p.gamma * x
        want[s] = x
    assert np.array_equal(learner.v, want)


def test_a_context_refuses_file_rewards_off_the_own_scale(ctx_c):
    with pytest.raises(ConfigError, match="own_scale"):
        GDQ(replace(ctx_c, prior_reward=np.zeros((ctx_c.n_states, ctx_c.n_actions))))
