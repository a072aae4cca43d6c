"""The knowledge baselines of issue 36 against hand values: shaping is potential-based (the
discounted shaping terms of any episode telescope), the potentials, R-max's known-pair
threshold and optimism on a two-state MDP, FF-Replan's shortest first plan and its
replanning, and each compiled rule against a plain-Python reference on random steps."""

from __future__ import annotations

import numba
import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from gdq_pddl.abstraction.prior import PriorModel
from gdq_pddl.abstraction.table import pack_plans
from gdq_pddl.envs.office import OfficeEnv
from gdq_pddl.errors import ConfigError
from gdq_pddl.learners import learned_model, make_learner
from gdq_pddl.learners.context import TaskContext
from gdq_pddl.learners.registry import parse_method
from gdq_pddl.learners.replan import NO_PLAN, FFReplan
from gdq_pddl.learners.rmax import RMax, RMaxShaping, now_known, plan_known
from gdq_pddl.learners.shaping import (
    distance_potential,
    goal_distances,
    observe_q,
    plan_step_potential,
    shaped_value,
    shaping_term,
)
from tests.helpers import Recording, run

NEW = ("Q-shaping", "Dyna-Q-shaping", "Plan-shaping", "R-max", "R-max-shaping", "FF-Replan")


def tiny_context(n_states: int, n_actions: int, goal: list[int], length: list[int],
                 s0: int = 0, r_max: float = 10.0, horizon: int | None = 20,
                 next_state: np.ndarray | None = None) -> TaskContext:
    """A hand-built task: ``length[s]`` the knowledge's goal distance (-1: none)."""
    g = np.zeros(n_states, dtype=np.bool_)
    g[goal] = True
    plans = pack_plans(n_actions, [[] for _ in range(n_states)],
                       np.asarray(length, dtype=np.int64), False)
    prior = None if next_state is None else PriorModel(np.asarray(next_state, dtype=np.int64))
    return TaskContext(s0=s0, goal=g, plans=plans, r_max=r_max, horizon=horizon, prior=prior)


# --- shaping is potential-based ------------------------------------------------------------

@settings(max_examples=200, deadline=None)
@given(st.lists(st.integers(0, 7), min_size=2, max_size=30),
       st.lists(st.floats(-50, 50), min_size=8, max_size=8),
       st.floats(0.0, 0.999), st.booleans())
def test_shaping_terms_of_any_episode_sum_to_the_potential_difference(states, phi, gamma,
                                                                      terminated):
    phi = np.array(phi)
    total = 0.0
    for t in range(len(states) - 1):
        last = t == len(states) - 2
        total += gamma ** t * shaping_term(phi, gamma, states[t], states[t + 1],
                                           terminated and last)
    end = 0.0 if terminated else phi[states[-1]]
    big_t = len(states) - 1
    assert total == pytest.approx(gamma ** big_t * end - phi[states[0]], abs=1e-9)


def test_the_potentials_by_hand():
    # distances 3, 2, 1, 0 (goal), none: the none is the step limit, 20
    ctx = tiny_context(5, 2, goal=[3], length=[3, 2, 1, 0, -1])
    assert goal_distances(ctx).tolist() == [3, 2, 1, 0, 20]
    assert distance_potential(ctx, 0.5).tolist() == [-1.5, -1.0, -0.5, -0.0, -10.0]
    # L = d(s0) = 3, w = r_max / L = 10 / 3: steps 0, 1, 2, 3 and 0 (farther than s0)
    w = 10.0 / 3
    assert plan_step_potential(ctx, 1.0) == pytest.approx([0, w, 2 * w, 3 * w, 0])
    no_limit = tiny_context(5, 2, goal=[3], length=[3, 2, 1, 0, -1], horizon=None)
    assert goal_distances(no_limit)[4] == 5  # the number of states


def test_scale_zero_is_the_unshaped_learner_bit_for_bit(ctx_c):
    env = OfficeEnv(task="C")
    for shaped, plain in (("Q-shaping:scale=0", "Q-learning"),
                          ("Dyna-Q-shaping:scale=0", "Dyna-Q")):
        a = Recording(make_learner(shaped, ctx_c))
        b = Recording(make_learner(plain, ctx_c))
        run(a, env, 40, 3, fast=False)
        run(b, env, 40, 3, fast=False)
        assert a.actions == b.actions
        assert np.array_equal(a.q, b.q)


# --- each compiled rule equals a plain-Python reference -----------------------------------

