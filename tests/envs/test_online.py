"""A PPDDL problem explored online (gdq_pddl.envs.online, gdq_pddl.learners.online): the
env steps exactly as the enumerated env does, Q-learning learns exactly as on the
enumerated problem, the rows of frontier and chain states carry the estimates, a
learner keeps what it learned when the arrays grow, and the command line falls back to
online exploration where the states do not fit."""

from __future__ import annotations

import json
from dataclasses import replace

import numpy as np
import pytest

from gdq_pddl.cli import main
from gdq_pddl.envs.online import ESTIMATE, OnlineInstance
from gdq_pddl.envs.online_env import OnlineEnv
from gdq_pddl.envs.pddl_env import PDDLEnv, PDDLInstance, load_instance
from gdq_pddl.errors import ConfigError, PlanningError, SizeError
from gdq_pddl.experiments.protocol import Experiment, ProblemSpec
from gdq_pddl.experiments.work import instance_of
from gdq_pddl.learners import make_learner, pddl_task_context, run_episodes
from gdq_pddl.learners.agents import learner_class
from gdq_pddl.learners.learned_model import new_model, resized
from gdq_pddl.learners.online import online_context
from gdq_pddl.planning.heuristic import INFINITE, hadd_for, hff_for
from gdq_pddl.resources import resolve_pddl
from tests.helpers import expanded_rows

PPDDL = [("keys-ppddl", "keys-ppddl-1"), ("lift", "lift-1"), ("courier", "courier-1"),
         ("courier", "courier-2")]


def shipped(domain: str, problem: str) -> PDDLInstance:
    return load_instance(domain, problem)


def twins(domain: str, problem: str) -> tuple[PDDLInstance, OnlineInstance]:
    """The enumerated instance and an online one with its reality constants."""
    base = shipped(domain, problem)
    return base, OnlineInstance(base, dynamics=base.dynamics)


@pytest.mark.parametrize("domain,problem", PPDDL)
def test_online_env_steps_as_the_enumerated_env(domain: str, problem: str) -> None:
    base, online = twins(domain, problem)
    a, b = PDDLEnv(instance=base), OnlineEnv(online)
    pick = np.random.default_rng(7)
    for episode in range(30):
        a.reset(seed=episode)
        b.reset(seed=episode)
        done = False
        while not done:
            mask = a.action_masks()
            act = int(pick.choice(np.flatnonzero(mask))) if pick.random() < 0.9 else \
                int(pick.integers(base.n_actions))
            s1, r1, t1, u1, i1 = a.step(act)
            s2, r2, t2, u2, i2 = b.step(act)
            assert base.atoms(s1) == online.atoms(s2)
            assert (r1, t1, u1, i1["cause"]) == (r2, t2, u2, i2["cause"])
            assert np.array_equal(i1["action_mask"], i2["action_mask"][:base.n_actions])
            done = t1 or u1


@pytest.mark.parametrize("domain,problem", PPDDL)
def test_q_learning_online_learns_as_on_the_enumerated_problem(domain: str,
                                                                problem: str) -> None:
    base, online = twins(domain, problem)
    enumerated = make_learner("Q-learning", pddl_task_context(base))
    found = make_learner("Q-learning", online_context(online))
    a, b = PDDLEnv(instance=base), OnlineEnv(online)
    a.reset(seed=3)
    b.reset(seed=3)
    ra = run_episodes(enumerated, a, 60, np.random.default_rng(5))
    rb = run_episodes(found, b, 60, np.random.default_rng(5))
    assert np.array_equal(ra.returns, rb.returns) and np.array_equal(ra.steps, rb.steps)
    for row in range(online.n_rows):  # the same Q for the same state, action by action
        x = online.state_of(row)
        if x < 0 or not online.graph.expanded[x]:
            continue
        s = base.graph.index[online.graph.mask(x)]
        live = online.columns[row] >= 0
        assert np.array_equal(online.columns[row][live], base.columns[s][base.columns[s] >= 0])
        assert np.allclose(found.q[row][live], enumerated.q[s][:live.sum()])


