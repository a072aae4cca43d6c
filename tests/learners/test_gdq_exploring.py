"""GDQ's exploring steps: the actions near the state's best value (``explore="values"``),
loop-free (``explore_loops``), and the share that tries untried actions (``explore_all``)
where the knowledge may lack some."""

from __future__ import annotations

from dataclasses import replace

import numpy as np
import pytest

from gdq_pddl.abstraction.prior import NO_CHANGE
from gdq_pddl.envs.office import OfficeEnv
from gdq_pddl.learners import GDQ, GDQConfig
from gdq_pddl.learners.gdq import act, act_reference
from tests.helpers import run


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


@pytest.mark.parametrize("settings", [
    {"explore_all": 0.0}, {"explore_all": 0.5}, {"explore_all": 0.5, "explore_all_last": 0.0},
    {"explore_loops": 0.0}, {"explore_loops": 0.0, "explore_band": 2.0},
    {"explore_band": -1.0}, {"epsilon": 1.0, "explore_all": 1.0, "explore_all_last": 0.0}])
def test_the_compiled_acting_rule_equals_its_plain_python_reference(ctx_c, settings):
    """GDQ's ``act`` (compiled) and ``act_reference`` (plain Python) draw the same action
    from the same generator, and leave it in the same state, in every state of a learner
    part-way through learning (ties, tried and untried pairs), with the band, loop-free
    draws, ``explore_all``, last-step sparing and dead ends (a third of the pairs made
    certain dead ends in the prior) each on and off."""
    learner = GDQ(ctx_c)
    run(learner, OfficeEnv(task="C"), 15, 3)
    t = learner.tables
    p = learner.params._replace(**({"epsilon": 0.5} | settings))
    dead = np.where(np.random.default_rng(1).random(t.table.q.shape) < 0.3, 1.0, 0.0)
    for prior in (t.prior, t.prior._replace(dead=dead)):
        for seed in range(6):
            fast, plain = np.random.default_rng(seed), np.random.default_rng(seed)
            for s in np.flatnonzero(~t.table.goal):
                a = act(t.table, t.model.visits, prior, p, int(s), fast)
                assert a == act_reference(t.table, t.model.visits, prior, p, int(s), plain)
            assert fast.bit_generator.state == plain.bit_generator.state
