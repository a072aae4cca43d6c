"""The online state store (gdq_pddl/pddl/lazy.py): expanding states one at a time, in any
order, gives the enumerated graph (reachable_graph, reality_outcomes) up to renaming states
by their rows, and exactly its numbering when states are expanded in id order."""

from __future__ import annotations

from dataclasses import replace

import numpy as np
import pytest

from gdq_pddl.errors import PDDLError
from gdq_pddl.pddl import parse_domain, parse_problem
from gdq_pddl.pddl.grounding import GroundOutcome
from gdq_pddl.pddl.lazy import LazyGraph
from gdq_pddl.pddl.outcomes import reality_outcomes
from gdq_pddl.pddl.ppddl import ProbabilisticTask, ground_ppddl
from gdq_pddl.pddl.reachable import reachable_graph
from gdq_pddl.pddl.wordrows import words
from gdq_pddl.planning.base import PlanningProblem
from tests.helpers import REPO_ROOT
from tests.pddl import ippc as language
from tests.pddl.ippc import random_domain
from tests.pddl.test_ippc_rewards import reward_effect
from tests.pddl.test_scale_enumeration import PICK, SLIPPERY, chain, pick

DATA = REPO_ROOT / "gdq_pddl" / "data"
SHIPPED = ["keys-ppddl-1", "keys-ppddl-2", "keys-1", "courier-1", "delivery-1", "lift-2"]
GOALS = ("(and (p o1) (q o3))", "(and (q o2) (not (r)) (p o3))",
         "(or (and (p o2) (r)) (and (q o1) (not (p o3))))", "(g)")


def shipped(name: str):
    domain = DATA / "domains" / (name.rsplit("-", 1)[0] + ".pddl")
    return PlanningProblem.from_files(domain, DATA / "problems" / f"{name}.pddl").learner_task


def random_task(seed: int) -> ProbabilisticTask:
    """A random PPDDL task of the language tests' generator (disjunctive, quantified and
    negative conditions, conditional and quantified effects, nested draws) over three
    objects, with a goal that may hold later (alternatives too), and by seed rewards,
    failed trials and the most-likely determinisation."""
    rng = np.random.default_rng(7000 + seed)
    objects, language.OBJECTS = language.OBJECTS, ("o1", "o2", "o3")
    try:  # the generator reads its objects from its module
        domain_text, problem_text = random_domain(rng, choices=bool(seed % 2))
    finally:
        language.OBJECTS = objects
    lines = domain_text.split("\n")
    for i, line in enumerate(lines):
        if not line.strip().startswith(":effect"):
            continue
        closers = ")" * (line.count(")") - line.count("("))
        body = line.strip()[len(":effect "):len(line.strip()) - len(closers)]
        if seed % 3 == 0:  # rewards on the problem's scale beside the effect
            body = f"(and {body} {reward_effect(rng, 2, ['?x'])})"
        if seed % 5 < 2:  # a failed trial
            body = f"(probabilistic 1/5 (stuck) 4/5 {body})"
        lines[i] = f"    :effect {body}{closers}"
    domain = parse_domain("\n".join(lines).replace("(g))", "(g) (stuck))"), "d.pddl")
    determinisation = "most-likely" if seed % 7 == 3 else "all-outcomes"
    for goal in (*GOALS[seed % 4:], "(g)"):  # the first that does not hold at the start
        try:
            problem = parse_problem(problem_text.replace("(:goal (g))", f"(:goal {goal})"),
                                    domain, "p.pddl")
        except PDDLError:  # a goal of atoms no action changes, false at the start
            continue
        task = ground_ppddl(domain, problem, determinisation)[0]
        if not task.is_goal(task.init):
            return task
    raise AssertionError("(g) is never true")


TRAP = """(define (domain trap) (:requirements :adl :probabilistic-effects :rewards)
  (:types spot)
  (:predicates (at ?s - spot) (link ?a ?b - spot) (trapped) (wet) (stuck) (done))
  (:action go :parameters (?a ?b - spot)
    :precondition (and (at ?a) (link ?a ?b) (not (trapped)))
    :effect (probabilistic 0.5 (and (at ?b) (not (at ?a)) (increase (reward) 2))
                           0.2 (and (at ?b) (not (at ?a)) (not (wet)) (increase (reward) 2))
                           0.1 (trapped)
                           0.1 (stuck)
                           0.1 (when (wet) (and (at ?b) (not (at ?a))))))
  (:action splash :parameters (?a - spot) :precondition (and (not (trapped)) (or (at ?a) (wet)))
    :effect (probabilistic 0.6 (wet) 0.4 (and (wet) (when (at ?a) (decrease (reward) 1)))))
  (:action finish :parameters (?a - spot) :precondition (and (at ?a) (not (wet)))
    :effect (probabilistic 0.3 (done) 0.7 (and)))
  (:action dry :precondition (and (wet) (not (trapped))) :effect (not (wet))))
"""
"""A dead end (trapped), failed trials, outcomes that reach one state (merged: moving
with or without drying when dry, the two splashes), a disjunctive precondition,
conditional effects and rewards."""