@pytest.mark.parametrize("method", ["Q-learning", "Dyna-Q"])
@pytest.mark.parametrize("domain,problem", [("courier", "courier-2"), ("lift", "lift-2")])
def test_learners_without_knowledge_learn_the_same_without_estimates(method, domain, problem):
    """A run of a learner that reads no knowledge estimates no state (the estimates were
    most of its time on large problems) and learns exactly as with them."""
    base = shipped(domain, problem)
    assert not learner_class(method).reads_knowledge
    assert learner_class("GDQ").reads_knowledge and learner_class("darling").reads_knowledge
    runs = []
    for estimate in ("h_add", None):
        online = OnlineInstance(base, estimate=estimate)
        learner = make_learner(method, online_context(online))
        env = OnlineEnv(online)
        env.reset(seed=4)
        result = run_episodes(learner, env, 40, np.random.default_rng(2))
        q = {online.graph.mask(x): learner.q[online.row_of_state[x]].copy()
             for x in range(online.graph.n_states) if online.graph.expanded[x]}
        runs.append((online, result, q))
    (with_h, a, qa), (without, b, qb) = runs
    assert without.h_start == with_h.h_start
    assert without.dynamics.step_limit == with_h.dynamics.step_limit
    assert np.array_equal(a.returns, b.returns) and np.array_equal(a.steps, b.steps)
    assert qa.keys() == qb.keys() and all(np.array_equal(qa[m], qb[m]) for m in qa)
    found = without.h_of[:without.graph.n_states]
    assert set(found[~without.graph.is_goal].tolist()) <= {INFINITE}  # none estimated
    assert (with_h.h_of[:with_h.graph.n_states] > 0).any()


def test_weighted_estimates_stand_further_from_the_goal() -> None:
    """``estimate_weight`` w: a state not reached yet stands ceil(w h) from the goal; the
    step limit and the estimate from the start stay h_add's. GDQ reads its estimates so
    when run_unit makes its instance, DARLING as they are, Q-learning none."""
    base = shipped("courier", "courier-2")
    plain, weighted = OnlineInstance(base), OnlineInstance(base, estimate_weight=1.25)
    assert weighted.h_start == plain.h_start
    assert weighted.dynamics.step_limit == plain.dynamics.step_limit
    for online in (plain, weighted):
        env = OnlineEnv(online)
        env.reset(seed=1)
        run_episodes(make_learner("GDQ", online_context(online)), env, 10,
                     np.random.default_rng(1))
    h = hadd_for(weighted.task)
    g = weighted.graph
    found = np.flatnonzero(~g.is_goal)
    raw = h.many(g.words[found])
    assert (raw > 0).any()
    assert np.array_equal(weighted.h_of[found],
                          np.where(raw < 0, raw, np.ceil(1.25 * raw).astype(np.int64)))
    for bad in (0.5, float("nan")):
        with pytest.raises(ConfigError, match="estimate_weight"):
            OnlineInstance(base, estimate_weight=bad)
    domain, problem, _ = resolve_pddl("courier", "courier-2", None)
    exp = Experiment("run", (("courier-2", 5),), world="pddl",
                     pddl=ProblemSpec(str(domain), str(problem), exploration="online"))
    assert instance_of(exp, "courier-2", learner_class("GDQ")).estimate_weight == 1.25
    darling = instance_of(exp, "courier-2", learner_class("DARLING"))
    assert darling.estimates and darling.estimate_weight == 1.0
    assert not instance_of(exp, "courier-2", learner_class("Q-learning")).estimates


