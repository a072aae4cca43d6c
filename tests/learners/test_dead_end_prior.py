"""GDQ's prior does not gamble on dead ends: of a PPDDL action's outcomes it keeps the one
closest to the goal, but the knowledge's chance of an outcome from which the goal cannot
be reached is valued as that dead end (``PriorModel.dead``,
:func:`gdq_pddl.learners.warm_start.prior_backup`), enumerated and online alike.

The domain below is derived by hand: from ``bank`` a rope bridge leads to the goal in two
steps, but the first step drops the walker into the river, where nothing can be done,
with probability 1/2; the ford is three sure steps; jumping is a dead end for certain.
With a flat step cost c = 1, gamma = 0.95 and R_max = 20, the prior values the bridge at
``1/2 (-1 + 0.95 * 20) + 1/2 D = -1`` (``D = -1 / 0.05 = -20``) and the ford at
``-1 + 0.95 (-1 + 0.95 * 20) = 16.1``: GDQ's first move is into the ford, where a prior
blind to the river took the bridge (valued 18)."""

from __future__ import annotations

from dataclasses import replace
from types import SimpleNamespace

import networkx as nx
import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from gdq_pddl.abstraction.prior import PriorModel, dead_chances
from gdq_pddl.envs.online import OnlineInstance
from gdq_pddl.envs.pddl_env import PDDLInstance
from gdq_pddl.errors import ConfigError, ResultsError
from gdq_pddl.learners import GDQ, GDQConfig, gdq, pddl_task_context, warm_start
from gdq_pddl.learners.online import online_context
from gdq_pddl.learners.saving import load_learner, save_learner
from gdq_pddl.pddl.distances import distances_from

DOMAIN = """(define (domain crossing)
  (:requirements :strips :probabilistic-effects)
  (:predicates (at-bank) (on-bridge) (in-river) (ford-1) (ford-2) (across))
  (:action step-on-bridge
    :precondition (at-bank)
    :effect (and (not (at-bank))
                 (probabilistic 1/2 (on-bridge) 1/2 (in-river))))
  (:action leave-bridge
    :precondition (on-bridge)
    :effect (and (not (on-bridge)) (across)))
  (:action wade-in
    :precondition (at-bank)
    :effect (and (not (at-bank)) (ford-1)))
  (:action wade-on
    :precondition (ford-1)
    :effect (and (not (ford-1)) (ford-2)))
  (:action wade-out
    :precondition (ford-2)
    :effect (and (not (ford-2)) (across)))
  (:action jump
    :precondition (at-bank)
    :effect (and (not (at-bank)) (in-river))))
"""

PROBLEM = """(define (problem cross) (:domain crossing)
  (:init (at-bank))
  (:goal (across)))
"""


@pytest.fixture(scope="module")
def crossing(tmp_path_factory) -> PDDLInstance:
    folder = tmp_path_factory.mktemp("crossing")
    (folder / "domain.pddl").write_text(DOMAIN)
    (folder / "problem.pddl").write_text(PROBLEM)
    return PDDLInstance.from_files(folder / "domain.pddl", folder / "problem.pddl")


def _column(instance, row: int, name: str) -> int:
    names = [instance.action_name(int(a)) for a in instance.columns[row] if a >= 0]
    return [n.strip("()").split()[0] for n in names].index(name)


def test_dead_chances_add_up_the_outcomes_into_dead_ends() -> None:
    # pair 0: 0.3 into dead state 2, 0.7 live; pair 1: every outcome dead; pair 2: none
    ptr = np.array([0, 2, 4, 4])
    prob = np.array([0.3, 0.7, 0.5, 0.5])
    nxt = np.array([2, 1, 2, 3])
    dead = np.array([False, False, True, True])
    assert dead_chances(ptr, prob, nxt, dead).tolist() == [0.3, 1.0, 0.0]


@settings(max_examples=60, deadline=None)
@given(st.lists(st.lists(st.tuples(st.floats(0.0, 1.0), st.integers(0, 5)), max_size=4),
                min_size=1, max_size=8), st.lists(st.booleans(), min_size=6, max_size=6))
def test_dead_chances_are_the_sums_over_the_dead_outcomes(pairs: list, dead: list) -> None:
    ptr = np.cumsum([0] + [len(p) for p in pairs])
    prob = np.array([q for p in pairs for q, _ in p], dtype=np.float64)
    nxt = np.array([x for p in pairs for _, x in p], dtype=np.int64)
    want = [0.0 if not p else 1.0 if all(dead[x] for _, x in p) else
            min(1.0, sum(q for q, x in p if dead[x])) for p in pairs]
    got = dead_chances(ptr, prob, nxt, np.array(dead))
    assert np.allclose(got, want, rtol=0, atol=1e-12)


