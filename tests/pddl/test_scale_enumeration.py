"""The array state enumeration (issue 22 item 4): the numbering of a one-state-at-a-time
BFS, a table budget instead of a state cap, and PPDDL outcomes as merged rows."""

from collections import deque

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from gdq_pddl.envs.model import merge_outcomes
from gdq_pddl.envs.pddl_env import load_instance
from gdq_pddl.errors import PlanningError
from gdq_pddl.limits import human_bytes
from gdq_pddl.pddl import reachable
from gdq_pddl.pddl.distances import distinct
from gdq_pddl.pddl.outcomes import reality_outcomes
from gdq_pddl.pddl.reachable import reachable_graph
from gdq_pddl.pddl.wordrows import KeyIndex, RowConditions, holds, words
from gdq_pddl.planning.base import PlanningProblem

SLIPPERY = """(define (domain slip) (:requirements :strips :probabilistic-effects)
  (:predicates (at ?x) (next ?x ?y) (tired))
  (:action go :parameters (?x ?y) :precondition (and (at ?x) (next ?x ?y))
    :effect (probabilistic 0.7 (and (at ?y) (not (at ?x)))
                           0.2 (and (at ?y) (not (at ?x)) (tired)))))
"""


def chain(n: int, goal: str) -> str:
    names = [f"p{i}" for i in range(n)]
    links = " ".join(f"(next {a} {b}) (next {b} {a})" for a, b in zip(names, names[1:],
                                                                       strict=False))
    return (f"(define (problem chain) (:domain slip) (:objects {' '.join(names)})\n"
            f"  (:init (at p0) {links}) (:goal {goal}))")


PICK = """(define (domain pick) (:requirements :strips :probabilistic-effects)
  (:predicates (free) (got ?x) (tired))
  (:action take :parameters (?x) :precondition (free)
    :effect (probabilistic 0.7 (and (got ?x) (not (free)))
                           0.2 (and (got ?x) (not (free)) (tired)))))
"""


def pick(n: int) -> str:
    names = " ".join(f"p{i}" for i in range(n))
    return f"(define (problem pick) (:domain pick) (:objects {names}) (:init (free)) " \
        f"(:goal (got p{n - 1})))"


def one_at_a_time(task):
    """The breadth-first numbering the arrays must keep: states popped one by one, the
    knowledge's edges in op order, then the states only reality reaches."""
    op_pos = {id(op): k for k, op in enumerate(task.ops)}
    index, states, queue, edges = {task.init: 0}, [task.init], deque([task.init]), []
    while queue:
        s = queue.popleft()
        if task.is_goal(s):
            continue
        succ = sorted(task.successors(s), key=lambda e: op_pos[id(e[0])])
        for t in [t for _, t in succ] + task.outcome_states(s):
            if t not in index:
                index[t] = len(states)
                states.append(t)
                queue.append(t)
        edges += [(index[s], op_pos[id(op)], index[t]) for op, t in succ]
    return states, edges


@pytest.mark.parametrize("determinisation", ["all-outcomes", "most-likely"])
@pytest.mark.parametrize("domain, problem", [(SLIPPERY, chain(5, "(and (at p4) (tired))")),
                                             (PICK, pick(70))], ids=["chain", "pick70"])
@pytest.mark.parametrize("chunk", [("PARENT_CHUNK", reachable.PARENT_CHUNK),
                                   ("PARENT_CHUNK", 2), ("EXPAND_CELLS", 3)])
def test_numbering_is_the_one_state_bfs(domain, problem, determinisation, chunk, monkeypatch):
    # pick: 72 facts, two uint64 words a state; most-likely: the (tired) outcome is
    # reality's only, and its states come after the edges' states; chunk 2: a level's
    # states are expanded two at a time; 3 cells: 3 // the widest row seen so far (1, 2
    # or 3 states at a time as rows widen)
    monkeypatch.setattr(reachable, *chunk)
    task = PlanningProblem.from_texts(domain, problem, determinisation=determinisation
                                      ).learner_task
    assert len(task.facts) > 64 or domain is SLIPPERY
    graph = reachable_graph(task)
    states, edges = one_at_a_time(task)
    assert graph.states == tuple(states)
    src = np.repeat(np.arange(graph.n_states), np.diff(graph.edge_ptr))
    assert list(zip(src.tolist(), graph.edge_op.tolist(), graph.edge_next.tolist(),
                    strict=True)) == edges
    assert graph.lookup(graph.words[::-1]).tolist() == list(range(graph.n_states))[::-1]
    offered = [sorted({op_pos for op_pos, _ in graph.edges(i)}) or [0]
               for i in range(graph.n_states)]
    assert all(set(e) <= set(row[row >= 0].tolist())
               for e, row in zip(offered, graph.offered, strict=True))
    op_pos = {id(op): k for k, op in enumerate(task.ops)}
    rows = [[] if goal else sorted(op_pos[id(op)] for op in task.applicable(state))
            for state, goal in zip(states, graph.is_goal.tolist(), strict=True)]
    want = np.full((len(rows), max(1, *map(len, rows))), -1)
    for i, row in enumerate(rows):
        want[i, :max(1, len(row))] = row or [0]  # none applies: ground action 0
    assert graph.offered.dtype == np.int64 and np.array_equal(graph.offered, want)


