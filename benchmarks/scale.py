"""Planning on generated buildings of 100, 300 and 1000 positions (the `graph` backend).

    python benchmarks/scale.py [--sizes 100 300 1000] [--repeats 5] [--seed 0]

For each size, the building of ``gdq-pddl building --positions N --seed S`` and its
task A (start and goal in rooms far apart) plus the reverse of task C (`C-reversed`):

cold      parse the domain and problem, ground, all shortest plans (a fresh problem)
warm      all shortest plans with the result cache emptied (grounding kept)
tol 0.3   every loop-free plan up to 1.3 x the shortest, warm (DARLING's and GDQ-code's H;
          only up to --tolerance-up-to positions, -1/nan beyond)
L         shortest plan length; states: nodes of the pruned state graph; generated:
          states whose h_max was computed (everything the search touched); plans

Times are medians of --repeats runs in milliseconds (imports and numba compilation
excluded: one untimed warm-up query first).

Then the learners at each size (skip with ``--no-learners``): env steps per second of
each method of ``gdq-pddl scale`` (learner and compact env, the compiled loop, one core)
over ``--episodes`` episodes of task A from a fresh learner, median of ``--repeats``
runs after an untimed warm-up run, and the seconds to build the task context (plan
tables for every learner state: the shortest plans, and the door-route plans within
1.3 x of :mod:`gdq_pddl.abstraction.routes` that DARLING and GDQ-code use).
"""

from __future__ import annotations

import argparse
import math
import time

import numpy as np
from _timing import median_ms  # benchmarks/_timing.py (this folder is on sys.path)

from gdq_pddl.buildings import building_world
from gdq_pddl.envs.office import CompactEnv
from gdq_pddl.experiments.scale import METHODS, TOLERANCE
from gdq_pddl.learners import make_learner, office_task_context
from gdq_pddl.learners.episodes import run_compact
from gdq_pddl.planning import PlanningProblem, get_planner
from gdq_pddl.resources import domain_text
from gdq_pddl.world_types import Task, office_problem


def measure(n: int, seed: int, repeats: int, tolerance: bool = True) -> list[dict]:
    world = building_world(n, seed)
    domain = domain_text()
    planner = get_planner("graph")
    out = []
    tasks = [world.tasks["A"], Task("C-reversed", world.tasks["C"].goal, world.tasks["C"].start)]
    for task in tasks:
        text = office_problem(world, task)

        def cold(text=text):
            return planner.solve(PlanningProblem.from_texts(domain, text))

        problem = PlanningProblem.from_texts(domain, text)
        cold()

        def warm(tolerance=0.0, problem=problem):
            problem._results.clear()
            return planner.solve(problem, tolerance=tolerance)

        result = warm()
        tol = warm(0.3) if tolerance else None
        out.append({
            "positions": n, "doors": len(world.doors), "task": task.name,
            "cold_ms": median_ms(cold, repeats), "warm_ms": median_ms(warm, repeats),
            "tol_ms": median_ms(lambda: warm(0.3), max(1, repeats // 2)) if tol else math.nan,
            "L": result.length, "states": result.metrics["states"],
            "generated": result.metrics["generated"], "plans": len(result.plans),
            "tol_plans": len(tol.plans) if tol else -1,
            "tol_states": tol.metrics["states"] if tol else -1,
        })
    return out


def learner_speed(n: int, seed: int, episodes: int, repeats: int) -> dict[str, float]:
    """Env steps per second of each method on task A of the ``n``-position building."""
    world = building_world(n, seed)
    t0 = time.perf_counter()
    ctx = office_task_context(world, "A", darling_tolerance=TOLERANCE, darling_kind="routes")
    out = {"context_s": time.perf_counter() - t0}
    env = CompactEnv(task="A", world=world)
    gamma = 1.0 - 1.0 / world.step_limit
    for name, (method, config) in METHODS.items():
        rates = []
        for r in range(repeats + 1):
            learner = make_learner(method, ctx, gamma=gamma, **config)
            env.reset(seed=r)
            t1 = time.perf_counter()
            records = run_compact(learner, env, episodes if r else 2, np.random.default_rng(r))
            if r:  # run 0 compiles
                rates.append(records.steps.sum() / (time.perf_counter() - t1))
            del learner
        out[name] = float(np.median(rates))
    return out


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--sizes", type=int, nargs="+", default=[100, 300, 1000])
    parser.add_argument("--repeats", type=int, default=5)
    parser.add_argument("--seed", type=int, default=0)
    parser.add_argument("--tolerance-up-to", type=int, default=300,
                        help="measure tolerance 0.3 only up to this size (1000: ~100 s a query)")
    parser.add_argument("--episodes", type=int, default=200,
                        help="episodes per learner speed run")
    parser.add_argument("--no-learners", action="store_true", help="planning only")
    args = parser.parse_args()
    print(f"{'positions':>9} {'doors':>5} {'task':>4} {'cold ms':>8} {'warm ms':>8} "
          f"{'L':>4} {'states':>6} {'generated':>9} {'plans':>5} {'tol0.3 ms':>9} "
          f"{'plans':>5} {'states':>6}")
    for n in args.sizes:
        for r in measure(n, args.seed, args.repeats, n <= args.tolerance_up_to):
            print(f"{r['positions']:>9} {r['doors']:>5} {r['task']:>4} {r['cold_ms']:>8.1f} "
                  f"{r['warm_ms']:>8.1f} {r['L']:>4} {r['states']:>6} {r['generated']:>9} "
                  f"{r['plans']:>5} {r['tol_ms']:>9.1f} {r['tol_plans']:>5} "
                  f"{r['tol_states']:>6}")

    if args.no_learners:
        return
    print(f"\nlearners, env steps/s (median of {args.repeats} x {args.episodes} episodes, "
          "task A, one core)")
    print(f"{'positions':>9} {'context s':>9} " + " ".join(f"{m:>11}" for m in METHODS))
    for n in args.sizes:
        r = learner_speed(n, args.seed, args.episodes, args.repeats)
        print(f"{n:>9} {r['context_s']:>9.1f} " + " ".join(f"{r[m]:>11,.0f}" for m in METHODS),
              flush=True)


if __name__ == "__main__":
    main()
