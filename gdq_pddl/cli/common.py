"""What the subcommands share: task and run options, validation, running and reporting."""

from __future__ import annotations

import argparse
import math
import sys
import time
from collections.abc import Callable, Sequence
from pathlib import Path

from gdq_pddl.errors import ConfigError, GdqError, SizeError
from gdq_pddl.experiments import DEFAULT_METHODS, Experiment, run_experiments
from gdq_pddl.experiments.checks import check_report_size, check_sizes
from gdq_pddl.experiments.protocol import safe_name
from gdq_pddl.experiments.runner import saved_units
from gdq_pddl.learners import registry
from gdq_pddl.learners.episodes import loops_cached
from gdq_pddl.limits import MAX_COUNT, MAX_TOLERANCE, MAX_WORLD_POSITIONS
from gdq_pddl.pddl.ppddl import DETERMINISATIONS
from gdq_pddl.pddl.problem_reader import problem_file
from gdq_pddl.planning import get_planner
from gdq_pddl.resources import problem_domain, resolve, resolve_pddl, shipped_names
from gdq_pddl.world import load_world
from gdq_pddl.world_types import Task, World

EXIT_ERROR, EXIT_NO_PLAN = 2, 1


def whole(low: int) -> Callable[[str], int]:
    """An argparse type: a whole number >= ``low`` (and small enough for int64)."""
    def parse(text: str) -> int:
        try:
            value = int(text)
        except ValueError:
            raise argparse.ArgumentTypeError(f"expected a whole number, got {text!r}") from None
        if value < low:
            raise argparse.ArgumentTypeError(f"must be a whole number >= {low}, got {text}")
        if value > MAX_COUNT:
            raise argparse.ArgumentTypeError(f"must be at most {MAX_COUNT:_}, got {text}")
        return value

    return parse


def tolerance_arg(text: str) -> float:
    """An argparse type: a plan-length tolerance, a finite number in ``[0, MAX_TOLERANCE]``."""
    try:
        value = float(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"expected a number, got {text!r}") from None
    if not math.isfinite(value) or not 0 <= value <= MAX_TOLERANCE:
        raise argparse.ArgumentTypeError(f"must be a finite number in [0, {MAX_TOLERANCE:g}] "
                                         f"(plans up to {1 + MAX_TOLERANCE:g} x the shortest), "
                                         f"got {text}")
    return value


POSITIVE, NONNEGATIVE = whole(1), whole(0)


def note(message: str) -> None:
    """A line for the user on stderr (stdout stays the results)."""
    print(f"gdq-pddl: {message}", file=sys.stderr)


def task_args(p: argparse.ArgumentParser, world: bool = True) -> None:
    p.add_argument("--task", help="a task of the world file (office: A B C D E X)")
    p.add_argument("--start", help="start position or landmark (with --goal, instead of --task)")
    p.add_argument("--goal", help="goal position or landmark")
    if world:
        world_arg(p)


def world_arg(p: argparse.ArgumentParser) -> None:
    """--world: a world file, or a shipped world's name, resolved to its file at once."""
    def parse(text: str) -> Path:
        try:
            return resolve("world", text)
        except GdqError as exc:
            raise argparse.ArgumentTypeError(str(exc)) from None

    p.add_argument("--world", type=parse, help=f"world file (TOML), or a shipped world "
                   f"({', '.join(shipped_names('world'))}; default: office)")


def determinisation(args: argparse.Namespace) -> str:
    """The --determinisation given, or the default one."""
    return args.determinisation or DETERMINISATIONS[0]