def test_the_budget_is_named(monkeypatch):
    task = PlanningProblem.from_texts(SLIPPERY, chain(30, "(at p29)")).learner_task
    monkeypatch.setattr(reachable, "TABLE_BUDGET", reachable.PAIR_BYTES * 10)  # <= 5 states
    need = human_bytes(6 * 2 * reachable.PAIR_BYTES)  # 2 actions a state (go left, right)
    with pytest.raises(PlanningError, match=rf"chain.pddl: more than 5 reachable states \(6 "
                       rf"found so far, up to 2 .* would need at least {need} .*TABLE_BUDGET "
                       rf"= {reachable.PAIR_BYTES * 10:,}; states of breadth-first levels 0 "
                       r"to 2 \(the last unfinished\): 1, 2, 3;"):
        reachable_graph(task, source="chain.pddl")


def test_the_budget_is_a_share_of_the_machines_memory(monkeypatch):
    task = PlanningProblem.from_texts(SLIPPERY, chain(30, "(at p29)")).learner_task
    whole = reachable_graph(task).n_states
    assert reachable.TABLE_BUDGET is None  # the default: what the machine has
    # a machine whose MEMORY_SHARE holds the tables of 12 states of 2 actions, then of 24
    for states in (12, 24):
        memory = states * 2 * reachable.PAIR_BYTES / reachable.MEMORY_SHARE
        monkeypatch.setenv("GDQ_PDDL_MEMORY", str(int(memory) + 1))
        assert reachable.state_cap(2) == states
        with pytest.raises(PlanningError, match=rf"more than {states} reachable states.*"
                           rf"{reachable.MEMORY_SHARE:g} of this machine's .*MEMORY_SHARE"):
            reachable_graph(task, source="chain.pddl")
    monkeypatch.setenv("GDQ_PDDL_MEMORY", str(int(whole * 2 * reachable.PAIR_BYTES
                                                  / reachable.MEMORY_SHARE) + 1))
    assert reachable_graph(task).n_states == whole  # fits: every state


