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
    except BrokenPipeError:  # output piped into `head` and closed early: not an error
        sys.stderr.close()
        return 0


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


# --- building ---------------------------------------------------------------------------

def _register_building(sub) -> None:
    p = sub.add_parser("building", help="generate an office-like building of N positions",
                       description="Write a generated building: a world file (TOML), the "
                                   "office domain and a PDDL problem per task. The same "
                                   "--positions, --seed and --doors give the same files.")
    p.add_argument("--positions", type=int, required=True, help="number of positions")
    p.add_argument("--seed", type=int, default=0, help="random seed (default 0)")
    p.add_argument("--doors", type=int, help="number of doors (default positions // 8)")
    p.add_argument("--out", type=Path, help="output folder (default results/building)")
    p.set_defaults(func=cmd_building)


def cmd_building(args: argparse.Namespace) -> int:
    from gdq_pddl.buildings import write_building

    world, problems = write_building(args.out or Path("results/building"), args.positions,
                                     args.seed, args.doors)
    for path in (world, *problems):
        print(path)
    return 0


# --- scale ------------------------------------------------------------------------------

def _register_scale(sub) -> None:
    p = sub.add_parser("scale", help="learning against building size (generated buildings)",
                       description="Run every method on generated buildings of each size "
                                   "and write scale.png/pdf and REPORT.md (episodes to "
                                   "convergence, env steps/s).")
    p.add_argument("--sizes", type=int, nargs="+", default=[100, 300, 1000])
    p.add_argument("--runs", type=int, default=3)
    p.add_argument("--episodes", type=int, default=1000)
    p.add_argument("--seed", type=int, default=0)
    p.add_argument("--out", type=Path, help="output folder (default results/scale)")
    p.set_defaults(func=cmd_scale)


def cmd_scale(args: argparse.Namespace) -> int:
    from gdq_pddl.analysis.scale import figure, report
    from gdq_pddl.experiments.scale import run_size

    out = args.out or Path("results/scale")
    out.mkdir(parents=True, exist_ok=True)
    results = [run_size(n, args.runs, args.episodes, args.seed) for n in args.sizes]
    figure(results, args.episodes, out)
    print(report(results, args.runs, args.episodes, args.seed, out))
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


# --- experiments ------------------------------------------------------------------------

def _run_args(p: argparse.ArgumentParser, methods: Sequence[str] | None = None,
              episodes: int = 2500, runs: int = 10) -> None:
    from gdq_pddl.experiments import METHODS, PAPER_METHODS

    p.add_argument("--method", nargs="+", metavar="M", default=list(methods or PAPER_METHODS),
                   help=f"methods to compare (from: {', '.join(METHODS)})")
    p.add_argument("--episodes", type=int, default=episodes, help="episodes per run (per task)")
    p.add_argument("--runs", type=int, default=runs, help="independent runs per method")
    p.add_argument("--seed", type=int, default=0, help="base seed (each run derives its own)")
    p.add_argument("--planner", default="graph", help="planner backend for GDQ and DARLING")
    _exec_args(p)


def _exec_args(p: argparse.ArgumentParser) -> None:
    p.add_argument("--jobs", type=int, help="parallel processes (default: all cores)")
    p.add_argument("--out", type=Path, help="output folder (default: results/<command>)")
    p.add_argument("--resume", action="store_true",
                   help="continue an interrupted run in --out (same command line)")
    p.add_argument("--executor", choices=("local", "ray"), default="local",
                   help="local processes, or a Ray cluster")
    p.add_argument("--address", help="Ray cluster address (default: start a local instance)")
    p.add_argument("--no-report", action="store_true", help="skip figures, tables and report")


def _register_run(sub) -> None:
    p = sub.add_parser("run", help="compare methods on one task",
                       description="Each method learns the task from scratch --runs times for "
                                   "--episodes episodes. Writes episodes.csv, figures and "
                                   "REPORT.md to --out.")
    _task_args(p)
    p.add_argument("--domain", type=Path,
                   help="a PDDL domain: with --problem and --dynamics, learn on that problem "
                        "instead of an office task (see docs/domains.md)")
    p.add_argument("--problem", type=Path, help="a PDDL problem of --domain")
    p.add_argument("--dynamics", type=Path,
                   help="the dynamics file (TOML) of --domain: success, failure, costs")
    _run_args(p)
    p.set_defaults(func=cmd_run)


