"""The nearest other successor of the plan tables' tolerant set (``_nearest_other``),
against its definition: the least goal distance over the successors ``w != s`` of ``v``."""

from __future__ import annotations

import math

import numpy as np
import pytest

from gdq_pddl.abstraction.pddl import _nearest_other
from gdq_pddl.envs.pddl_env import PDDLInstance

# Random directed graphs: one-way links (dead ends, states that cannot reach the goal),
# self-loops, and two actions over overlapping links (two edges to one successor).
DOMAIN = """(define (domain hops) (:requirements :strips :probabilistic-effects)
  (:predicates (at ?x) (link ?x ?y) (hop ?x ?y))
  (:action go :parameters (?x ?y) :precondition (and (at ?x) (link ?x ?y))
    :effect (probabilistic 0.9 (and (at ?y) (not (at ?x)))))
  (:action jump :parameters (?x ?y) :precondition (and (at ?x) (hop ?x ?y))
    :effect (probabilistic 0.5 (and (at ?y) (not (at ?x))))))"""


def random_graph(seed: int):
    rng = np.random.default_rng(seed)
    n = int(rng.integers(3, 12))
    path = [(i, i + 1) for i in range(n - 1)]  # every room is reachable from n0
    links = path + [(int(a), int(b)) for a, b in rng.integers(0, n, (n, 2))]
    hops = [(int(a), int(b)) for a, b in rng.integers(0, n, (n // 2 + 1, 2))]
    hops += [links[i] for i in rng.integers(0, len(links), 2)]
    facts = " ".join([f"(link n{a} n{b})" for a, b in links]
                     + [f"(hop n{a} n{b})" for a, b in hops])
    goal = int(rng.integers(1, n))
    problem = (f"(define (problem h) (:domain hops) "
               f"(:objects {' '.join(f'n{i}' for i in range(n))}) "
               f"(:init (at n0) {facts}) (:goal (at n{goal})))")
    return PDDLInstance.from_texts(DOMAIN, problem).graph


def reference(graph, v: int, s: int) -> float:
    d = graph.distances
    return min((float(d[w]) if d[w] >= 0 else math.inf
                for _, w in graph.edges(v) if w != s), default=math.inf)


@pytest.mark.parametrize("seed", range(40))
def test_nearest_other_successor_is_its_definition(seed):
    graph = random_graph(seed)
    n = graph.n_states
    v, s = np.divmod(np.arange(n * n), n)  # every pair, edges or not
    got = _nearest_other(graph, v, s)
    want = [reference(graph, int(a), int(b)) for a, b in zip(v, s, strict=True)]
    assert got.tolist() == want


def test_the_graphs_have_what_the_function_must_handle():
    """Dead ends, states that cannot reach the goal, self-loops and repeated successors
    occur among the random graphs, so the comparison above covers them."""
    seen = {"unreachable goal": False, "self-loop": False, "repeated": False}
    for seed in range(40):
        graph = random_graph(seed)
        seen["unreachable goal"] |= bool((graph.distances < 0).any())
        for i in range(graph.n_states):
            succ = [w for _, w in graph.edges(i)]
            seen["self-loop"] |= i in succ
            seen["repeated"] |= len(set(succ)) < len(succ)
    assert all(seen.values()), seen


def test_slippery_blocks_match_too():
    domain = """(define (domain b) (:requirements :strips :probabilistic-effects)
      (:predicates (on ?x ?y) (ontable ?x) (clear ?x) (holding ?x) (handempty))
      (:action pick-up :parameters (?x)
        :precondition (and (clear ?x) (ontable ?x) (handempty))
        :effect (probabilistic 0.9 (and (holding ?x) (not (ontable ?x)) (not (clear ?x))
                                        (not (handempty)))))
      (:action put-down :parameters (?x) :precondition (holding ?x)
        :effect (and (ontable ?x) (clear ?x) (handempty) (not (holding ?x))))
      (:action stack :parameters (?x ?y) :precondition (and (holding ?x) (clear ?y))
        :effect (and (clear ?x) (handempty) (not (holding ?x))
                     (probabilistic 0.8 (and (on ?x ?y) (not (clear ?y))) 0.2 (ontable ?x))))
      (:action unstack :parameters (?x ?y) :precondition (and (on ?x ?y) (clear ?x) (handempty))
        :effect (probabilistic 0.8 (and (holding ?x) (clear ?y) (not (on ?x ?y))
                                        (not (clear ?x)) (not (handempty))))))"""
    problem = """(define (problem p) (:domain b) (:objects a b c d)
      (:init (handempty) (clear a) (on a b) (on b c) (on c d) (ontable d))
      (:goal (and (on b a) (on c b) (on d c))))"""
    graph = PDDLInstance.from_texts(domain, problem).graph
    src = np.repeat(np.arange(graph.n_states), np.diff(graph.edge_ptr))
    v, s = graph.edge_next, src  # as the plan table asks: a successor, avoiding its source
    got = _nearest_other(graph, v, s)
    assert got.tolist() == [reference(graph, int(a), int(b)) for a, b in zip(v, s, strict=True)]
    assert _nearest_other(graph, v[:0], s[:0]).shape == (0,)
