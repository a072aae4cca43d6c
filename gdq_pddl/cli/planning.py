"""Subcommands about knowledge and planning: problem, building, plan, planners, list."""

from __future__ import annotations

import argparse
import json
import sys
from pathlib import Path

from gdq_pddl.abstraction import OfficeAbstraction
from gdq_pddl.buildings import write_building
from gdq_pddl.cli.common import (
    EXIT_NO_PLAN,
    NONNEGATIVE,
    POSITIVE,
    determinisation,
    load_world_checked,
    pddl_args,
    pddl_files,
    refuse_given,
    task_args,
    tolerance_arg,
    world_and_task,
)
from gdq_pddl.errors import ConfigError, SizeError
from gdq_pddl.learners import registry
from gdq_pddl.outputs import output_file, output_folder, save_figure, write_text
from gdq_pddl.pddl.sexpr import read_pddl_text
from gdq_pddl.planning import PlanningProblem, Status, get_planner, planners
from gdq_pddl.resources import domain_text, problem_domain, resolve, shipped_names
from gdq_pddl.world import builtin_world
from gdq_pddl.world_types import office_problem


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
    if args.all:
        world = load_world_checked(args.world)
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
    pddl_args(p, "plan for it (no learner mapping; default domain: office)")
    p.add_argument("--json", action="store_true", help="machine-readable output")
    p.add_argument("--figure", type=Path, metavar="FILE",
                   help="also draw the plans on the office's map into FILE (.png, .pdf, "
                        ".svg; an office task only)")
    p.set_defaults(func=cmd_plan)


def cmd_plan(args: argparse.Namespace) -> int:
    planner = get_planner(args.planner)
    if args.tolerance and not getattr(planner, "all_plans", True):
        raise ConfigError(f"--tolerance {args.tolerance:g}: planner {args.planner} returns one "
                          "plan, not every plan within a tolerance; use --planner graph or "
                          "clingo, or no --tolerance")
    abstraction = None
    if args.problem is not None:
        refuse_given(args, ["--task", "--start", "--goal", "--world", "--figure"],
                     "is for an office task; with --problem the start and goal are the "
                     "problem's own")
        domain, path, _ = pddl_files(args, "office")
        problem = PlanningProblem.from_files(domain, path, determinisation(args))
        start = goal = None
        source = str(args.problem)
    else:
        refuse_given(args, ["--determinisation"], "is for a PPDDL domain (with --problem); "
                     "an office task has no determinisation to choose")
        world, task = world_and_task(args)
        dtext, dsrc = (domain_text(), "office.pddl (built in)") if args.domain is None else \
            (read_pddl_text(resolve("domain", args.domain)), args.domain)
        source = f"task {task.name} (generated from {world.source})"
        problem = PlanningProblem.from_texts(dtext, office_problem(world, task), dsrc, source)
        abstraction = OfficeAbstraction(world)
        start, goal = None, abstraction.goal(task.goal)
        if args.figure is not None:
            output_file(args.figure, "--figure")
    try:
        result = planner.solve(problem, start, goal, args.tolerance)
    except MemoryError:
        raise SizeError(f"{source}: planning ran out of memory; give a smaller problem"
                        + (" or a smaller --tolerance" if args.tolerance else "")) from None
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
    if args.figure is not None:
        _plans_figure(args.figure, world, task, result.plans, abstraction)
    if result.length == 0:
        print("gdq-pddl: warning: the goal already holds at the start (or is empty): the plan "
              "has no action, and `gdq-pddl run` refuses such a task", file=sys.stderr)
    return 0


def _plans_figure(path: Path, world, task, plans, abstraction: OfficeAbstraction) -> None:
    """The planner's ``plans`` drawn on the map of ``world``, as the learner's moves."""
    from matplotlib.figure import Figure  # start-up time: matplotlib loads when drawing

    from gdq_pddl.envs.render import MapPainter, plan_route  # start-up time, as above

    routes = [plan_route(abstraction.spaces, [(abstraction.learner_state(s),
                                               abstraction.learner_action(a))
                                              for s, a in plan.pairs()]) for plan in plans]
    fig = Figure(figsize=(6.5, 6.5 + 0.2 * len(routes)), layout="constrained")
    ax = fig.add_subplot()
    MapPainter(world).draw_plans(ax, routes, task)
    ax.set_title(f"task {task.name}: {len(routes)} plan(s) from {task.start} to {task.goal} "
                 "(blue ring: start, green: goal)", fontsize=10)
    save_figure(fig, path, dpi=100)
    print(f"figure: {path}")


def _plan_json(plan, abstraction) -> dict:
    out: dict = {"actions": list(plan.actions)}
    if abstraction is not None:
        sp = abstraction.spaces
        out["learner"] = [{"state": sp.state_name(abstraction.learner_state(s)),
                           "action": sp.action_name(abstraction.learner_action(a))}
                          for s, a in plan.pairs()]
    return out


def register_planners(sub) -> None:
    p = sub.add_parser("planners", help="list the planner backends and whether they can run",
                       description="List every backend registered under the `gdq_pddl.planners` "
                                   "entry-point group, by this package or any other.")
    p.add_argument("--json", action="store_true", help="machine-readable output")
    p.set_defaults(func=cmd_planners)


def cmd_planners(args: argparse.Namespace) -> int:
    infos = planners()
    if args.json:
        print(json.dumps([{"name": i.name, "usable": i.usable, "reason": i.reason}
                          for i in infos], indent=2))
        return 0
    for i in infos:
        state = "usable" if i.usable else f"not usable: {i.reason}"
        print(f"{i.name:12s} {state}   ({i.target})")
    return 0


def register_list(sub) -> None:
    p = sub.add_parser("list", help="the shipped domains, problems, dynamics, worlds, planners",
                       description="List what every --domain, --problem, --dynamics and "
                                   "--world option (and gymnasium.make) takes by name: the "
                                   "files that ship with the package; and the planners "
                                   "registered under the `gdq_pddl.planners` entry-point "
                                   "group.")
    p.add_argument("--json", action="store_true", help="machine-readable output")
    p.set_defaults(func=cmd_list)


def cmd_list(args: argparse.Namespace) -> int:
    shipped = {
        "domains": shipped_names("domain"),
        "problems": {name: problem_domain(resolve("problem", name))
                     for name in shipped_names("problem")},
        "dynamics": shipped_names("dynamics"),
        "worlds": {name: list(builtin_world(name).tasks) for name in shipped_names("world")},
        "planners": {i.name: i.reason if not i.usable else "usable" for i in planners()},
        "methods": {e.name: e.description + (f" ({need})" if (need := registry.missing(e))
                                             else "") for e in registry.entries()}}
    if args.json:
        print(json.dumps(shipped, indent=2))
        return 0
    print("domains (--domain):   ", " ".join(shipped["domains"]))
    print("problems (--problem), with their domain:")
    for name, domain in shipped["problems"].items():
        print(f"  {name:22s} {domain}")
    print("dynamics (--dynamics):", " ".join(shipped["dynamics"]))
    print("worlds (--world), with their tasks (--task):")
    for name, tasks in shipped["worlds"].items():
        print(f"  {name:22s} {' '.join(tasks)}")
    print("planners (--planner; entry-point group gdq_pddl.planners):")
    for name, state in shipped["planners"].items():
        print(f"  {name:22s} {state}")
    print("methods (--method; entry-point group gdq_pddl.learners; settings: gdq-pddl methods):")
    for name, description in shipped["methods"].items():
        print(f"  {name:22s} {description}")
    for why in registry.plugin_problems():
        print(f"  warning: {why}")
    return 0
