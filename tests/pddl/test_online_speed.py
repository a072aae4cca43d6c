"""What makes a domain like IPPC-2008 boxworld (every effect under a `when`, a drive
whose wrong destinations are three nested foralls over the cities under static `when`s)
fast to ground and to explore online: a binding whose static `when` fails is not
grounded further (gdq_pddl/pddl/ppddl_effects.py), and an action none of whose
conditions holds in a state is not applied outcome by outcome (gdq_pddl/pddl/lazy.py).
Both give what the plain way gives."""

from __future__ import annotations

from dataclasses import replace

import numpy as np
import pytest

from gdq_pddl.pddl import ppddl_effects
from gdq_pddl.pddl.grounding import GroundOutcome
from gdq_pddl.pddl.lazy import LazyGraph
from gdq_pddl.pddl.reachable import reality_ranks
from gdq_pddl.planning.base import PlanningProblem
from tests.pddl.test_lazy import (
    ORDER,
    TRAP,
    assert_same_graph,
    expand_all,
    random_task,
    trap,
)

ORDER_PROBLEM = "(define (problem o) (:domain order) (:init (zz) (aa)) (:goal (and (x1) (x2))))"

DOMAIN = """(define (domain drive)
 (:requirements :typing :conditional-effects :probabilistic-effects :rewards)
 (:types city truck)
 (:predicates (at ?t - truck ?c - city) (road ?a - city ?b - city)
              (wrong1 ?a - city ?b - city) (wrong2 ?a - city ?b - city))
 (:action drive
  :parameters (?t - truck ?a - city ?b - city)
  :effect (when (and (at ?t ?a) (road ?a ?b))
           (and (not (at ?t ?a)) (decrease (reward) 1)
            (probabilistic
             0.25 (forall (?w1 - city) (when (wrong1 ?a ?w1)
                   (forall (?w2 - city) (when (wrong2 ?a ?w2)
                    (probabilistic 1/2 (at ?t ?w1) 1/2 (at ?t ?w2))))))
             0.75 (at ?t ?b))))))
"""


def problem_text(n: int) -> str:
    cities = " ".join(f"c{i}" for i in range(n))
    facts = []
    for i in range(n):
        j, k = (i + 1) % n, (i + 2) % n
        facts += [f"(road c{i} c{j})", f"(road c{i} c{k})", f"(wrong1 c{i} c{j})",
                  f"(wrong2 c{i} c{k})"]
    return (f"(define (problem p) (:domain drive) (:objects {cities} - city t0 t1 - truck)"
            f" (:init (at t0 c0) (at t1 c1) {' '.join(facts)})"
            f" (:goal (and (at t0 c{n - 1}) (at t1 c0))))")


def load(tmp_path, n: int) -> PlanningProblem:
    (tmp_path / "d.pddl").write_text(DOMAIN)
    (tmp_path / "p.pddl").write_text(problem_text(n))
    return PlanningProblem.from_files(tmp_path / "d.pddl", tmp_path / "p.pddl")


def test_a_failed_static_when_is_not_grounded_further(tmp_path, monkeypatch):
    """Without the pruning, each drive grounds n x n inner bindings (n^3 actions x n^2):
    with it, the inner forall is grounded only under the one ?w1 whose wrong1 holds."""
    n = 9
    calls = [0]
    plain = ppddl_effects._ground_outcome

    def counted(*args, **kw):
        calls[0] += 1
        return plain(*args, **kw)

    monkeypatch.setattr(ppddl_effects, "_ground_outcome", counted)
    task = load(tmp_path, n).learner_task
    n_drives = 2 * n * n
    assert calls[0] < n_drives * 4 * n  # the plain way: n_drives * (2 + n + 2 n^2)
    drive = next(op for op in task.ops if op.name == "(drive t0 c0 c1)")
    # a wrong turn to c1 or c2 (1/2 each of 0.25), or c1 as meant (0.75)
    moved = sorted((round(o.probability, 6), tuple(sorted(task.atoms(
        next(a for _, _, a, _ in o.conditional if a))))) for o in drive.outcomes)
    assert moved == [(0.125, ("(at t0 c1)",)), (0.125, ("(at t0 c2)",)),
                     (0.75, ("(at t0 c1)",))]