def pddl_args(p: argparse.ArgumentParser, what: str, dynamics: bool = False) -> None:
    """--domain, --problem (``what`` the command does with it), --dynamics if
    ``dynamics``, and --determinisation (default None: :func:`determinisation`)."""
    named = "a file, or a shipped name (`gdq-pddl list` shows them)"
    p.add_argument("--domain", help=f"a PDDL domain: {named}; default: the --problem file "
                   "if it holds one, else the shipped domain --problem names")
    p.add_argument("--problem", help=f"a PDDL problem instead of an office task ({named}): "
                   f"{what}; FILE:NAME picks the problem NAME of a file that holds several")
    if dynamics:
        p.add_argument("--dynamics", help=f"the dynamics file (TOML) of --domain: {named}; "
                       "success, failure and costs of a STRIPS domain's actions, an optional "
                       "overlay (r_max, step_limit, costs) for a PPDDL domain; default: the "
                       "shipped dynamics of a shipped --domain, if there is one")
    p.add_argument("--determinisation", choices=DETERMINISATIONS, default=None,
                   help="what the planner knows of a PPDDL domain: every outcome of an "
                        "action is a planner action (all-outcomes, the default), or only its "
                        "most likely one (most-likely)")


def pddl_files(args: argparse.Namespace, default_domain: str | None = None
               ) -> tuple[Path | None, Path | None, Path | None]:
    """--domain, --problem and --dynamics as files (--domain: by default the problem's:
    the shipped one it names, or the problem file itself if it defines one, else
    ``default_domain``; with none of these, an error saying which domain to give)."""
    domain = args.domain
    if domain is None and args.problem is not None:
        path = resolve("problem", problem_file(args.problem)[0])
        named = problem_domain(path)
        domain = named if named in (*shipped_names("domain"), str(path)) else default_domain
        if domain is None:  # IPPC-2008 ships problems apart from their domain
            raise GdqError(f"{path} holds a problem of domain {named or '(none named)'} and "
                           f"no domain, and {named or 'it'} is not a shipped domain: give "
                           "the file that defines it with --domain")
    if domain is None or args.problem is None:
        return None, None, None
    return resolve_pddl(domain, args.problem, getattr(args, "dynamics", None))


def refuse_given(args: argparse.Namespace, options: Sequence[str], why: str) -> None:
    """Refuse the first of ``options`` given on the command line (it would be ignored)."""
    for option in options:
        if getattr(args, option.removeprefix("--").replace("-", "_"), None) is not None:
            raise ConfigError(f"{option} {why}")


def load_world_checked(path: Path | None) -> World:
    """The world of ``--world`` (None: the office), refused if too large to plan over."""
    world = load_world(path)
    if len(world.positions) > MAX_WORLD_POSITIONS:
        raise SizeError(f"{world.source}: {len(world.positions):,} positions, more than the "
                        f"{MAX_WORLD_POSITIONS:,} a world may have to be planned over (its "
                        "grounded problem grows with the square of the positions); give a "
                        "smaller world")
    return world


def world_and_task(args: argparse.Namespace) -> tuple[World, Task]:
    world = load_world_checked(args.world)
    if args.task is None and args.start is None and args.goal is None:
        raise GdqError("give --task, or --start and --goal")
    return world, world.resolve(args.task, args.start, args.goal)


def run_args(p: argparse.ArgumentParser, out: str, methods: Sequence[str] | None = None,
             episodes: int = 2500, runs: int = 10) -> None:
    """The options of a command that runs methods; ``out`` names its default --out."""
    size_args(p, methods or DEFAULT_METHODS, registry.names(), episodes, runs)
    readers = ", ".join(e.name for e in registry.BUILT_IN if e.knowledge == "plans")
    p.add_argument("--planner", default="graph",
                   help=f"planner backend of the methods that read plans ({readers}); the "
                   "default GDQ reads the knowledge as a prior and never asks a planner")
    exec_args(p, out)


def size_args(p: argparse.ArgumentParser, methods: Sequence[str], known: Sequence[str],
              episodes: int, runs: int, seed: str = "base seed (each run derives its own)"
              ) -> None:
    """--method (default ``methods``, from ``known``), --episodes, --runs and --seed."""
    p.add_argument("--method", nargs="+", metavar="M", default=list(methods),
                   help=f"methods to compare (default: {' '.join(methods)}; from: "
                        f"{', '.join(known)}; any case; NAME:key=value,... sets a "
                        "learner's settings, `gdq-pddl methods` lists them)")
    p.add_argument("--episodes", type=POSITIVE, default=episodes,
                   help=f"episodes per run (per task; default {episodes})")
    p.add_argument("--runs", type=POSITIVE, default=runs,
                   help=f"independent runs per method (and case, or building; paired "
                        f"across methods; default {runs})")
    p.add_argument("--seed", type=NONNEGATIVE, default=0, help=seed)