def _register_switch(sub) -> None:
    p = sub.add_parser("switch", help="change the task halfway (the paper's Hypothesis III)",
                       description="Learn --from for --episodes episodes, then --to for as many; "
                                   "GDQ keeps its learned model and replans for the new goal.")
    p.add_argument("--from", dest="first", default="C", help="first task (default C)")
    p.add_argument("--to", dest="second", default="D", help="second task (default D)")
    p.add_argument("--world", type=Path, help="world file (TOML); default: the built-in office")
    _run_args(p)
    p.set_defaults(func=cmd_switch)


def _register_robot(sub) -> None:
    p = sub.add_parser("robot", help="the paper's real-robot protocol, simulated",
                       description="Task X on the office with area 5 forbidden, 10 actions per "
                                   "trial, R_max 1000, durations as costs, alpha 0.5.")
    _run_args(p, methods=("GDQ", "Dyna-Q", "GDQ-code"), episodes=30, runs=10)
    p.set_defaults(func=cmd_robot)


def _register_reproduce(sub) -> None:
    p = sub.add_parser("reproduce", help="every experiment of the paper, with figures and report",
                       description="Tasks A-D (2500 episodes x 10 runs), the switches C->D and "
                                   "C->E (5000 episodes), the robot protocol; then figures, the "
                                   "area-visit table and REPORT.md in --out.")
    p.add_argument("--quick", action="store_true", help="300 episodes x 3 runs: a first look")
    p.add_argument("--seed", type=int, default=0, help="base seed")
    _exec_args(p)
    p.set_defaults(func=cmd_reproduce)


def _register_knowledge(sub) -> None:
    from gdq_pddl.experiments.knowledge import KNOWLEDGE_METHODS

    p = sub.add_parser("knowledge", help="learn with PDDL knowledge that disagrees with the world",
                       description="Task C with a door locked in reality but usable in the "
                                   "knowledge (d3, d1), a corridor only reality has, and a "
                                   "control; each also with accurate knowledge. Writes "
                                   "episodes.csv, figures and REPORT.md to --out.")
    p.add_argument("--episodes", type=int, default=1500, help="episodes per run")
    p.add_argument("--runs", type=int, default=10, help="independent runs per method and case")
    p.add_argument("--seed", type=int, default=0, help="base seed (each run derives its own)")
    p.add_argument("--method", nargs="+", metavar="M", default=list(KNOWLEDGE_METHODS),
                   help="methods to compare")
    _exec_args(p)
    p.set_defaults(func=cmd_knowledge)


def _register_report(sub) -> None:
    p = sub.add_parser("report", help="redraw figures, tables and REPORT.md of an output folder")
    p.add_argument("out", type=Path, help="an output folder of run/switch/robot/reproduce")
    p.set_defaults(func=cmd_report)


def _experiment_kw(args: argparse.Namespace) -> dict:
    from gdq_pddl.experiments import METHODS

    unknown = [m for m in args.method if m not in METHODS]
    if unknown:
        raise GdqError(f"unknown method {unknown[0]!r} (known: {', '.join(METHODS)})")
    if args.episodes < 1 or args.runs < 1:
        raise GdqError("--episodes and --runs must be at least 1")
    return {"methods": tuple(dict.fromkeys(args.method)), "runs": args.runs, "seed": args.seed,
            "planner": args.planner}


def _check_planner(name: str) -> None:
    from gdq_pddl.planning import get_planner

    get_planner(name)  # fail now, with the list of known planners, not inside a worker


def cmd_run(args: argparse.Namespace) -> int:
    from gdq_pddl.experiments import Experiment

    if args.domain or args.problem or args.dynamics:
        return _run_pddl(args)
    world, task = _world_and_task(args)
    kw = _experiment_kw(args)
    _check_planner(args.planner)
    spec = task.name if task.name in world.tasks else f"{task.start}->{task.goal}"
    exp = Experiment("run", ((spec, args.episodes),), world=str(args.world or "office"), **kw)
    return _execute([exp], args, f"run-{task.name}")


