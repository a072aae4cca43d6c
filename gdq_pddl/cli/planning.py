"""Subcommands about knowledge and planning: problem, building, plan, planners."""

from __future__ import annotations

import argparse
import json
import sys
from pathlib import Path

from gdq_pddl.cli.common import (
    EXIT_NO_PLAN,
    NONNEGATIVE,
    POSITIVE,
    determinisation_arg,
    task_args,
    tolerance_arg,
    world_and_task,
)


def register_problem(sub) -> None:
    p = sub.add_parser("problem", help="write the PDDL problem for a task, from the world file",
                       description="Write the PDDL problem of a task, generated from the world "
                                   "file. The files in problems/ are this command's output.")
    task_args(p)
    p.add_argument("--all", action="store_true", help="every task of the world")
    p.add_argument("--out", type=Path,
                   help="output file (a folder with --all: writes task-<x>.pddl there)")
    p.set_defaults(func=cmd_problem)


def cmd_problem(args: argparse.Namespace) -> int:
    from gdq_pddl.outputs import output_file, output_folder, write_text
    from gdq_pddl.world import load_world, office_problem

    if args.all:
        world = load_world(args.world)
        out = output_folder(args.out or Path("problems"))
        for name, task in world.tasks.items():
            path = out / f"task-{name.lower()}.pddl"
            write_text(path, office_problem(world, task))
            print(path)
        return 0
    world, task = world_and_task(args)
    text = office_problem(world, task)
    if args.out:
        write_text(output_file(args.out), text)
    else:
        sys.stdout.write(text)
    return 0


def register_building(sub) -> None:
    p = sub.add_parser("building", help="generate an office-like building of N positions",
                       description="Write a generated building: a world file (TOML), the "
                                   "office domain and a PDDL problem per task. The same "
                                   "--positions, --seed and --doors give the same files.")
    p.add_argument("--positions", type=POSITIVE, required=True, help="number of positions")
    p.add_argument("--seed", type=NONNEGATIVE, default=0, help="random seed (default 0)")
    p.add_argument("--doors", type=NONNEGATIVE, help="number of doors (default positions // 8)")
    p.add_argument("--out", type=Path, help="output folder (default results/building)")
    p.set_defaults(func=cmd_building)


def cmd_building(args: argparse.Namespace) -> int:
    from gdq_pddl.buildings import write_building

    world, problems = write_building(args.out or Path("results/building"), args.positions,
                                     args.seed, args.doors)
    for path in (world, *problems):
        print(path)
    return 0


def register_plan(sub) -> None:
    p = sub.add_parser("plan", help="all shortest plans from a start to a goal",
                       description="Plan with the robot's knowledge (the PDDL domain) and show "
                                   "each plan with the learner state/action each step maps to.")
    task_args(p)
    p.add_argument("--planner", default="graph", help="planner backend (see `gdq-pddl planners`)")
    p.add_argument("--tolerance", type=tolerance_arg, default=0.0,
                   help="also every loop-free plan up to (1+T) x the shortest length")
    p.add_argument("--domain", type=Path, help="PDDL domain file (default: the office domain)")
    p.add_argument("--problem", type=Path,
                   help="PDDL problem file (instead of --task/--start/--goal; no learner mapping)")
    determinisation_arg(p)
    p.add_argument("--json", action="store_true", help="machine-readable output")
    p.set_defaults(func=cmd_plan)


def cmd_plan(args: argparse.Namespace) -> int:
    from gdq_pddl.planning import PlanningProblem, Status, get_planner

    planner = get_planner(args.planner)
    abstraction = None
    if args.problem is not None:
        domain = args.domain or _shipped_domain()
        problem = PlanningProblem.from_files(domain, args.problem, args.determinisation)
        start = goal = None
    else:
        from gdq_pddl.abstraction import OfficeAbstraction
        from gdq_pddl.resources import domain_text
        from gdq_pddl.world import office_problem

        world, task = world_and_task(args)
        dtext, dsrc = (domain_text(), "office.pddl (built in)") if args.domain is None else \
            (_read_text(args.domain), str(args.domain))
        problem = PlanningProblem.from_texts(dtext, office_problem(world, task), dsrc,
                                             f"task {task.name} (generated)")
        abstraction = OfficeAbstraction(world)
        start, goal = None, abstraction.goal(task.goal)
    result = planner.solve(problem, start, goal, args.tolerance)
    plans = [_plan_json(plan, abstraction) for plan in result.plans]
    if args.json:
        print(json.dumps({"status": str(result.status), "planner": result.planner,
                          "length": result.length, "capped": result.capped, "plans": plans},
                         indent=2))
    elif result.status is Status.SOLVED:
        print(f"{len(plans)} plan(s) of length {result.length} from {result.planner}"
              + (f" (tolerance {args.tolerance})" if args.tolerance else ""))
        for i, plan in enumerate(plans, 1):
            print(f"\nplan {i} ({len(plan['actions'])} actions):")
            for j, action in enumerate(plan["actions"]):
                learner = plan.get("learner")
                note = f"   learner: {learner[j]['state']} -> {learner[j]['action']}" \
                    if learner else ""
                print(f"  {j + 1:2d}. {action:28s}{note}")
    if result.status is not Status.SOLVED:
        print("gdq-pddl: no plan: the goal cannot be reached from the start", file=sys.stderr)
        return EXIT_NO_PLAN
    if result.length == 0:
        print("gdq-pddl: warning: the goal already holds at the start (or is empty): the plan "
              "has no action, and `gdq-pddl run` refuses such a task", file=sys.stderr)
    return 0


def _plan_json(plan, abstraction) -> dict:
    out: dict = {"actions": list(plan.actions)}
    if abstraction is not None:
        sp = abstraction.spaces
        out["learner"] = [{"state": sp.state_name(abstraction.learner_state(s)),
                           "action": sp.action_name(abstraction.learner_action(a))}
                          for s, a in plan.pairs()]
    return out


def _shipped_domain() -> Path:
    from gdq_pddl.resources import data_file

    return Path(str(data_file("domains", "office.pddl")))


def _read_text(path: Path) -> str:
    from gdq_pddl.pddl.parser import _read

    return _read(path)


def register_planners(sub) -> None:
    p = sub.add_parser("planners", help="list the planner backends and whether they can run",
                       description="List every backend registered under the `gdq_pddl.planners` "
                                   "entry-point group, by this package or any other.")
    p.add_argument("--json", action="store_true", help="machine-readable output")
    p.set_defaults(func=cmd_planners)


def cmd_planners(args: argparse.Namespace) -> int:
    from gdq_pddl.planning import planners

    infos = planners()
    if args.json:
        print(json.dumps([{"name": i.name, "usable": i.usable, "reason": i.reason}
                          for i in infos], indent=2))
        return 0
    for i in infos:
        state = "usable" if i.usable else f"not usable: {i.reason}"
        print(f"{i.name:12s} {state}   ({i.target})")
    return 0