def test_own_scale_prior_rewards_are_the_enumerated_ones() -> None:
    base, online = twins("courier", "courier-2")
    enumerated = pddl_task_context(base).prior_reward
    env = OnlineEnv(online)
    run_episodes(make_learner("Q-learning", online_context(online)), env, 30,
                 np.random.default_rng(1))
    checked = 0
    for row, s, k in expanded_rows(online, base):
        assert np.allclose(online.prior_reward[row, :k], enumerated[s, :k])
        checked += 1
    assert checked > 5


def test_rows_carry_the_estimates() -> None:
    _, online = twins("lift", "lift-2")
    env = OnlineEnv(online)
    run_episodes(make_learner("Q-learning", online_context(online)), env, 5,
                 np.random.default_rng(2))
    n_ops, chain, g = online.n_ops, online.chain, online.graph
    assert online.goal[chain[0]] and not online.goal[chain[1:]].any()
    for k, r in enumerate(chain[1:], start=1):  # chain row k leads to chain row k - 1
        assert online.columns[r, 0] == n_ops and online.prior_next[r, 0] == chain[k - 1]
        assert online.dist[r] == k
    assert online.prior_next[online.dead, 0] < 0 and online.dist[online.dead] == -1
    assert online.action_name(n_ops) == ESTIMATE
    unreached = 0
    for r in range(online.n_rows):
        x = online.state_of(r)
        if x < 0 or g.is_goal[x]:
            continue
        assert g.expanded[x]  # a state with a row was reached, and expanded then
        op, nxt = g.edges(x)
        for j, a in enumerate(online.columns[r][online.columns[r] >= 0].tolist()):
            stands = set()  # what the prior successor of each outcome of a would be
            for y in nxt[op == a].tolist():
                if g.is_goal[y]:  # a goal's own row or the chain's: both pay R_max
                    stands |= {chain[0], int(online.row_of_state[y])}
                elif online.row_of_state[y] >= 0:
                    stands.add(int(online.row_of_state[y]))
                else:
                    h = int(online.h_of[y])
                    stands.add(online.dead if h < 0 else chain[h - 1])
                    unreached += 1
            if stands:
                assert online.prior_next[r, j] in stands
            else:
                assert online.prior_next[r, j] < 0
    assert unreached  # some prior successors stand for states not reached yet


def test_gdq_values_the_chain_by_its_estimates() -> None:
    _, online = twins("keys-ppddl", "keys-ppddl-2")
    gdq = make_learner("GDQ", online_context(online))
    env = OnlineEnv(online)
    run_episodes(gdq, env, 20, np.random.default_rng(4))
    gamma, cost, r_max = gdq.config.gamma, gdq.params.prior_cost, online.r_max
    v = r_max  # R_max one step before the goal, then -cost + gamma V a step further
    for r in online.chain[1:]:
        assert gdq.v[r] == pytest.approx(v)
        v = -cost + gamma * v
    assert gdq.v[online.dead] == pytest.approx(-cost / (1 - gamma))


def test_resized_model_keeps_transitions_and_known_pairs() -> None:
    m = new_model(3, 2, 2)
    m.visits[1, 1] = 4
    m.slots[1, 1, 0] = (2 << 32) | 4
    m.known[0] = 1 * 2 + 1
    m.n_known[0] = 1
    big = resized(m, 5, 4)
    assert big.visits.shape == (5, 4) and big.visits[1, 1] == 4
    assert big.slots[1, 1, 0] == (2 << 32) | 4
    assert big.known[0] == 1 * 4 + 1 and big.n_known[0] == 1


