"""Plan tables kept as distance layers equal the enumerated plans (issue 22 item 4)."""

from __future__ import annotations

import numpy as np
import pytest

from gdq_pddl.abstraction.pddl import graph_plan_table
from gdq_pddl.envs.pddl_env import PDDLInstance

# Random small graphs: rooms in a ring with dead ends, a one-way door, several goals.
DOMAIN = """(define (domain walk) (:requirements :strips :probabilistic-effects)
  (:predicates (at ?x) (link ?x ?y))
  (:action go :parameters (?x ?y) :precondition (and (at ?x) (link ?x ?y))
    :effect (probabilistic 0.9 (and (at ?y) (not (at ?x))))))"""


def problem(n: int, links: list[tuple[int, int]], goal: int) -> str:
    facts = " ".join(f"(link n{a} n{b})" for a, b in links)
    return (f"(define (problem w) (:domain walk) (:objects {' '.join(f'n{i}' for i in range(n))})"
            f" (:init (at n0) {facts}) (:goal (at n{goal})))")


def random_problem(rng: np.random.Generator) -> PDDLInstance:
    n = int(rng.integers(4, 10))
    links = {(i, i + 1) for i in range(n - 1)} | {(i + 1, i) for i in range(n - 1)}
    links |= {(int(a), int(b)) for a, b in rng.integers(0, n, (n, 2)) if a != b}
    return PDDLInstance.from_texts(DOMAIN, problem(n, sorted(links), n - 1))


def enumerated_first_actions(table) -> np.ndarray:
    out = np.zeros_like(table.first_actions)
    for s in range(table.n_states):
        for plan in table.plans_from(s):
            out[s, plan[0][1]] = True
    return out


@pytest.mark.parametrize("seed", range(12))
@pytest.mark.parametrize("tolerance", [0.0, 0.3, 1.0])
def test_first_actions_and_start_pairs_equal_the_enumerated_plans(seed, tolerance):
    graph = random_problem(np.random.default_rng(seed)).graph
    layered = graph_plan_table(graph, tolerance)
    assert not layered.enumerated
    first, pairs = layered.first_actions.copy(), layered.start_pairs(0)
    assert not layered.capped  # reading it enumerates
    assert (enumerated_first_actions(layered) == first).all()
    walked = np.zeros_like(first)
    for plan in layered.plans_from(0):
        for s, a in plan:
            walked[s, a] = True
    assert (walked == pairs).all()


def test_a_detour_through_the_state_itself_is_no_plan():
    # n0 - n1 - ... - n8 (goal) with a dead end n9 off n0: going to n9 and back is 2
    # actions more than the 8 of the shortest plan, within 1.3 x 8 = 10, but it loops.
    links = [(i, i + 1) for i in range(8)] + [(0, 9), (9, 0)]
    graph = PDDLInstance.from_texts(DOMAIN, problem(10, links, 8)).graph
    table = graph_plan_table(graph, 0.3)
    to_dead_end = graph.op_index["(go n0 n9)"]
    assert not table.first_actions[0, to_dead_end]
    assert (enumerated_first_actions(table) == table.first_actions).all()


def test_independent_subgoals_are_not_enumerated_for_the_learners():
    switches = PDDLInstance.from_texts(
        "(define (domain sw) (:requirements :strips :negative-preconditions "
        ":probabilistic-effects) (:predicates (on ?s)) (:action turn :parameters (?s) "
        ":precondition (not (on ?s)) :effect (probabilistic 0.9 (on ?s))))",
        "(define (problem p) (:domain sw) (:objects " + " ".join(f"s{i}" for i in range(12))
        + ") (:init) (:goal (and " + " ".join(f"(on s{i})" for i in range(12)) + ")))")
    table = switches.plan_table("graph", 0.0)  # 12! shortest plans from the start
    assert table.start_pairs(0).sum() == 12 * 2**11 and table.first_actions[0].all()
    assert not table.enumerated