def test_q_shaping_rule_equals_its_reference_on_random_steps(ctx_c):
    rng = np.random.default_rng(4)
    for method in ("Q-shaping:scale=0.7", "Plan-shaping"):
        learner = make_learner(method, ctx_c)
        t, p = learner.tables, learner.params
        t.table.q[:] = rng.normal(size=t.table.q.shape)
        learner.tables.table.v[:] = t.table.q.max(axis=1)  # every action allowed
        phi = learner.phi
        for _ in range(200):
            s, a, s2 = rng.integers(31), rng.integers(95), rng.integers(31)
            r, term, trunc = rng.normal(), bool(rng.random() < 0.2), bool(rng.random() < 0.1)
            q0 = t.table.q[s, a]
            f = (0.0 if term else p.gamma * phi[s2]) - phi[s]
            boot = 0.0 if (term or trunc) else p.gamma * t.table.q[s2].max()
            want = q0 + p.alpha * (r + f + boot - q0)
            observe_q(*t, p, s, a, r, s2, term, trunc, rng)
            assert t.table.q[s, a] == pytest.approx(want, abs=1e-12)
            assert t.table.v[s] == pytest.approx(t.table.q[s].max())


def test_dyna_q_shaping_backup_equals_its_reference(ctx_c):
    rng = np.random.default_rng(5)
    learner = make_learner("Dyna-Q-shaping:scale=2", ctx_c)
    env = OfficeEnv(task="C")
    run(learner, env, 30, 1, fast=False)
    t, p, phi = learner.tables, learner.params, learner.phi
    counts = learned_model.dense_counts(t.model.slots, 31)
    tried = np.argwhere(t.model.visits > 0)
    for s, a in tried[rng.choice(len(tried), 40)]:
        n = t.model.visits[s, a]
        c = learned_model.mean_cost(t.model.cost_sum, t.model.cost_n, t.model.cost_all, s, a)
        want = t.model.stuck[s, a] * -p.r_max
        for s2 in np.flatnonzero(counts[s, a]):
            k = counts[s, a, s2]
            if t.table.goal[s2]:
                want += k * p.r_max  # a terminal successor: phi 0
            else:
                want += k * (-c + p.gamma * t.table.v[s2] + p.gamma * phi[s2])
        want = want / n - phi[s]
        assert shaped_value(t.table, t.model, phi, p, s, a) == pytest.approx(want, abs=1e-9)


# --- R-max on a two-state MDP --------------------------------------------------------------
# state 0 (start), state 1 (goal, r_max = 10); action 0 reaches the goal or stays, action 1
# stays at cost 1; gamma 0.95, V_max = r_max = 10.

def _two_state(method: str = "R-max:m=2"):
    ctx = tiny_context(2, 2, goal=[1], length=[3, 0], r_max=10.0)
    return make_learner(method, ctx, gamma=0.95), np.random.default_rng(0)


def test_rmax_unknown_pairs_are_worth_v_max_until_tried_m_times():
    learner, rng = _two_state()
    assert learner.q[0].tolist() == [10.0, 10.0]
    learner.observe(0, 1, -1.0, 0, False, False, rng)  # one trial of m = 2: still unknown
    assert learner.q[0].tolist() == [10.0, 10.0]
    learner.observe(0, 1, -1.0, 0, False, False, rng)  # known: -1 + 0.95 * V(0), V(0) = 10
    assert learner.q[0, 1] == pytest.approx(-1 + 0.95 * 10)
    assert learner.q[0, 0] == 10.0  # still optimistic


def test_rmax_plans_on_the_known_model_by_hand():
    learner, rng = _two_state()
    for _ in range(2):
        learner.observe(0, 1, -1.0, 0, False, False, rng)
    learner.observe(0, 0, 10.0, 1, True, False, rng)
    learner.observe(0, 0, -1.0, 0, False, False, rng)
    # Q(0,0) = 1/2 * 10 + 1/2 * (-1 + 0.95 V), V = Q(0,0): V = 4.5 / 0.525
    v = 4.5 / 0.525
    assert learner.q[0, 0] == pytest.approx(v, abs=1e-5)
    assert learner.q[0, 1] == pytest.approx(-1 + 0.95 * v, abs=1e-5)
    assert learner.greedy_policy()[0] == 0
    assert learner.sweeps > 0


def test_rmax_shaping_values_unknown_pairs_by_the_potential():
    learner, _ = _two_state("R-max-shaping:m=2,scale=1.5")
    # d(0) = 3: Phi(0) = V_max - 1.5 * (3 - 1) = 7
    assert learner.q[0].tolist() == [7.0, 7.0]
    assert isinstance(learner, RMaxShaping)


def test_rmax_m_below_one_is_refused():
    with pytest.raises(ConfigError, match="m must be"):
        parse_method("R-max:m=0")