@pytest.mark.parametrize("method", ["Q-learning", "DARLING", "GDQ"])
def test_learners_keep_learning_through_growth(method: str) -> None:
    _, online = twins("keys-ppddl", "keys-ppddl-2")
    learner = make_learner(method, online_context(online))
    env = OnlineEnv(online)
    env.reset(seed=0)
    first = online.revision
    records = run_episodes(learner, env, 40, np.random.default_rng(0))
    assert online.revision > first  # the arrays grew while learning
    assert learner.q.shape == online.columns.shape
    assert records.success.any()
    if method == "GDQ":  # an untried pair is worth its prior backup, however it was found
        t = learner.tables
        for r in range(online.n_rows):
            x = online.state_of(r)
            if x < 0 or online.goal[r]:
                continue
            for j in np.flatnonzero(t.table.allowed[r] & (t.model.visits[r] == 0)):
                nxt = online.prior_next[r, j]
                if nxt >= 0:
                    expected = online.r_max if online.goal[nxt] else \
                        -learner.params.prior_cost + learner.config.gamma * learner.v[nxt]
                    # within what the sweeps leave: they stop at a threshold and budget
                    assert learner.q[r, j] == pytest.approx(expected, abs=0.05)


def test_online_refusals() -> None:
    _, online = twins("lift", "lift-1")
    with pytest.raises(ConfigError, match="starts at its initial state"):
        OnlineEnv(online).reset(options={"start": "(at l1)"})
    with pytest.raises(PlanningError, match="not .*pyperplan"):
        online.plan_table("pyperplan")
    with pytest.raises(PlanningError, match="STRIPS domain with a dynamics file"):
        OnlineInstance(shipped("keys", "keys-1"))
    learner = make_learner("GDQ-literal", pddl_task_context(shipped("lift", "lift-1")))
    assert learner is not None  # the paper's variants walk plans: refused online
    with pytest.raises(ConfigError, match="no enumerated plans"):
        make_learner("GDQ-literal", online_context(online))
    with pytest.raises(ConfigError, match="estimate 'h_max': expected one of h_add, h_FF, or "
                       "None"):
        OnlineInstance(shipped("lift", "lift-1"), estimate="h_max")


def test_h_ff_as_the_estimate() -> None:
    """The estimate a run reads can be h_FF: its value from the start, and GDQ learns."""
    base = shipped("courier", "courier-2")
    online = OnlineInstance(base, estimate="h_FF")
    assert online.h_start == hff_for(online.task).many(online.graph.words[:1])[0] <= \
        OnlineInstance(base).h_start
    env = OnlineEnv(online)
    env.reset(seed=0)
    r = run_episodes(make_learner("GDQ", online_context(online)), env, 40,
                     np.random.default_rng(0))
    assert r.success[-10:].any()


def test_cli_explores_online(tmp_path, capsys) -> None:
    out = tmp_path / "run"
    domain, problem, _ = resolve_pddl("lift", "lift-2", None)
    assert main(["run", "--domain", str(domain), "--problem", str(problem), "--explore",
                 "online", "--method", "GDQ", "Q-learning", "--episodes", "20", "--runs",
                 "2", "--jobs", "1", "--out", str(out), "--no-report"]) == 0
    optimal = next(iter(json.loads((out / "optimal.json").read_text()).values()))
    assert optimal["explored"] == "online" and optimal["v_star"] is None
    assert not (out / "policies.csv").exists()
    rows = (out / "episodes.csv").read_text().splitlines()
    assert len(rows) == 1 + 2 * 2 * 20


def test_cli_falls_back_to_online_past_the_budget(tmp_path, capsys, monkeypatch) -> None:
    monkeypatch.setattr("gdq_pddl.pddl.reachable.TABLE_BUDGET", 20_000)
    out = tmp_path / "run"
    domain, problem, _ = resolve_pddl("lift", "lift-2", None)
    assert main(["run", "--domain", str(domain), "--problem", str(problem), "--method",
                 "DARLING", "--episodes", "5", "--runs", "1", "--jobs", "1", "--out",
                 str(out), "--no-report"]) == 0
    assert "explored online" in capsys.readouterr().err
    assert main(["run", "--task", "C", "--explore", "online", "--out",
                 str(tmp_path / "x")]) != 0
    assert "--explore is for a PPDDL problem" in capsys.readouterr().err