def _run_pddl(args: argparse.Namespace) -> int:
    from gdq_pddl.analysis.generic import write_generic_report
    from gdq_pddl.experiments import Experiment
    from gdq_pddl.experiments.work import load_pddl_instance

    if not (args.domain and args.problem and args.dynamics):
        raise GdqError("a PDDL run needs --domain, --problem and --dynamics")
    if args.task or args.start or args.goal or args.world:
        raise GdqError("--task/--start/--goal/--world are for the office; a PDDL run takes "
                       "its start and goal from --problem")
    files = tuple(str(p) for p in (args.domain, args.problem, args.dynamics))
    instance = load_pddl_instance(files)  # check the files (and size) before any worker
    instance.model  # noqa: B018
    kw = _experiment_kw(args)
    _check_planner(args.planner)
    exp = Experiment("run", ((instance.name, args.episodes),), world="pddl", pddl=files, **kw)
    return _execute([exp], args, f"run-{instance.name}", report=write_generic_report)


def cmd_switch(args: argparse.Namespace) -> int:
    from gdq_pddl.experiments import switch_experiment
    from gdq_pddl.world import load_world

    world = load_world(args.world)
    first, second = world.task(args.first).name, world.task(args.second).name
    kw = _experiment_kw(args)
    _check_planner(args.planner)
    exp = switch_experiment(first, second, args.episodes, world=str(args.world or "office"), **kw)
    return _execute([exp], args, exp.name)


def cmd_robot(args: argparse.Namespace) -> int:
    from dataclasses import replace

    from gdq_pddl.experiments import robot_experiment

    kw = _experiment_kw(args)
    _check_planner(args.planner)
    exp = robot_experiment(runs=kw.pop("runs"), **kw)
    exp = replace(exp, schedule=(("X", args.episodes),))
    return _execute([exp], args, "robot")


def cmd_reproduce(args: argparse.Namespace) -> int:
    from gdq_pddl.experiments import paper_protocol

    name = "reproduce-quick" if args.quick else "reproduce"
    return _execute(paper_protocol(quick=args.quick, seed=args.seed), args, name)


def cmd_knowledge(args: argparse.Namespace) -> int:
    from gdq_pddl.experiments import METHODS, run_experiments
    from gdq_pddl.experiments.knowledge import knowledge_experiments

    unknown = [m for m in args.method if m not in METHODS]
    if unknown:
        raise GdqError(f"unknown method {unknown[0]!r} (known: {', '.join(METHODS)})")
    if args.episodes < 1 or args.runs < 1:
        raise GdqError("--episodes and --runs must be at least 1")
    exps = knowledge_experiments(args.episodes, args.runs, args.seed,
                                 tuple(dict.fromkeys(args.method)))
    out = args.out or Path("results") / "knowledge"
    run_experiments(exps, out, jobs=args.jobs, executor=args.executor, address=args.address,
                    resume=args.resume)
    print(f"ran {sum(e.runs * len(e.methods) for e in exps)} runs; results in "
          f"{out}/episodes.csv")
    if not args.no_report:
        from gdq_pddl.analysis.knowledge import make_knowledge_report

        command = (f"gdq-pddl knowledge --episodes {args.episodes} --runs {args.runs} "
                   f"--seed {args.seed}")
        paths = make_knowledge_report(out, command)
        print(f"wrote {len(paths)} figures and reports; read {out / 'REPORT.md'}")
    return 0


def cmd_report(args: argparse.Namespace) -> int:
    if not (args.out / "episodes.csv").exists():
        raise GdqError(f"{args.out} has no episodes.csv: is it an output folder of gdq-pddl?")
    _report(args.out)
    return 0


def _execute(experiments, args: argparse.Namespace, name: str, report=None) -> int:
    import time

    from gdq_pddl.experiments import run_experiments

    out = args.out or Path("results") / name
    t0 = time.perf_counter()
    run_experiments(experiments, out, jobs=args.jobs, executor=args.executor,
                    address=args.address, resume=args.resume)
    print(f"ran {sum(e.runs * len(e.methods) for e in experiments)} runs in "
          f"{time.perf_counter() - t0:.1f} s; results in {out}/episodes.csv")
    if not args.no_report and report is not None:
        print(f"wrote {report(out)}")
    elif not args.no_report:
        _report(out)
    return 0


def _report(out: Path) -> None:
    from gdq_pddl.analysis import make_all

    paths = make_all(out)
    report = next((p for p in paths if p.name == "REPORT.md"), None)
    print(f"wrote {len(paths)} figures, tables and reports" +
          (f"; read {report}" if report else ""))


COMMANDS: list[Callable] = [_register_problem, _register_building, _register_plan,
                            _register_planners, _register_run, _register_switch, _register_robot,
                            _register_reproduce, _register_report, _register_knowledge,
                            _register_scale]

if __name__ == "__main__":
    raise SystemExit(main())