def test_pruned_grounding_matches_the_plain_one(tmp_path, monkeypatch):
    """The same ground actions and outcomes with the pruning as without it."""
    pruned = load(tmp_path, 5).learner_task
    monkeypatch.setattr(ppddl_effects, "_guards", lambda o: frozenset())
    plain = load(tmp_path, 5).learner_task

    def shape(task):
        return [(op.name, op.pre, op.neg, [(o.probability, o.add, o.dele, o.stuck,
                                            o.conditional, o.reward, o.rewards)
                                           for o in op.outcomes]) for op in task.ops]

    assert shape(pruned) == shape(plain)


def plain_expansion(task, s: int, index: dict[int, int]) -> tuple:
    """State ``s`` expanded the plain way, one outcome at a time on its bitmask
    (:meth:`GroundOutcome.apply`, :meth:`GroundOutcome.gain`), by the rules LazyGraph
    states: ``(offered, edges, outcomes, new masks)``, the new masks numbered from
    ``len(index)`` (``index`` gets them)."""
    n, fresh = len(index), []

    def id_of(t: int) -> int:
        if t not in index:
            index[t] = n + len(fresh)
            fresh.append(t)
        return index[t]

    acts = [k for k, op in enumerate(task.ops) if op.holds(s)]
    edges = []
    for k in acts:  # the determinisation's: each next state once a ground action
        seen = []
        for j in task.ops[k].known:
            t = task.ops[k].outcomes[j].apply(s)
            if t not in seen:
                seen.append(t)
                edges.append((k, id_of(t)))
    rank = reality_ranks(task)
    for k in sorted(acts, key=lambda k: rank[k]):  # reality's other outcomes
        for j, o in enumerate(task.ops[k].outcomes):
            if o.probability > 0 and not o.stuck and o.moves() and j not in task.ops[k].known:
                id_of(o.apply(s))
    outcomes = []
    for c, k in enumerate(acts):
        merged: dict[tuple, float] = {}
        for o in task.ops[k].outcomes:
            if o.probability > 0:
                t = o.apply(s) if o.moves() and not o.stuck else s
                key = (index[t], bool(o.stuck), o.gain(s))
                merged[key] = merged.get(key, 0.0) + o.probability
        outcomes += [(c, p, *key) for key, p in merged.items()]
    return acts, edges, outcomes, fresh


TASKS = ["drive", "trap", "trap most-likely", "order most-likely",
         *(f"random {seed}" for seed in range(12))]
"""Conditional effects under nested foralls (drive), failed trials, merged outcomes and
a disjunctive precondition (trap), states only reality reaches numbered by
reality_ranks (most-likely: order's ground actions rank the other way round), and the
language tests' random domains (seeds 3 and 10: most-likely)."""


def small_task(name: str, tmp_path):
    how = "most-likely" if name.endswith("most-likely") else "all-outcomes"
    if name == "drive":
        return load(tmp_path, 4).learner_task
    if name.startswith("trap"):
        return PlanningProblem.from_texts(TRAP, trap(4), determinisation=how).learner_task
    if name.startswith("order"):
        return PlanningProblem.from_texts(ORDER, ORDER_PROBLEM, determinisation=how
                                          ).learner_task
    return random_task(int(name.split()[1]))