def test_a_step_limit_below_h_max_is_refused_online_as_enumerated(tmp_path, capsys) -> None:
    """keys-ppddl-2: the shortest plan has 7 actions (h_max from the start: 7); a step limit
    of 5 is refused by the enumerated run, and now online too, naming the same key
    (issue 38: online ran every episode into the wall and wrote a report)."""
    from tests.cli.hostile import refused
    from tests.helpers import cli

    shipped_toml = resolve_pddl("keys-ppddl", "keys-ppddl-2", None)[2]
    short = tmp_path / "short.toml"
    short.write_text(shipped_toml.read_text().replace("step_limit = 25", "step_limit = 5"))
    for explore in ("enumerate", "online"):
        code, text = cli(capsys, "run", "--domain", "keys-ppddl", "--problem", "keys-ppddl-2",
                         "--dynamics", short, "--explore", explore, "--method", "Q-learning",
                         "--episodes", 2, "--runs", 1, "--jobs", 1, "--no-report", "--out",
                         tmp_path / explore)
        refused(code, text, "dynamics.step_limit", "5 is less than the shortest plan",
                "no episode can reach the goal")
        assert code == 2 and not (tmp_path / explore / "episodes.csv").exists()
    base = shipped("keys-ppddl", "keys-ppddl-2")
    assert OnlineInstance(base, dynamics=replace(base.dynamics, step_limit=7)).h_start == 9


def test_estimate_weight_is_checked(monkeypatch) -> None:
    """A weight is a finite real in [1, 100] whose chain rows fit the table budget (1e6
    built 3e7 chain rows until memory ran out; 1e300 overflowed; a string was a TypeError)."""
    base = shipped("lift", "lift-1")
    for bad in (1e6, 1e300, 101, "2", None, True, float("inf"), 0.99):
        with pytest.raises(ConfigError, match=r"^estimate_weight must be a finite number "
                           r"in \[1, 100\], got"):
            OnlineInstance(base, estimate_weight=bad)
    assert OnlineInstance(base, estimate_weight=np.float64(100.0)).estimate_weight == 100.0
    for bad in ("0.3", -0.1, float("nan")):
        with pytest.raises(ConfigError, match="^darling_tolerance must be a finite number"):
            OnlineInstance(base, darling_tolerance=bad)
    monkeypatch.setattr("gdq_pddl.pddl.reachable.TABLE_BUDGET", 100_000)
    with pytest.raises(ConfigError, match="estimate_weight 100: .* chain rows .*table budget"):
        OnlineInstance(base, estimate_weight=100)
    # a state found later, with an estimate far past the initial state's: refused up
    # front by the rows still to make, before any is allocated
    monkeypatch.undo()
    online = OnlineInstance(base, estimate_weight=100)
    rows = online.n_rows
    with pytest.raises(SizeError, match=r"stands 1,000,000,000 actions from the goal .*"
                       r"estimate_weight"):
        online._chain_row(999_999_999)
    assert online.n_rows == rows


MOST_LIKELY_NOWHERE = ("""(define (domain rare) (:requirements :probabilistic-effects)
  (:predicates (on))
  (:action flip :parameters () :precondition (not (on))
    :effect (probabilistic 0.1 (on))))""", """(define (problem p) (:domain rare)
  (:init) (:goal (on)))""")


def test_most_likely_knowledge_without_a_way_says_so() -> None:
    """The most likely outcome of the one action does nothing: the knowledge has no way
    to the goal, though reality reaches it (issue 38: online said "unreachable even
    ignoring delete effects", which is false of reality)."""
    base = PDDLInstance.from_texts(*MOST_LIKELY_NOWHERE, determinisation="most-likely")
    with pytest.raises(PlanningError, match="most-likely determinisation .* has no way to the "
                       "goal .*less likely outcomes may still reach it.*all-outcomes"):
        OnlineInstance(base)
    assert OnlineInstance(PDDLInstance.from_texts(*MOST_LIKELY_NOWHERE)).h_start == 1
