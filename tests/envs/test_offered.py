"""Tables sized by what is applicable: a PDDL state offers its applicable ground actions,
and the true model, the prior, the plan tables and the learners are over those columns."""

from __future__ import annotations

import numpy as np
import pytest

from gdq_pddl.envs.pddl_env import PDDLEnv, load_instance
from gdq_pddl.envs.step import env_act, env_step
from gdq_pddl.learners import make_learner, pddl_task_context
from gdq_pddl.pddl.offered import column_of

SHIPPED = [("keys", "keys-1"), ("lift", "lift-2"), ("courier", "courier-2"),
           ("keys-ppddl", "keys-ppddl-1"), ("delivery", "delivery-1")]


@pytest.fixture(scope="module", params=SHIPPED, ids=[p for _, p in SHIPPED])
def inst(request):
    return load_instance(*request.param)


def test_a_state_offers_exactly_its_applicable_ground_actions(inst):
    graph = inst.graph
    for s in range(graph.n_states):
        row = graph.offered[s]
        live = row[row >= 0].tolist()
        if graph.is_goal[s]:
            assert live == [0]
            continue
        applicable = sorted({graph.op_index[op.name]
                             for op in graph.task.applicable(graph.states[s])}) \
            if hasattr(graph.task, "applicable") else None
        edges = sorted({op for op, _ in graph.edges(s)})
        assert set(edges) <= set(live)  # every planner edge is an offered action
        if applicable is not None:
            assert live == (applicable or [0])
        assert live == sorted(live) and (row[len(live):] == -1).all()


def test_column_of_inverts_the_rows():
    offered = np.array([[1, 5, -1], [2, -1, -1], [0, 3, 7], [0, -1, -1]])  # the layout
    s, j = np.nonzero(offered >= 0)
    assert (column_of(offered, s, offered[s, j]) == j).all()
    assert column_of(offered, np.array([0, 1, 2, 3]), np.array([2, 5, 1, 9])).tolist() == \
        [-1, -1, -1, 0 if offered[3, 0] == 9 else -1]


def test_the_true_model_is_over_the_offered_columns(inst):
    m = inst.model
    width = inst.columns.shape[1]
    assert m.acts.shape == inst.columns.shape and len(m.ptr) == inst.n_states * width + 1
    counts = np.diff(m.ptr).reshape(inst.n_states, width)
    assert ((counts > 0) == (inst.columns >= 0)).all()  # padding lists no outcome


def test_env_step_of_an_action_is_the_step_of_its_column(inst):
    m, cols = inst.model, inst.columns
    s = inst.start_state
    for j in np.flatnonzero(cols[s] >= 0):
        a = int(cols[s, j])
        one = env_act(m, s, a, 0, inst.goal_pos, np.random.default_rng(7))
        other = env_step(m, s, int(j), 0, inst.goal_pos, np.random.default_rng(7))
        assert one == other


def test_an_inapplicable_action_changes_nothing_at_its_cost(inst):
    m, cols = inst.model, inst.columns
    s = inst.start_state
    a = next(a for a in range(inst.n_actions) if a not in cols[s])
    rng = np.random.default_rng(3)
    fs, r, terminated, truncated, _ = env_act(m, s, a, 0, inst.goal_pos, rng)
    assert fs == s and not terminated and not truncated
    assert r == pytest.approx(-inst.costs[a].a) or inst.costs[a].kind != "const"
    env = PDDLEnv(instance=inst)
    env.reset(seed=0)
    obs, _, _, _, info = env.step(a)
    assert obs == s and info["action_mask"][a] == 0


def test_learners_act_and_learn_in_env_actions(inst):
    ctx = pddl_task_context(inst)
    assert ctx.n_actions == inst.columns.shape[1] and ctx.n_env_actions == inst.n_actions
    rng = np.random.default_rng(0)
    for method in ("Q-learning", "DARLING", "GDQ"):
        learner = make_learner(method, ctx)
        s = ctx.s0
        for _ in range(30):
            a = learner.act(s, rng)
            assert a in inst.columns[s]  # an applicable ground action
        policy = learner.greedy_policy()
        live = [set(row[row >= 0].tolist()) for row in inst.columns]
        assert all(int(a) in live[s] for s, a in enumerate(policy))
        bad = next(a for a in range(inst.n_actions) if a not in inst.columns[s])
        with pytest.raises(ValueError, match="not offered in state"):
            learner.observe(s, bad, -1.0, s, False, False, rng)


def test_the_prior_is_each_offered_actions_edge_closest_to_the_goal(inst):
    """prior_from_graph against its definition, state by state: per offered action, the
    planner edge closest to the goal (ties: the lowest state), else no change."""
    graph = inst.graph
    dist = np.where(graph.distances < 0, np.inf, graph.distances)
    prior = inst.prior.next_state
    assert prior.shape == graph.offered.shape
    for s in range(graph.n_states):
        best: dict[int, int] = {}
        for op, nxt in graph.edges(s):
            if op not in best or (dist[nxt], nxt) < (dist[best[op]], best[op]):
                best[op] = nxt
        want = [best.get(int(a), -1) for a in graph.offered[s]]
        assert prior[s].tolist() == want


def test_a_context_with_broken_columns_is_refused():
    from dataclasses import replace

    ctx = pddl_task_context(load_instance("keys", "keys-1"))
    holes = ctx.columns.copy()
    holes[3, 0] = -1  # a row that starts with padding
    for bad in (holes, ctx.columns[:, :1].copy(), ctx.columns.astype(np.int32)):
        with pytest.raises(ValueError, match="TaskContext.columns"):
            make_learner("Q-learning", replace(ctx, columns=bad))