def test_rmax_planning_equals_plain_value_iteration(ctx_c):
    learner = make_learner("R-max:m=1", ctx_c)
    run(learner, OfficeEnv(task="C"), 20, 2, fast=False)
    t, p = learner.tables, learner.params
    counts = learned_model.dense_counts(t.model.slots, 31)
    q = t.table.q.copy()
    for _ in range(2000):  # plain value iteration from the learner's values
        v = np.where(t.table.goal, 0.0, q.max(axis=1))
        new = np.empty_like(q)
        for s in range(31):
            for a in range(95):
                n = t.model.visits[s, a]
                if n < 1:
                    new[s, a] = t.own.unknown[s]
                    continue
                c = learned_model.mean_cost(t.model.cost_sum, t.model.cost_n,
                                            t.model.cost_all, s, a)
                x = t.model.stuck[s, a] * -p.r_max
                for s2 in np.flatnonzero(counts[s, a]):
                    x += counts[s, a, s2] * (p.r_max if t.table.goal[s2]
                                             else -c + p.gamma * v[s2])
                new[s, a] = x / n
        new[t.table.goal] = q[t.table.goal]
        if np.abs(new - q).max() < 1e-10:
            break
        q = new
    plan_known(t.table, t.model, t.own, p, 1e-12, 5000)
    live = ~t.table.goal
    assert np.allclose(t.table.q[live], q[live], atol=1e-6)


def _plan_every_state(q, v, allowed, goal, model, unknown, p, tolerance, max_sweeps):
    """Gauss-Seidel value iteration visiting every state in every sweep (plan_known as it
    was before it skipped the states without a known pair), in plain Python."""
    done = 0
    for _ in range(max_sweeps):
        done += 1
        change = 0.0
        for s in range(q.shape[0]):
            if goal[s]:
                continue
            best = -np.inf
            for a in range(q.shape[1]):
                if not allowed[s, a]:
                    continue
                if model.visits[s, a] > p.m:
                    x = learned_model.learned_value(
                        model.slots, model.stuck, model.visits, model.cost_sum,
                        model.cost_n, model.cost_all, goal, v, p, s, a)
                else:
                    x = unknown[s]
                change = max(change, abs(x - q[s, a]))
                q[s, a] = x
                best = max(best, x)
            v[s] = best
        if change <= tolerance:
            break
    return done


@pytest.mark.parametrize("method", ["R-max:m=1", "R-max-shaping:m=2"])
def test_rmax_planning_skips_unknown_states_to_the_bit(ctx_c, method):
    # after some episodes few states have a known pair; then every unknown value moves, so
    # the first sweep changes every state and the later ones propagate through the known
    learner = make_learner(method, ctx_c)
    run(learner, OfficeEnv(task="C"), 15, 3, fast=False)
    t, p = learner.tables, learner.params
    known = (t.model.visits > p.m) & t.table.allowed
    assert 0 < known.any(axis=1).sum() < (~t.table.goal).sum()  # some states skipped
    t.own.unknown[:] -= 1.5
    t.own.planned[1] = 0  # U changed outside planning: the next plan visits every state
    q, v = t.table.q.copy(), t.table.v.copy()
    want = _plan_every_state(q, v, t.table.allowed, t.table.goal, t.model, t.own.unknown, p,
                             1e-12, 400)
    before = learner.sweeps
    got = plan_known(t.table, t.model, t.own, p, 1e-12, 400)
    assert got == want > 2 and learner.sweeps == before + got
    assert t.table.q.tobytes() == q.tobytes() and t.table.v.tobytes() == v.tobytes()


@numba.njit
def _observe_full_first(table, model, plans, prior, queue, own, p, s, a, r, s2, terminated,
                        truncated, rng):
    """R-max's observe with every plan's first sweep over every state (as before the
    known states were kept between plans)."""
    if not learned_model.record(model, table.goal, p, s, a, r, s2, terminated, truncated):
        return False
    if model.visits[s, a] == p.m + 1:
        own.planned[1] = 0
        plan_known(table, model, own, p, p.sweep_threshold, p.n_backups)
    return True


class _RMaxFullFirst(RMax):
    observe_rule = staticmethod(_observe_full_first)
    loop_rules = None


class _RMaxShapingFullFirst(RMaxShaping):
    observe_rule = staticmethod(_observe_full_first)
    loop_rules = None


@pytest.mark.parametrize("method, reference", [("R-max", _RMaxFullFirst),
                                               ("R-max-shaping", _RMaxShapingFullFirst)])
def test_rmax_known_states_kept_between_plans_to_the_bit(ctx_c, method, reference):
    learner = make_learner(method, ctx_c)
    full = reference(ctx_c, learner.config)
    a = run(learner, OfficeEnv(task="C"), 30, 4, fast=False)
    b = run(full, OfficeEnv(task="C"), 30, 4, fast=False)
    assert a.returns.tobytes() == b.returns.tobytes()
    assert learner.q.tobytes() == full.q.tobytes() and learner.sweeps == full.sweeps
    own = learner.tables.own
    n = own.planned[0]
    has_known = ((learner.tables.model.visits > learner.params.m)
                 & learner.tables.table.allowed).any(axis=1)
    assert own.planned[1] == 1 and own.known_states[:n].tolist() == \
        np.flatnonzero(has_known).tolist()