def exec_args(p: argparse.ArgumentParser, out: str) -> None:
    """--jobs, --out (default ``out``), --resume and the executor's options."""
    p.add_argument("--jobs", type=POSITIVE,
                   help="parallel processes (default: all cores; never more than the runs)")
    p.add_argument("--out", type=Path, help=f"output folder (default: {out})")
    p.add_argument("--resume", action="store_true",
                   help="continue an interrupted run in --out (same command line)")
    p.add_argument("--executor", choices=("local", "ray"), default="local",
                   help="local processes, or a Ray cluster")
    p.add_argument("--address", help="Ray cluster address, with --executor ray (default: "
                                     "start a local instance)")
    p.add_argument("--no-report", action="store_true", help="skip figures, tables and report")


def checked_methods(args: argparse.Namespace) -> tuple[str, ...]:
    """The --method names (with their settings), checked, canonical (a learner's own name,
    in any case on input) and without repeats."""
    return tuple(dict.fromkeys(registry.canonical(m) for m in args.method))


def experiment_kw(args: argparse.Namespace) -> dict:
    """Experiment fields from the run options, the planner checked."""
    methods = checked_methods(args)
    check_planner(args.planner, methods)
    deep = [m for m in methods if registry.parse_method(m).entry.extra]
    if getattr(args, "keep_learners", False) and deep:
        raise GdqError(f"--keep-learners saves tabular learners; {', '.join(deep)} "
                       "cannot be saved so")
    return {"methods": methods, "runs": args.runs, "seed": args.seed,
            "planner": args.planner}


def check_planner(name: str, methods: Sequence[str] = ()) -> None:
    """Fail now, not inside a worker, on an unknown planner; warn when one that returns
    one plan per query is given to methods that learn from every plan."""
    planner = get_planner(name)
    users = [m for m in methods if registry.parse_method(m).entry.knowledge != "none"]
    if users and not getattr(planner, "all_plans", True):
        note(f"warning: planner {name} returns one plan per query: {', '.join(users)} "
             "learn from that plan alone where the graph planner gives every shortest plan "
             "(and every plan within a tolerance)")


def office_report(out: Path) -> str:
    """Figures, tables and REPORT.md of an office output folder; returns what was written."""
    from gdq_pddl.analysis import make_all  # start-up time: matplotlib and numba

    paths = make_all(out)
    report = next((p for p in paths if p.name == "REPORT.md"), None)
    return f"wrote {len(paths)} figures, tables and reports" + \
        (f"; read {report}" if report else "")


def out_folder(args: argparse.Namespace, name: str) -> Path:
    """--out, or by default ``results/<safe name>``."""
    return args.out or Path("results") / safe_name(name)


def execute(experiments: list[Experiment], args: argparse.Namespace, name: str,
            report: Callable[[Path], str] = office_report, results: str = "episodes.csv",
            **run_kw) -> int:
    """Run ``experiments`` into --out (default results/<safe name>), then ``report`` on it;
    ``results`` names the collected file, ``run_kw`` goes to ``run_experiments``."""
    if args.address is not None and args.executor != "ray":
        raise ConfigError("--address is the Ray cluster's address: it needs --executor ray "
                          f"(the executor is {args.executor})")
    out = out_folder(args, name)
    check_sizes(experiments, args.jobs or 1)  # the runs first: their message names options
    if not args.no_report:
        check_report_size(experiments)
    before = saved_units(out, experiments) if args.resume else 0
    t0 = time.perf_counter()
    if not loops_cached({m for e in experiments for m in e.methods}):
        note("compiling the learners' code for its first use (numba caches it for the next "
             "runs): this takes 10-60 s")
    run_experiments(experiments, out, jobs=args.jobs, executor=args.executor,
                    address=args.address, resume=args.resume, log=note, **run_kw)
    ran = sum(e.runs * len(e.methods) for e in experiments) - before
    print(f"ran {ran} runs in {time.perf_counter() - t0:.1f} s; results in {out}/{results}")
    if not args.no_report:
        print(report(out))
    return 0
