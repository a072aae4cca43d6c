"""h_FF (``planning/heuristic.py: HFF``): values derived by hand on a gripper and on a
blocksworld of our own where h_add counts the shared hand steps twice, and on random
small tasks the bounds any relaxed plan's size obeys (h_max <= h_FF <= h_add, 0 and
unreachable exactly where h_add says so)."""

from __future__ import annotations

import numpy as np
import pytest

from gdq_pddl.pddl import parse_domain, parse_problem
from gdq_pddl.pddl.ppddl import ground_ppddl
from gdq_pddl.planning.heuristic import HFF, INFINITE, HAdd, HMax, hff_for
from tests.pddl.ippc import random_domain
from tests.planning.test_hadd import (
    GRIPPER,
    hmax_of,
    random_goal,
    random_task,
    reference,
    rows,
    strips,
)

# Two piles, a on c and b on d; the goal a on b, b on the table. Four actions do it:
# unstack b d, put-down b, unstack a c, stack a b. Six start the other way: unstack a c,
# put-down a, unstack b d, put-down b, pick-up a, stack a b.
BLOCKS = """(define (domain bw) (:requirements :strips)
  (:predicates (on ?x ?y) (ontable ?x) (clear ?x) (handempty) (handfull) (holding ?x))
  (:action pick-up :parameters (?x) :precondition (and (clear ?x) (ontable ?x) (handempty))
    :effect (and (not (ontable ?x)) (not (clear ?x)) (not (handempty)) (handfull)
                 (holding ?x)))
  (:action put-down :parameters (?x) :precondition (and (holding ?x) (handfull))
    :effect (and (not (holding ?x)) (clear ?x) (handempty) (not (handfull)) (ontable ?x)))
  (:action stack :parameters (?x ?y) :precondition (and (holding ?x) (clear ?y) (handfull))
    :effect (and (not (holding ?x)) (not (clear ?y)) (clear ?x) (handempty)
                 (not (handfull)) (on ?x ?y)))
  (:action unstack :parameters (?x ?y) :precondition (and (on ?x ?y) (clear ?x) (handempty))
    :effect (and (holding ?x) (clear ?y) (not (clear ?x)) (not (handempty)) (handfull)
                 (not (on ?x ?y)))))
(define (problem two-piles) (:domain bw) (:objects a b c d)
  (:init (on a c) (on b d) (clear a) (clear b) (ontable c) (ontable d) (handempty))
  (:goal (and (on a b) (ontable b))))
"""


def test_gripper_by_hand():
    """From the start the relaxed plan is move a b, pick b1, pick b2, drop b1, drop b2: 5
    (h_add 6, the plan 7). Robot in b holding b1, b2 in a: drop b1 b (which also frees
    the hand), move b a, pick b2 a, drop b2 b: 4 (h_add 5, counting a second way to free
    the hand; the plan 5)."""
    task = strips(GRIPPER)
    h, ha = HFF(task), HAdd(task)
    mid = task.mask({"(at-robby b)", "(carry b1)", "(at b2 a)"})
    done = task.mask({"(at b1 b)", "(at b2 b)", "(at-robby a)"})
    nothing = task.mask({"(at b1 b)"})
    assert [h(task.init), h(mid), h(done), h(nothing)] == [5, 4, 0, INFINITE]
    assert [ha(task.init), ha(mid)] == [6, 5]
    assert h.many(rows(task, [task.init, mid, done, nothing])).tolist() == [5, 4, 0, -1]


def test_blocks_where_h_add_counts_the_hand_twice():
    """h_add charges ``handfull`` and ``holding`` one action each although one unstack
    gives both: from the start it says 6 (the plan: 4), and after ``unstack b d`` 5 (the
    plan: 3), more than after ``unstack a c`` (4; the plan: 5), so a learner led by it
    starts the long way. The relaxed plans: 4 from the start (unstack b d, put-down b,
    unstack a c, stack a b), 3 after unstack b d, 4 after unstack a c: the short way
    looks shorter."""
    task = strips(BLOCKS)
    h, ha = HFF(task), HAdd(task)
    short = task.mask({"(on a c)", "(holding b)", "(handfull)", "(clear a)", "(clear d)",
                       "(ontable c)", "(ontable d)"})
    long = task.mask({"(holding a)", "(on b d)", "(handfull)", "(clear b)", "(clear c)",
                      "(ontable c)", "(ontable d)"})
    assert [h(task.init), h(short), h(long)] == [4, 3, 4]
    assert [ha(task.init), ha(short), ha(long)] == [6, 5, 4]


def bounded(task, states: list[int]) -> None:
    """h_max <= h_FF <= h_add on each state, all three unreachable together, h_FF and
    h_add 0 together; one state or many."""
    h, ha = HFF(task), HAdd(task)
    got = [h(s) for s in states]
    assert h.many(rows(task, states)).tolist() == got
    for s, value in zip(states, got, strict=True):
        hadd, hmax = ha(s), reference(task, s, hmax_of)
        assert (value == INFINITE) == (hadd == INFINITE) == (hmax == INFINITE)
        if value != INFINITE:
            assert hmax <= value <= hadd
            assert (value == 0) == (hadd == 0)


@pytest.mark.parametrize("seed", range(20))
def test_random_tasks_are_bounded(seed):
    rng = np.random.default_rng(seed)
    domain, problem = random_domain(rng)
    problem = problem.replace("(:goal (g))", f"(:goal {random_goal(rng)})")
    dom = parse_domain(domain, "d.pddl")
    learner, planner = ground_ppddl(dom, parse_problem(problem, dom, "p.pddl"),
                                    ("all-outcomes", "most-likely")[seed % 2])
    n = len(learner.facts)
    states = [learner.init, 0, (1 << n) - 1] + [int(rng.integers(0, 1 << n)) for _ in range(12)]
    for task in (learner, planner):
        bounded(task, states)


@pytest.mark.parametrize("seed", range(30))
def test_random_mask_tasks_are_bounded(seed):
    rng = np.random.default_rng(2000 + seed)
    task = random_task(rng)
    n = len(task.facts)
    bounded(task, [task.init, 0] + [int(sum(1 << f for f in np.flatnonzero(rng.random(n) < p)))
                                    for p in (0.05, 0.1, 0.2, 0.3, 0.5) for _ in range(4)])


def test_hff_for_is_cached_per_task():
    task = strips(BLOCKS)
    assert hff_for(task) is hff_for(task)
    assert isinstance(hff_for(task), HFF) and not isinstance(HMax(task), HAdd)
