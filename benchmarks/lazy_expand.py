"""Expanding one state at a time on a problem too large to enumerate (gdq_pddl/pddl/lazy.py).

    python benchmarks/lazy_expand.py [--blocks 23] [--steps 5000] [--seed 0]
    python benchmarks/lazy_expand.py --domain D.pddl --problem P.pddl

A random walk, as an online agent makes one: in each state a ground action drawn
uniformly among those offered, its next state drawn from reality's outcomes; a goal or a
dead end starts the walk again from state 0. Each state the walk visits for the first
time is expanded (:meth:`LazyGraph.expand`, with gains), and that call is timed.

Without files the problem is generated: a blocks world of ``--blocks`` blocks in piles
of at most three, where a block set down may crack (a cracked block can be neither
picked up nor stacked on) and putting a block on the table may break the table (then
nothing can be put down there): ``2 + 2 b`` ground actions a block (1,104 for 23 blocks,
as many as pddlgym's exploding blocks of 23), about ``b**2`` facts.

Prints the task's size, the seconds to build the store, the expansions and the states
discovered, and the median, 90th percentile and slowest expansion in milliseconds.
"""

from __future__ import annotations

import argparse
import statistics
import time

import numpy as np

from gdq_pddl.pddl.lazy import LazyGraph
from gdq_pddl.planning import PlanningProblem

DOMAIN = """(define (domain cracking-blocks)
  (:requirements :strips :negative-preconditions :probabilistic-effects)
  (:predicates (on ?x ?y) (ontable ?x) (clear ?x) (handempty) (holding ?x)
               (cracked ?x) (table-broken))
  (:action pick-up :parameters (?x)
    :precondition (and (clear ?x) (ontable ?x) (handempty) (not (cracked ?x)))
    :effect (and (holding ?x) (not (clear ?x)) (not (ontable ?x)) (not (handempty))))
  (:action put-down :parameters (?x)
    :precondition (and (holding ?x) (not (table-broken)))
    :effect (and (ontable ?x) (clear ?x) (handempty) (not (holding ?x))
                 (probabilistic 0.05 (table-broken) 0.1 (cracked ?x))))
  (:action unstack :parameters (?x ?y)
    :precondition (and (on ?x ?y) (clear ?x) (handempty) (not (cracked ?x)))
    :effect (and (holding ?x) (clear ?y) (not (clear ?x)) (not (on ?x ?y))
                 (not (handempty))))
  (:action stack :parameters (?x ?y)
    :precondition (and (holding ?x) (clear ?y) (not (cracked ?y)))
    :effect (and (on ?x ?y) (clear ?x) (handempty) (not (holding ?x)) (not (clear ?y))
                 (probabilistic 0.2 (cracked ?y)))))
"""


def blocks_problem(n: int, rng: np.random.Generator) -> str:
    """Piles of at most three of ``n`` blocks, shuffled; the goal: one tower of the first
    quarter of them."""
    names = [f"b{i}" for i in range(n)]
    order = [names[i] for i in rng.permutation(n)]
    init = ["(handempty)"]
    for p in range(0, n, 3):
        pile = order[p:p + 3]
        init += [f"(ontable {pile[0]})", f"(clear {pile[-1]})"]
        init += [f"(on {a} {b})" for b, a in zip(pile, pile[1:], strict=False)]
    tower = names[:max(2, n // 4)]
    goal = " ".join(f"(on {a} {b})" for a, b in zip(tower, tower[1:], strict=False))
    return (f"(define (problem cracking-{n}) (:domain cracking-blocks) "
            f"(:objects {' '.join(names)})\n  (:init {' '.join(init)})\n"
            f"  (:goal (and {goal})))")


def walk(lazy: LazyGraph, steps: int, rng: np.random.Generator) -> list[float]:
    """Seconds of each first expansion along a random walk of ``steps`` steps."""
    times, x = [], 0
    for _ in range(steps):
        if not lazy.expanded[x] and not lazy.is_goal[x]:
            t0 = time.perf_counter()
            lazy.expand([x])
            times.append(time.perf_counter() - t0)
        column, prob, nxt, _, _ = lazy.outcomes(x)
        if not len(column):  # a goal or a dead end: start again
            x = 0
            continue
        here = column == rng.integers(len(lazy.offered(x)))
        x = int(rng.choice(nxt[here], p=prob[here] / prob[here].sum()))
    return times


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--blocks", type=int, default=23)
    parser.add_argument("--steps", type=int, default=5000)
    parser.add_argument("--seed", type=int, default=0)
    parser.add_argument("--domain", help="a PPDDL domain file (with --problem)")
    parser.add_argument("--problem", help="its problem file")
    args = parser.parse_args()
    rng = np.random.default_rng(args.seed)
    if args.domain:
        problem = PlanningProblem.from_files(args.domain, args.problem)
        name = args.problem
    else:
        problem = PlanningProblem.from_texts(DOMAIN, blocks_problem(args.blocks, rng))
        name = f"generated cracking blocks, {args.blocks} blocks"
    task = problem.learner_task
    t0 = time.perf_counter()
    lazy = LazyGraph(task, gains=True)
    built = time.perf_counter() - t0
    times = walk(lazy, args.steps, rng)
    ms = sorted(1000 * t for t in times)
    print(f"{name}: {len(task.ops):,} ground actions, {len(task.facts):,} facts "
          f"({lazy.n_words} words a state); store built in {built:.3f} s")
    print(f"{args.steps:,} steps: {len(ms):,} expansions, {lazy.n_states:,} states "
          f"discovered; expansion ms: median {statistics.median(ms):.3f}, "
          f"90th percentile {ms[int(0.9 * (len(ms) - 1))]:.3f}, slowest {ms[-1]:.3f}")


if __name__ == "__main__":
    main()