def test_rows_of_many_facts_count_in_the_budget(monkeypatch):
    # 201 facts: rows of 4 words, whose copies enumeration holds beside the tables
    task = PlanningProblem.from_texts(SLIPPERY, chain(200, "(at p199)")).learner_task
    n_words = -(-len(task.facts) // 64)
    assert n_words == 4
    per_state = reachable.state_bytes(2, n_words)
    assert per_state == 2 * reachable.PAIR_BYTES + 3 * 8 * reachable.ROW_COPIES
    monkeypatch.setattr(reachable, "TABLE_BUDGET", 10 * per_state)
    assert reachable.TABLE_BUDGET // (2 * reachable.PAIR_BYTES) > 10  # tables alone: more
    with pytest.raises(PlanningError, match=r"more than 10 reachable states .*ROW_COPIES: 4 "
                       r"words of facts here"):
        reachable_graph(task, source="chain.pddl")
    whole = reachable_graph(task, 10**6).n_states
    monkeypatch.setattr(reachable, "TABLE_BUDGET", whole * per_state)
    assert reachable_graph(task).n_states == whole  # fits: every state


@pytest.mark.parametrize("gains", [False, True])
def test_reality_outcomes_merge_as_the_per_state_rule(gains):
    graph = load_instance("courier", "courier-2").graph  # conditional effects, rewards
    task = graph.task
    want = []
    for s, state in enumerate(graph.states):
        here = [] if graph.is_goal[s] else task.applicable(state)
        for op in sorted(here, key=task.ops.index):
            merged = merge_outcomes((((s, True) if o.stuck else (graph.index[o.apply(state)],
                                                                 False))
                                     + ((o.gain(state),) if gains else ()), o.probability)
                                    for o in op.outcomes)
            column = int(np.flatnonzero(graph.offered[s] == task.ops.index(op))[0])
            want += [(s * graph.offered.shape[1] + column, p, *key)
                     for key, p in merged.items()]
    pair, prob, fields = reality_outcomes(graph, gains)
    assert list(zip(pair.tolist(), prob.tolist(), *(f.tolist() for f in fields),
                    strict=True)) == want


def test_distinct_is_unique():
    a = np.random.default_rng(0).integers(0, 50, 400)
    assert np.array_equal(distinct(a), np.unique(a))
    assert len(distinct(a[:0])) == 0


def test_a_start_that_is_a_goal_is_a_graph_of_one_state():
    task = PlanningProblem.from_texts(SLIPPERY, chain(3, "(at p0)")).learner_task
    graph = reachable_graph(task)
    assert graph.n_states == 1 and graph.is_goal.tolist() == [True]
    assert graph.edge_ptr.tolist() == [0, 0] and len(graph.edge_op) == len(graph.edge_next) == 0
    assert graph.offered.tolist() == [[0]]


def test_the_known_states_index_finds_what_was_added_in_any_batches():
    rng = np.random.default_rng(3)
    for _ in range(20):
        rows = rng.integers(0, 50, size=(rng.integers(1, 400), 3)).astype(np.uint64)
        keys = reachable.row_keys(np.unique(rows, axis=0))
        keys = keys[rng.permutation(len(keys))]
        index = KeyIndex(keys[:1].copy(), np.zeros(1, dtype=np.int64))
        c = 1
        while c < len(keys):  # batches of random sizes, as chunks add them
            step = int(rng.integers(1, 60))
            index.add(keys[c:c + step], np.arange(c, min(c + step, len(keys))))
            c += step
            assert len(index.runs) <= 1 + int(np.log2(c))  # few runs to search
        assert (index.find(keys) == np.arange(len(keys))).all()
        absent = reachable.row_keys(np.full((2, 3), 99, dtype=np.uint64))
        assert (index.find(absent) == -1).all()


@given(st.integers(1, 200), st.integers(0, 2**31 - 1))
@settings(max_examples=60, deadline=None)
def test_row_conditions_hold_where_the_rows_stack_holds(n_facts, seed):
    """One row against many conditions as fact lists gives what the stack of the
    conditions' word rows gives (:func:`holds`), and a row is the mask's bits."""
    rng = np.random.default_rng(seed)
    n_words = -(-n_facts // 64)

    def mask(p):
        return sum(1 << f for f in np.flatnonzero(rng.random(n_facts) < p).tolist())

    conditions = [(mask(0.05), mask(0.05)) for _ in range(int(rng.integers(0, 40)))]
    state = mask(0.5)
    row = words(state, n_words)
    assert all((int(row[j]) >> b) & 1 == (state >> (64 * j + b)) & 1
               for j in range(n_words) for b in range(64))
    expected = np.array([state & p == p and not state & n for p, n in conditions],
                        dtype=np.bool_)
    assert np.array_equal(RowConditions(conditions).holds(row), expected)
    if conditions:
        stack = np.stack([words(p, n_words) for p, _ in conditions])
        neg = np.stack([words(n, n_words) for _, n in conditions])
        assert np.array_equal(holds(row[None, :], stack, neg), expected)


@settings(max_examples=60, deadline=None)
@given(st.integers(1, 6), st.integers(1, 7), st.integers(1, 3), st.integers(0, 2**32 - 1))
def test_first_seen_keeps_each_parents_first_outcome_of_a_successor(n_out, n_rows, n_words,
                                                                     seed):
    """`first_seen` (one sort) marks what comparing each outcome's successor with every
    earlier outcome's, row by row, marks: the first outcome of each distinct successor of
    a parent (values from a small range, so that successors repeat)."""
    rng = np.random.default_rng(seed)
    after = [rng.integers(0, 3, size=(n_rows, n_words)).astype(np.uint64)
             for _ in range(n_out)]
    expected = []
    for j, t in enumerate(after):
        expected.append(np.array([all((t[r] != s[r]).any() for s in after[:j])
                                  for r in range(n_rows)], dtype=np.bool_))
    got = reachable.first_seen(after)
    assert len(got) == n_out
    for g, e in zip(got, expected, strict=True):
        np.testing.assert_array_equal(g, e)
