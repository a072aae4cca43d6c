"""Planning speed on the office: cold and warm queries of `graph`, and `pyperplan`.

    python benchmarks/planning.py [--repeats 7]

cold      parse the domain and problem, ground, plan (a fresh PlanningProblem each time)
ground    ground + plan on an already parsed problem
warm-new  plan the same query with the result cache emptied (grounding kept)
warm-hit  the same query again (served from the per-(state, goal) cache)
pyperplan one optimal plan through unified-planning (reader and engine already loaded)

Each figure is the median of --repeats runs, in milliseconds, interpreter start-up and
imports excluded. The authors' released planner (clingo in a subprocess per query) took
313 to 916 ms per cold office query on this machine kind.
"""

from __future__ import annotations

import argparse

from _timing import median_ms  # benchmarks/_timing.py (this folder is on sys.path)

from gdq_pddl.abstraction import OfficeAbstraction
from gdq_pddl.planning import PlanningProblem, get_planner
from gdq_pddl.resources import domain_text
from gdq_pddl.world import load_world
from gdq_pddl.world_types import office_problem


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--repeats", type=int, default=7)
    parser.add_argument("--task", default="C")
    args = parser.parse_args()
    world = load_world()
    dtext, ptext = domain_text(), office_problem(world, world.task(args.task))
    ab = OfficeAbstraction(world)
    goal = ab.goal(world.task(args.task).goal)
    graph = get_planner("graph")
    graph.solve(PlanningProblem.from_texts(dtext, ptext))  # warm imports and caches

    def cold() -> None:
        graph.solve(PlanningProblem.from_texts(dtext, ptext), None, goal)

    parsed = PlanningProblem.from_texts(dtext, ptext)

    def grounded() -> None:
        PlanningProblem(parsed.domain, parsed.problem).task  # noqa: B018 (grounds)
        graph.solve(PlanningProblem(parsed.domain, parsed.problem), None, goal)

    shared = PlanningProblem.from_texts(dtext, ptext)

    def warm_new() -> None:
        shared._results.clear()  # no cached result can answer it; grounding is kept
        graph.solve(shared, None, goal)

    graph.solve(shared, None, goal)

    def warm_hit() -> None:
        graph.solve(shared, None, goal)

    rows = [("graph cold (parse+ground+plan)", median_ms(cold, args.repeats)),
            ("graph ground+plan", median_ms(grounded, args.repeats)),
            ("graph warm, uncached (search only)", median_ms(warm_new, args.repeats * 5)),
            ("graph warm, cached", median_ms(warm_hit, args.repeats * 50))]
    try:
        pyperplan = get_planner("pyperplan")
        pp_problem = PlanningProblem.from_texts(dtext, ptext)
        pyperplan.solve(pp_problem, None, goal)  # loads unified-planning's reader once

        def pyperplan_query() -> None:
            pp_problem._results.clear()
            pyperplan.solve(pp_problem, None, goal)

        rows.append(("pyperplan (one optimal plan)", median_ms(pyperplan_query, args.repeats)))
    except Exception as exc:  # report, do not hide, a backend that cannot run
        rows.append((f"pyperplan unavailable: {exc}", float("nan")))
    print(f"office task {args.task}, median of {args.repeats}+ runs")
    for name, ms in rows:
        print(f"  {name:36s} {ms:9.4f} ms")


if __name__ == "__main__":
    main()
