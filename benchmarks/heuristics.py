"""Speed of the delete-relaxation heuristics (`planning/heuristic.py`) on one state.

    python benchmarks/heuristics.py [--blocks 23] [--states 300] [--repeats 5] [--seed 0]

The problem is ``blocks N`` of ``benchmarks/scale_problems.py`` (a slippery blocksworld:
N blocks in one tower, the reverse tower as the goal; at 23 blocks 599 facts and 1,104
ground actions, 2,162 in the planner's all-outcomes determinisation). The states are
those of random walks from the initial state (restarted every 50 steps), --states
distinct ones. For reality's task (the PPDDL ground actions) and the planner's (its
STRIPS determinisation):

actions   the task's ground actions; relaxed: its relaxed actions (what both heuristics read)
hmax      HMax(state, goal): one call per state
hadd      HAdd(state): one call per state
hadd-many HAdd.many over all the states' word rows at once, per state (a mean)
hff       HFF(state): one call per state (h_add's search and the relaxed plan's extraction)
mean hadd, mean hff, mean hmax   the heuristics' mean values over the states

Figures are the median over the states of each state's median of --repeats calls, in
microseconds (hadd-many: the median of --repeats batches, divided by the number of
states); numba compilation excluded (one untimed call first).
"""

from __future__ import annotations

import argparse
import statistics
import time

import numpy as np
from scale_problems import KINDS  # benchmarks/scale_problems.py (this folder is on sys.path)

from gdq_pddl.pddl import parse_domain, parse_problem
from gdq_pddl.pddl.grounding import GroundTask
from gdq_pddl.pddl.ppddl import ground_ppddl
from gdq_pddl.pddl.wordrows import words
from gdq_pddl.planning.heuristic import HFF, HAdd, HMax, relaxed_actions


def walk_states(task: GroundTask, count: int, rng: np.random.Generator) -> list[int]:
    """``count`` distinct states of random walks from ``task.init`` over its successors."""
    seen: dict[int, None] = {task.init: None}
    state, steps = task.init, 0
    while len(seen) < count:
        nexts = task.successors(state)
        if not nexts or steps == 50:
            state, steps = task.init, 0
            continue
        state = nexts[int(rng.integers(len(nexts)))][1]
        steps += 1
        seen[state] = None
    return list(seen)


def per_state_us(call, states: list[int], repeats: int) -> float:
    """Median over ``states`` of the median of ``repeats`` timed ``call(state)``, in us."""
    out = []
    for s in states:
        times = []
        for _ in range(repeats):
            t0 = time.perf_counter_ns()
            call(s)
            times.append(time.perf_counter_ns() - t0)
        out.append(statistics.median(times) / 1000)
    return statistics.median(out)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--blocks", type=int, default=23)
    parser.add_argument("--states", type=int, default=300)
    parser.add_argument("--repeats", type=int, default=5)
    parser.add_argument("--seed", type=int, default=0)
    args = parser.parse_args()
    domain_text, problem_of = KINDS["blocks"]
    domain = parse_domain(domain_text, "blocks.pddl")
    problem = parse_problem(problem_of(args.blocks), domain, f"blocks-{args.blocks}.pddl")
    learner, planner = ground_ppddl(domain, problem)
    states = walk_states(planner, args.states, np.random.default_rng(args.seed))
    n_words = (len(learner.facts) + 63) // 64
    block = np.stack([words(s, n_words) for s in states])
    print(f"blocks {args.blocks}: {len(learner.facts)} facts, {len(states)} states of "
          f"random walks, median us per state")
    print(f"{'task':10} {'actions':>8} {'relaxed':>8} {'hmax':>8} {'hadd':>8} "
          f"{'hadd-many':>10} {'hff':>8} {'mean hadd':>10} {'mean hff':>9} {'mean hmax':>10}")
    for name, task in (("reality", learner), ("planner", planner)):
        hmax, hadd, hff = HMax(task), HAdd(task), HFF(task)
        goal = task.goal_pos
        hmax(task.init, goal), hadd(task.init), hadd.many(block[:1]), hff(task.init)  # compile
        t_max = per_state_us(lambda s, h=hmax, g=goal: h(s, g), states, args.repeats)
        t_add = per_state_us(hadd, states, args.repeats)
        t_ff = per_state_us(hff, states, args.repeats)
        batches = []
        for _ in range(args.repeats):
            t0 = time.perf_counter_ns()
            values = hadd.many(block)
            batches.append((time.perf_counter_ns() - t0) / 1000 / len(states))
        assert values.tolist() == [hadd(s) for s in states]
        mean_add = float(np.mean(values))
        mean_max = float(np.mean([hmax(s, goal) for s in states]))
        mean_ff = float(np.mean([hff(s) for s in states]))
        print(f"{name:10} {len(task.ops):8d} {len(relaxed_actions(task)):8d} {t_max:8.1f} "
              f"{t_add:8.1f} {statistics.median(batches):10.1f} {t_ff:8.1f} {mean_add:10.1f} "
              f"{mean_ff:9.1f} {mean_max:10.1f}")


if __name__ == "__main__":
    main()
