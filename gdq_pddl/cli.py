"""The ``gdq-pddl`` command line.

Every subcommand turns bad input (a malformed file, an unknown position, task or
planner) into one clear message on stderr and a non-zero exit, never a traceback.
"""

from __future__ import annotations

import argparse
import json
import sys
from collections.abc import Callable, Sequence
from pathlib import Path

from gdq_pddl.errors import GdqError

EXIT_ERROR, EXIT_NO_PLAN = 2, 1


def main(argv: Sequence[str] | None = None) -> int:
    """Entry point of ``gdq-pddl``; returns the exit status."""
    parser = build_parser()
    args = parser.parse_args(argv)
    if not hasattr(args, "func"):
        parser.print_help()
        return EXIT_ERROR
    try:
        return args.func(args)
    except GdqError as exc:
        print(f"gdq-pddl: error: {exc}", file=sys.stderr)
        return EXIT_ERROR
    except KeyboardInterrupt:
        print("gdq-pddl: interrupted", file=sys.stderr)
        return 130


def build_parser() -> argparse.ArgumentParser:
    parser = argparse.ArgumentParser(
        prog="gdq-pddl",
        description="Guided Dyna-Q: reinforcement learning whose exploration is guided by "
                    "a PDDL planner. Start with `gdq-pddl plan --task C` to see the plans "
                    "the learner is given, then `gdq-pddl run --task C`.")
    sub = parser.add_subparsers(title="commands", metavar="COMMAND")
    for register in COMMANDS:
        register(sub)
    return parser


def _task_args(p: argparse.ArgumentParser, world: bool = True) -> None:
    p.add_argument("--task", help="a task of the world file (office: A B C D E X)")
    p.add_argument("--start", help="start position or landmark (with --goal, instead of --task)")
    p.add_argument("--goal", help="goal position or landmark")
    if world:
        p.add_argument("--world", type=Path, help="world file (TOML); default: the built-in office")


def _world_and_task(args: argparse.Namespace):
    from gdq_pddl.world import load_world

    world = load_world(args.world)
    if args.task is None and args.start is None and args.goal is None:
        raise GdqError("give --task, or --start and --goal")
    task = world.resolve(args.task, args.start, args.goal)
    if task.start == task.goal:
        raise GdqError(f"start and goal are the same position ({task.start})")
    return world, task


# --- problem ----------------------------------------------------------------------------

def _register_problem(sub) -> None:
    p = sub.add_parser("problem", help="write the PDDL problem for a task, from the world file",
                       description="Write the PDDL problem of a task, generated from the world "
                                   "file. The files in problems/ are this command's output.")
    _task_args(p)
    p.add_argument("--all", action="store_true", help="every task of the world")
    p.add_argument("--out", type=Path,
                   help="output file (a folder with --all: writes task-<x>.pddl there)")
    p.set_defaults(func=cmd_problem)


def cmd_problem(args: argparse.Namespace) -> int:
    from gdq_pddl.pddl.office import office_problem
    from gdq_pddl.world import load_world

    if args.all:
        world = load_world(args.world)
        out = args.out or Path("problems")
        out.mkdir(parents=True, exist_ok=True)
        for name, task in world.tasks.items():
            path = out / f"task-{name.lower()}.pddl"
            path.write_text(office_problem(world, task), encoding="utf-8")
            print(path)
        return 0
    world, task = _world_and_task(args)
    text = office_problem(world, task)
    if args.out:
        args.out.write_text(text, encoding="utf-8")
    else:
        sys.stdout.write(text)
    return 0


# --- plan -------------------------------------------------------------------------------

def _register_plan(sub) -> None:
    p = sub.add_parser("plan", help="all shortest plans from a start to a goal",
                       description="Plan with the robot's knowledge (the PDDL domain) and show "
                                   "each plan with the learner state/action each step maps to.")
    _task_args(p)
    p.add_argument("--planner", default="graph", help="planner backend (see `gdq-pddl planners`)")
    p.add_argument("--tolerance", type=float, default=0.0,
                   help="also every loop-free plan up to (1+T) x the shortest length")
    p.add_argument("--domain", type=Path, help="PDDL domain file (default: the office domain)")
    p.add_argument("--problem", type=Path,
                   help="PDDL problem file (instead of --task/--start/--goal; no learner mapping)")
    p.add_argument("--json", action="store_true", help="machine-readable output")
    p.set_defaults(func=cmd_plan)


def cmd_plan(args: argparse.Namespace) -> int:
    from gdq_pddl.planning import PlanningProblem, Status, get_planner

    planner = get_planner(args.planner)
    abstraction = None
    if args.problem is not None:
        domain = args.domain or _shipped_domain()
        problem = PlanningProblem.from_files(domain, args.problem)
        start = goal = None
    else:
        from gdq_pddl.abstraction import OfficeAbstraction
        from gdq_pddl.pddl.office import office_problem
        from gdq_pddl.resources import domain_text

        world, task = _world_and_task(args)
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


# --- planners ---------------------------------------------------------------------------

def _register_planners(sub) -> None:
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


COMMANDS: list[Callable] = [_register_problem, _register_plan, _register_planners]

if __name__ == "__main__":
    raise SystemExit(main())