def trap(n: int) -> str:
    spots = [f"s{i}" for i in range(n)]
    links = " ".join(f"(link {a} {b}) (link {b} {a})" for a, b in zip(spots, spots[1:],
                                                                       strict=False))
    return (f"(define (problem trap) (:domain trap) (:objects {' '.join(spots)} - spot)\n"
            f"  (:init (at s0) {links}) (:goal (and (done) (at s{n - 1}))))")


def expand_all(lazy: LazyGraph, how: str, rng: np.random.Generator) -> None:
    """Expand every reachable state: in id order one at a time, in a random order one at
    a time, or in random batches (with repeats, goals and expanded states among them)."""
    while True:
        todo = np.flatnonzero(~lazy.expanded & ~lazy.is_goal)
        if not len(todo):
            return
        if how == "id order":
            lazy.expand([todo[0]])
        elif how == "random":
            lazy.expand([rng.choice(todo)])
        else:
            pick = rng.choice(lazy.n_states, size=min(lazy.n_states, 4))
            lazy.expand(np.concatenate([pick, rng.choice(todo, size=2)]))


def assert_same_graph(task, how: str, seed: int = 0) -> LazyGraph:
    """The lazily expanded graph is the enumerated one, states renamed by their rows (no
    renaming: ``how`` is id order)."""
    graph = reachable_graph(task)
    lazy = LazyGraph(task, gains=True)
    expand_all(lazy, how, np.random.default_rng(seed))
    assert lazy.n_states == graph.n_states
    assert lazy.words.dtype == np.uint64 and lazy.words.shape == graph.words.shape
    ren = graph.lookup(lazy.words)  # graph id of each lazy id
    assert np.array_equal(graph.words[ren], lazy.words)
    assert sorted(ren.tolist()) == list(range(graph.n_states))
    if how == "id order":
        assert ren.tolist() == list(range(graph.n_states))
    assert np.array_equal(graph.is_goal[ren], lazy.is_goal)
    assert np.array_equal(lazy.expanded, ~lazy.is_goal)
    assert np.array_equal(lazy.lookup(graph.words[ren]), np.arange(lazy.n_states))
    probabilistic = isinstance(task, ProbabilisticTask)
    if probabilistic:
        pair, prob, (nxt, stuck, gain) = reality_outcomes(graph, gains=True)
        width = graph.offered.shape[1]
        starts = np.searchsorted(pair // width, np.arange(graph.n_states + 1))
    for x, i in enumerate(ren.tolist()):
        assert lazy.mask(x) == graph.states[i]
        assert lazy.atoms(x) == task.atoms(graph.states[i])
        row = graph.offered[i][graph.offered[i] >= 0]
        offered = lazy.offered(x)
        assert offered.dtype == np.int64
        assert offered.tolist() == row.tolist() or (len(offered) == 0 and row.tolist() == [0])
        op, to = lazy.edges(x)
        assert list(zip(op.tolist(), ren[to].tolist(), strict=True)) == graph.edges(i)
        column, p, there, stays, earned = lazy.outcomes(x)
        if probabilistic:
            lo, hi = starts[i], starts[i + 1]
            assert column.tolist() == (pair[lo:hi] % width).tolist()
            assert p.tolist() == prob[lo:hi].tolist()  # bit for bit: summed in one order
            assert ren[there].tolist() == nxt[lo:hi].tolist()
            assert stays.tolist() == stuck[lo:hi].tolist()
            assert earned.tolist() == gain[lo:hi].tolist()
        else:  # a STRIPS task: each ground action's one effect, for sure
            assert column.tolist() == list(range(len(offered)))
            assert p.tolist() == [1.0] * len(offered) and not stays.any()
            assert there.tolist() == to.tolist() and not earned.any()
    return lazy


@pytest.mark.parametrize("how", ["id order", "random", "batches"])
@pytest.mark.parametrize("name", SHIPPED)
def test_shipped_problems_expand_into_the_enumerated_graph(name, how):
    assert_same_graph(shipped(name), how)


@pytest.mark.parametrize("determinisation", ["all-outcomes", "most-likely"])
@pytest.mark.parametrize("how", ["id order", "random"])
def test_two_word_rows_and_reality_only_states(determinisation, how):
    # pick: 72 facts (two words a row); most-likely: the (tired) outcome is reality's only,
    # its states numbered after the edges'
    for domain, problem in ((PICK, pick(70)), (SLIPPERY, chain(5, "(and (at p4) (tired))"))):
        task = PlanningProblem.from_texts(domain, problem,
                                          determinisation=determinisation).learner_task
        assert_same_graph(task, how)


@pytest.mark.parametrize("determinisation", ["all-outcomes", "most-likely"])
@pytest.mark.parametrize("how", ["id order", "random", "batches"])
def test_dead_ends_failed_trials_and_merged_outcomes(determinisation, how):
    task = PlanningProblem.from_texts(TRAP, trap(4), determinisation=determinisation
                                      ).learner_task
    lazy = assert_same_graph(task, how)
    live = np.flatnonzero(lazy.expanded)
    dead = [x for x in live if not len(lazy.offered(x))]
    assert dead and all(len(lazy.edges(x)[0]) == 0 for x in dead)
    outs = [lazy.outcomes(x) for x in live]
    assert any(o[3].any() for o in outs)  # stuck
    assert any(len(set(o[0].tolist())) < len(o[0]) for o in outs)
    assert any((o[4] != 0).any() for o in outs)  # gains
    go = [k for k, op in enumerate(task.ops) if op.name.startswith("(go")]
    merged = [(x, c) for x, o in zip(live, outs, strict=True) for c in set(o[0].tolist())
              if lazy.offered(x)[c] in go and (o[0] == c).sum() < 5]
    assert merged  # fewer rows than go's five outcomes: some were one state


ORDER = """(define (domain order) (:requirements :strips :probabilistic-effects)
  (:predicates (zz) (aa) (done1) (done2) (x1) (x2))
  (:action first :precondition (zz)
    :effect (probabilistic 0.6 (and (done1) (not (zz))) 0.4 (and (x1) (not (zz)))))
  (:action second :precondition (aa)
    :effect (probabilistic 0.6 (and (done2) (not (aa))) 0.4 (and (x2) (not (aa))))))
"""
"""Two ground actions listed first, second whose only preconditions sort the other way
among the facts ((aa) before (zz)): the states only reality reaches (x1, x2 under
most-likely) are numbered in the order GroundTask.applicable lists the ground actions,
second's first."""


def test_states_only_reality_reaches_are_numbered_as_the_enumeration_does():
    problem = "(define (problem o) (:domain order) (:init (zz) (aa)) (:goal (and (x1) (x2))))"
    task = PlanningProblem.from_texts(ORDER, problem, determinisation="most-likely"
                                      ).learner_task
    lazy = assert_same_graph(task, "id order")
    assert [sorted(lazy.atoms(x) - lazy.atoms(0)) for x in (3, 4)] == [["(x2)"], ["(x1)"]]


def test_outcomes_of_probability_zero_are_left_out():
    task = PlanningProblem.from_texts(TRAP, trap(3)).learner_task
    every = (1 << len(task.facts)) - 1
    ops = tuple(replace(op, outcomes=(*op.outcomes, GroundOutcome(0.0, every, 0)))
                for op in task.ops)
    never = replace(task, ops=ops)  # a way to a state of every fact, never taken
    lazy = assert_same_graph(never, "id order")
    assert lazy.lookup(words(every, lazy.n_words)[None]).tolist() == [-1]
    assert all((lazy.outcomes(x)[1] > 0).all() for x in np.flatnonzero(lazy.expanded))
    assert lazy.n_states == reachable_graph(task).n_states


@pytest.mark.parametrize("seed", range(40))
def test_random_domains_expand_into_the_enumerated_graph(seed):
    task = random_task(seed)
    lazy = assert_same_graph(task, ("id order", "random", "batches")[seed % 3], seed)
    if seed % 3 == 0 and seed % 5 < 2:
        assert any(lazy.outcomes(x)[3].any() for x in np.flatnonzero(lazy.expanded))


def test_the_random_tasks_cover_what_they_are_for():
    # a test that passes on tasks without goals, stuck outcomes, alternatives or gains
    # would not check them: the generator must make them
    tasks = [random_task(seed) for seed in range(40)]
    graphs = [reachable_graph(t) for t in tasks]
    assert sum(g.is_goal.any() for g in graphs) >= 10
    assert sum(t.disjunctive for t in tasks) >= 10
    assert sum(any(o.stuck for op in t.ops for o in op.outcomes) for t in tasks) >= 10
    assert sum(any(o.rewards or o.reward for op in t.ops for o in op.outcomes)
               for t in tasks) >= 5
    assert sum(t.determinisation == "most-likely" for t in tasks) >= 3
    assert sum(len(t.goal_alternatives) > 0 for t in tasks) >= 2
    assert sum(g.n_states for g in graphs) >= 300


def test_ids_are_stable_and_new_states_come_in_order():
    task = shipped("keys-ppddl-1")
    lazy = LazyGraph(task)
    assert lazy.n_states == 1 and not lazy.expanded[0]
    assert lazy.mask(0) == task.init and lazy.n_words == max(1, -(-len(task.facts) // 64))
    seen_rows, seen_masks = [], []
    rng = np.random.default_rng(3)
    while not lazy.expanded[~lazy.is_goal].all() and lazy.n_states < 60:
        before = lazy.n_states
        seen_rows.append(lazy.words.copy())
        seen_masks.append([lazy.mask(x) for x in range(before)])
        todo = np.flatnonzero(~lazy.expanded & ~lazy.is_goal)
        new = lazy.expand(rng.choice(todo, size=min(3, len(todo)), replace=False))
        assert new.dtype == np.int64
        assert new.tolist() == list(range(before, lazy.n_states))
    assert len(seen_rows) > 3  # the capacity (16 rows) doubled on the way
    for rows, masks in zip(seen_rows, seen_masks, strict=True):
        assert np.array_equal(lazy.words[:len(rows)], rows)
        assert np.array_equal(lazy.lookup(rows), np.arange(len(rows)))
        assert [lazy.mask(x) for x in range(len(masks))] == masks


def test_expand_is_idempotent():
    lazy = LazyGraph(shipped("courier-1"), gains=True)
    first = lazy.expand([0])
    assert len(first) and lazy.expanded[0]
    kept = (lazy.offered(0), lazy.edges(0), lazy.outcomes(0), lazy.words.copy())
    for again in ([0], [0, 0], np.array([0])):
        assert lazy.expand(again).tolist() == []
        assert lazy.n_states == 1 + len(first)
    assert lazy.offered(0) is kept[0] and lazy.edges(0) is kept[1]
    assert lazy.outcomes(0) is kept[2] and np.array_equal(lazy.words, kept[3])
    both = lazy.expand([first[0], first[0]])  # a repeat in one call: expanded once
    assert lazy.expand([first[0]]).tolist() == [] and both.tolist() == \
        list(range(1 + len(first), lazy.n_states))


def test_goal_states_are_never_expanded():
    task = shipped("keys-ppddl-1")
    start = replace(task, init=(task.init | task.goal_pos) & ~task.goal_neg)
    assert start.is_goal(start.init)
    lazy = LazyGraph(start)
    assert lazy.is_goal.tolist() == [True]
    assert lazy.expand([0, 0]).tolist() == [] and not lazy.expanded[0]
    assert lazy.offered(0).tolist() == [] and lazy.edges(0)[0].tolist() == []
    assert all(len(a) == 0 for a in lazy.outcomes(0))
    full = LazyGraph(task)
    expand_all(full, "id order", np.random.default_rng(0))
    goals = np.flatnonzero(full.is_goal)
    assert len(goals) and not full.expanded[goals].any()
    assert full.expand(goals).tolist() == [] and not full.expanded[goals].any()
    assert all(full.offered(x).tolist() == [] for x in goals)


def test_lookup_of_rows_never_seen_is_minus_one():
    task = shipped("keys-ppddl-1")
    lazy = LazyGraph(task)
    lazy.expand([0])
    graph = reachable_graph(task)
    ids = lazy.lookup(graph.words)  # every reachable row: the few found, the rest unknown
    assert ids.dtype == np.int64 and (ids == -1).sum() == graph.n_states - lazy.n_states
    assert np.array_equal(lazy.words[ids[ids >= 0]], graph.words[ids >= 0])
    rows = np.concatenate([lazy.words, np.zeros((1, lazy.n_words), dtype=np.uint64),
                           np.full((1, lazy.n_words), np.uint64(2**63))])
    assert lazy.lookup(rows).tolist() == list(range(lazy.n_states)) + [-1, -1]
    assert lazy.lookup(rows[:0]).tolist() == []


def test_asking_about_a_state_not_expanded_or_not_found_says_so():
    lazy = LazyGraph(shipped("keys-ppddl-1"))
    with pytest.raises(ValueError, match=r"state 0 is not expanded yet: call expand\(\[0\]\)"):
        lazy.offered(0)
    with pytest.raises(IndexError, match="state 5 is not a discovered state"):
        lazy.outcomes(5)
    with pytest.raises(IndexError, match="state -1 is not a discovered state"):
        lazy.expand([-1])