def test_the_enumerated_prior_keeps_the_chance_of_the_river(crossing: PDDLInstance) -> None:
    prior = crossing.prior
    s0 = crossing.learner_start
    bridge, ford = _column(crossing, s0, "step-on-bridge"), _column(crossing, s0, "wade-in")
    assert prior.dead is not None
    assert prior.dead[s0, bridge] == pytest.approx(0.5)
    assert prior.dead[s0, ford] == 0.0
    assert prior.dead[s0, _column(crossing, s0, "jump")] == 1.0
    # in the river nothing can be done: its row's one column (no change) is a dead end
    river = [s for s in range(crossing.n_states) if "(in-river)" in crossing.atoms(s)]
    assert prior.dead[river, 0].tolist() == [1.0]
    others = np.setdiff1d(np.arange(crossing.n_states), [s0, *river])
    assert (prior.dead[others] == 0).all()
    # the optimism stays: the bridge's prior successor is the walker on the bridge
    on_bridge = int(prior.next_state[s0, bridge])
    assert "(on-bridge)" in crossing.atoms(on_bridge)


def test_gdq_values_the_bridge_by_hand_and_takes_the_ford(crossing: PDDLInstance) -> None:
    ctx = pddl_task_context(crossing)
    learner = GDQ(ctx)
    s0 = ctx.s0
    bridge, ford = _column(crossing, s0, "step-on-bridge"), _column(crossing, s0, "wade-in")
    assert learner.q[s0, bridge] == pytest.approx(-1.0)
    assert learner.q[s0, ford] == pytest.approx(16.1)
    assert learner.v[s0] == pytest.approx(16.1)
    # blind to the river, the prior took the bridge
    blind = GDQ(replace(ctx, prior=PriorModel(ctx.prior.next_state)))
    assert blind.q[s0, bridge] == pytest.approx(18.0)
    assert int(np.argmax(blind.q[s0])) == bridge


def test_the_warm_start_is_the_fixed_point_with_dead_ends(crossing: PDDLInstance) -> None:
    """Policy iteration on the prior gives OptInit's values: one sweep confirms them."""
    learner = GDQ(pddl_task_context(crossing))
    t, p = learner.tables, learner.params
    init = warm_start.prior_values(t.table, t.prior, p)
    assert np.allclose(init, learner.v, atol=1e-9)
    assert gdq.value_iteration(t.table, t.model, t.prior, t.queue, p, 1e-9, 1000) == 1


def test_online_exploration_reads_the_same_chance(crossing: PDDLInstance) -> None:
    online = OnlineInstance(crossing, dynamics=crossing.dynamics)
    r0 = online.learner_start
    bridge = _column(online, r0, "step-on-bridge")
    ford = _column(online, r0, "wade-in")
    assert online.prior.dead[r0, bridge] == pytest.approx(0.5)
    assert online.prior.dead[r0, ford] == 0.0
    learner = GDQ(online_context(online))
    assert learner.q[r0, bridge] < learner.q[r0, ford]


@pytest.mark.parametrize("knows_dead_ends", [True, False])
def test_exploring_never_jumps_into_a_certain_dead_end(crossing: PDDLInstance,
                                                       knows_dead_ends: bool) -> None:
    """Every step explores (epsilon 1) with a band wide enough for every move from the
    bank; the jump is drawn only by a prior blind to dead ends, the bridge either way."""
    ctx = pddl_task_context(crossing)
    if not knows_dead_ends:
        ctx = replace(ctx, prior=PriorModel(ctx.prior.next_state))
    learner = GDQ(ctx, GDQConfig(epsilon=1.0, plan_tolerance=30.0))
    rng = np.random.default_rng(0)
    drawn = {crossing.action_name(learner.act(ctx.s0, rng)).strip("()")
             for _ in range(300)}
    assert {"wade-in", "step-on-bridge"} <= drawn
    assert ("jump" in drawn) == (not knows_dead_ends)


def test_the_chances_are_saved_and_a_file_without_them_is_refused(crossing: PDDLInstance,
                                                                   tmp_path) -> None:
    ctx = pddl_task_context(crossing)
    learner = GDQ(ctx)
    path, old = tmp_path / "g.npz", tmp_path / "old.npz"
    save_learner(path, learner)
    assert np.array_equal(load_learner(path, ctx).tables.prior.dead, ctx.prior.dead)
    with np.load(path, allow_pickle=False) as z:  # as saved before the prior kept chances
        np.savez(old, **{k: z[k] for k in z.files if k != "prior.dead"})
    with pytest.raises(ResultsError, match=r"old\.npz: damaged learner file .*prior\.dead"):
        load_learner(old, ctx)