def test_rmax_now_known_keeps_the_states_ascending_once_each():
    own = RMax(tiny_context(6, 2, goal=[5], length=[1, 1, 1, 1, 1, 0])).tables.own
    own.planned[:] = (0, 1)
    for s in (3, 1, 4, 1, 0, 3):
        now_known(own, s)
    assert own.planned[0] == 4 and own.known_states[:4].tolist() == [0, 1, 3, 4]
    own.planned[:] = (0, 0)  # no list kept: the next plan makes it
    now_known(own, 2)
    assert own.planned[0] == 0


def test_rmax_is_refused_nothing_and_acts_greedily(ctx_c):
    learner = make_learner("R-max", ctx_c, epsilon=0.0)
    assert learner.config.epsilon == 0.0
    with pytest.raises(ConfigError, match="epsilon"):
        parse_method("R-max:epsilon=0.1")
    assert isinstance(learner, RMax)


# --- FF-Replan -----------------------------------------------------------------------------

def test_ff_replan_first_plan_is_a_shortest_plan(ctx_c):
    learner = make_learner("FF-Replan", ctx_c)
    assert isinstance(learner, FFReplan)
    plan = learner.plan(ctx_c.s0)
    assert len(plan) == ctx_c.plans.length[ctx_c.s0]
    s = ctx_c.s0
    for a in plan:  # it reaches the goal on the knowledge's successors
        assert ctx_c.plans.first_actions[s, a]
        s = int(ctx_c.prior.next_state[s, a])
    assert ctx_c.goal[s]
    assert learner.act(ctx_c.s0, np.random.default_rng(0)) == plan[0]


def test_ff_replan_replans_after_a_deviation():
    # a chain 0 -> 1 -> 2 (goal) by action 0; action 1 does nothing
    nxt = np.array([[1, -1], [2, -1], [-1, -1]])
    ctx = tiny_context(3, 2, goal=[2], length=[2, 1, 0], next_state=nxt)
    learner = make_learner("FF-Replan", ctx)
    rng = np.random.default_rng(0)
    assert learner.plan(0) == [0, 0]
    assert learner.act(0, rng) == 0
    learner.observe(0, 0, -1.0, 1, False, False, rng)  # as planned
    assert learner.replans == 0
    learner.observe(1, 0, -1.0, 0, False, False, rng)  # slipped back: replan from 0
    assert learner.replans == 1
    assert learner.act(0, rng) == 0 and learner.plan(0) == [0, 0]
    learner.observe(1, 0, 10.0, 2, True, False, rng)  # the goal ends it: no replan
    assert learner.replans == 1


def test_ff_replan_without_a_plan_acts_at_random():
    nxt = np.array([[-1, -1], [-1, -1]])
    ctx = tiny_context(2, 2, goal=[1], length=[-1, 0], next_state=nxt)
    learner = make_learner("FF-Replan", ctx)
    assert learner.q[0, 0] == -(1.0 + NO_PLAN)
    rng = np.random.default_rng(1)
    assert {learner.act(0, rng) for _ in range(50)} == {0, 1}


def test_ff_replan_refuses_another_determinisation(ctx_c):
    from dataclasses import replace
    ctx = replace(ctx_c, determinisation="all-outcomes")
    with pytest.raises(ConfigError, match="determinisation"):
        make_learner("FF-Replan:determinisation=most-likely", ctx)


# --- every new learner runs, compiled and in Python, with the same results ----------------

@pytest.mark.parametrize("method", NEW)
def test_compiled_loop_equals_python_loop(ctx_c, method):
    env = OfficeEnv(task="C")
    out = []
    for fast in (True, False):
        learner = make_learner(method, ctx_c)
        rec = run(learner, env, 30, 7, fast=fast)
        out.append((rec.returns.copy(), learner.q.copy()))
    assert np.array_equal(out[0][0], out[1][0])
    assert np.array_equal(out[0][1], out[1][1])


@pytest.mark.parametrize("method", NEW)
def test_a_task_switch_rebuilds_the_knowledge(ctx_c, method):
    from gdq_pddl.learners import office_task_context
    from tests.learners.learning import WORLD

    learner = make_learner(method, ctx_c)
    run(learner, OfficeEnv(task="C"), 5, 2, fast=False)
    ctx_d = office_task_context(WORLD, "D")
    learner.start_task(ctx_d)
    if hasattr(learner, "phi"):
        assert np.array_equal(learner.phi, learner._potential(ctx_d))
    if isinstance(learner, FFReplan):
        assert len(learner.plan(ctx_d.s0)) == ctx_d.plans.length[ctx_d.s0]
    rec = run(learner, OfficeEnv(task="D"), 5, 3, fast=False)
    assert len(rec) == 5