@pytest.mark.parametrize("name", TASKS)
def test_the_vectorised_expansion_is_the_plain_one_on_random_states(name, tmp_path):
    """From random states (any set of facts, reachable or not), a random order of
    expansions gives the offered actions, edges, merged outcomes (probabilities and gains
    bit for bit) and new states' numbering of the plain way, one outcome at a time."""
    task = small_task(name, tmp_path)
    rng = np.random.default_rng(len(name) + 31 * sum(map(ord, name)))
    checked = 0
    for _ in range(40):
        if checked >= 24:
            break
        start = int.from_bytes(rng.bytes(-(-len(task.facts) // 8)), "little") \
            & ((1 << len(task.facts)) - 1)
        if task.is_goal(start):
            continue
        lazy = LazyGraph(replace(task, init=start), gains=True)
        index = {start: 0}
        for _ in range(12):
            todo = np.flatnonzero(~lazy.expanded & ~lazy.is_goal)
            if not len(todo):
                break
            x = int(rng.choice(todo))
            acts, edges, outcomes, fresh = plain_expansion(task, lazy.mask(x), index)
            new = lazy.expand([x])
            assert [lazy.mask(y) for y in new] == fresh
            assert lazy.offered(x).tolist() == acts
            op, nxt = lazy.edges(x)
            assert list(zip(op.tolist(), nxt.tolist(), strict=True)) == edges
            column, prob, there, stuck, gain = lazy.outcomes(x)
            assert list(zip(column.tolist(), prob.tolist(), there.tolist(), stuck.tolist(),
                            gain.tolist(), strict=True)) == outcomes
            checked += 1
    assert checked >= 8


def test_expanding_applies_no_outcome_one_by_one(tmp_path, monkeypatch):
    """The expansion applies every outcome of the applicable ground actions at once on
    rows of words: GroundOutcome's own apply and gain (a Python call per outcome: 1,800
    ground actions' a state on IPPC boxworld p05) are never called, and the graph is
    still the enumerated one."""
    task = load(tmp_path, 5).learner_task

    def refused(self, state):
        raise AssertionError("an outcome applied one by one")

    monkeypatch.setattr(GroundOutcome, "apply", refused)
    monkeypatch.setattr(GroundOutcome, "gain", refused)
    lazy = LazyGraph(task, gains=True)
    expand_all(lazy, "random", np.random.default_rng(0))
    assert lazy.n_states > 10
    monkeypatch.undo()
    assert_same_graph(task, "id order")


def test_an_online_run_shows_its_episodes_and_the_states_found(monkeypatch):
    """A run on a problem explored online reports each episode to a progress bar (shown
    after 2 s on a terminal: slow_progress), with the states found so far."""
    from gdq_pddl.envs.online import OnlineInstance
    from gdq_pddl.envs.online_env import OnlineEnv
    from gdq_pddl.learners import episodes, make_learner, run_episodes
    from gdq_pddl.learners.online import online_context
    from tests.envs.test_online import shipped

    bars = []

    class Bar:
        def __init__(self, desc, unit, total):
            self.desc, self.total, self.n, self.states, self.closed = desc, total, 0, [], False
            bars.append(self)

        def update(self, k):
            self.n += k

        def set_postfix(self, states, refresh):
            self.states.append(states)

        def close(self):
            self.closed = True

    monkeypatch.setattr(episodes, "slow_progress", Bar)
    online = OnlineInstance(shipped("keys-ppddl", "keys-ppddl-1"))
    env = OnlineEnv(online)
    env.reset(seed=0)
    run_episodes(make_learner("Q-learning", online_context(online)), env, 5,
                 np.random.default_rng(0))
    [bar] = bars
    assert (bar.total, bar.n, bar.closed) == (5, 5, True)
    assert "online" in bar.desc and bar.states[0] >= 1
    assert bar.states == sorted(bar.states) and bar.states[-1] <= online.graph.n_states


def test_each_columns_least_edge_is_the_sorts():
    """An online row's prior successor of each column: the edge of least key, the first
    among equals, by one reduction over the columns' consecutive edges (envs/online.py
    _first_least), as the stable sort by column then key picks it."""
    from gdq_pddl.envs.online import _first_least

    rng = np.random.default_rng(5)
    for _ in range(200):
        n = int(rng.integers(0, 40))
        col = np.sort(rng.integers(0, 8, size=n))
        key = rng.integers(0, 4, size=n) * (1 if rng.random() < 0.5 else 10**12)
        order = np.lexsort((key, col))
        plain = order[np.r_[True, col[order[1:]] != col[order[:-1]]]] if n else order
        assert _first_least(col, key).tolist() == plain.tolist()