@pytest.mark.parametrize("step_limit,first", [(3, "wade-in"), (2, "step-on-bridge")])
def test_a_way_that_does_not_fit_the_step_limit_is_a_dead_end(tmp_path, step_limit: int,
                                                              first: str) -> None:
    """With two steps, the ford (three) cannot reach the goal in time from the bank: its
    states are dead ends, wading in is one for certain, and the bridge is GDQ's way."""
    for name, text in (("d.pddl", DOMAIN), ("p.pddl", PROBLEM)):
        (tmp_path / name).write_text(text)
    (tmp_path / "r.toml").write_text(f"[dynamics]\nname = \"r\"\nstep_limit = {step_limit}\n")
    inst = PDDLInstance.from_files(tmp_path / "d.pddl", tmp_path / "p.pddl", tmp_path / "r.toml")
    s0 = inst.learner_start
    wade = inst.prior.dead[s0, _column(inst, s0, "wade-in")]
    assert wade == (1.0 if step_limit == 2 else 0.0)
    learner = GDQ(pddl_task_context(inst))
    best = int(np.argmax(np.where(learner.tables.table.allowed[s0], learner.q[s0], -np.inf)))
    assert best == _column(inst, s0, first)


def test_the_dead_ends_of_the_step_limit_are_the_starts_own(tmp_path) -> None:
    """Started on the ford, two steps reach the goal: a restarted instance keeps no dead
    end of the bank's."""
    for name, text in (("d.pddl", DOMAIN), ("p.pddl", PROBLEM)):
        (tmp_path / name).write_text(text)
    (tmp_path / "r.toml").write_text("[dynamics]\nname = \"r\"\nstep_limit = 2\n")
    bank = PDDLInstance.from_files(tmp_path / "d.pddl", tmp_path / "p.pddl", tmp_path / "r.toml")
    ford = bank.restarted(start="(ford-1)")
    s = ford.learner_start
    wade_on = _column(ford, s, "wade-on")
    assert bank.prior.dead[s, wade_on] == 1.0  # from the bank, ford-2 is too far
    assert ford.prior.dead is None or ford.prior.dead[s, wade_on] == 0.0
    assert bank.prior.dead[s, wade_on] == 1.0  # the bank's own prior is untouched


def test_distances_from_a_state_by_breadth_first_search(crossing: PDDLInstance) -> None:
    came = distances_from(crossing.graph, crossing.learner_start)
    by_atom = {atom: int(came[s]) for s in range(crossing.n_states)
               for atom in crossing.atoms(s)}
    assert by_atom == {"(at-bank)": 0, "(on-bridge)": 1, "(in-river)": 1, "(ford-1)": 1,
                       "(ford-2)": 2, "(across)": 2}


@settings(max_examples=60, deadline=None)
@given(st.integers(1, 12).flatmap(lambda n: st.tuples(
    st.just(n), st.lists(st.tuples(st.integers(0, n - 1), st.integers(0, n - 1)),
                         max_size=3 * n))))
def test_distances_from_are_networkx_shortest_paths(graph: tuple) -> None:
    """On random graphs, in the state graph's CSR form (edges grouped by state)."""
    n, edges = graph
    edges = sorted(set(edges))
    ptr = np.searchsorted([a for a, _ in edges], np.arange(n + 1))
    csr = SimpleNamespace(n_states=n, edge_ptr=ptr,
                          edge_next=np.array([b for _, b in edges], dtype=np.int64))
    g = nx.DiGraph()
    g.add_nodes_from(range(n))
    g.add_edges_from(edges)
    want = nx.single_source_shortest_path_length(g, 0)
    assert distances_from(csr, 0).tolist() == [want.get(x, -1) for x in range(n)]


def test_most_likely_knowledge_has_no_dead_ends_to_keep(tmp_path) -> None:
    """Knowing each action's most likely outcome alone, a state the knowledge cannot lead
    to the goal may well reach it in reality: no chances are kept, enumerated or online."""
    (tmp_path / "d.pddl").write_text(DOMAIN)
    (tmp_path / "p.pddl").write_text(PROBLEM)
    likely = PDDLInstance.from_files(tmp_path / "d.pddl", tmp_path / "p.pddl",
                                     determinisation="most-likely")
    assert not likely.knows_dead_ends and likely.prior.dead is None
    assert OnlineInstance(likely, dynamics=likely.dynamics).prior.dead is None


def test_a_chance_outside_zero_one_is_refused(crossing: PDDLInstance) -> None:
    ctx = pddl_task_context(crossing)
    bad = ctx.prior.dead.copy()
    bad[ctx.s0, 0] = 1.5
    with pytest.raises(ConfigError, match="dead"):
        GDQ(replace(ctx, prior=replace(ctx.prior, dead=bad)))
