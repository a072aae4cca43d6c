"""Subcommands that run experiments: run, switch, robot, reproduce, knowledge, scale, pairs,
report."""

from __future__ import annotations

import argparse
import sys
from dataclasses import replace
from functools import partial
from pathlib import Path

from gdq_pddl.cli.common import (
    NONNEGATIVE,
    POSITIVE,
    checked_methods,
    determinisation,
    exec_args,
    execute,
    experiment_kw,
    load_world_checked,
    out_folder,
    pddl_args,
    pddl_files,
    refuse_given,
    run_args,
    size_args,
    task_args,
    world_and_task,
    world_arg,
)
from gdq_pddl.envs.online import OnlineInstance
from gdq_pddl.errors import GdqError, SizeError, TooManyStates
from gdq_pddl.experiments import (
    Experiment,
    pairs,
    paper_protocol,
    robot_experiment,
    switch_experiment,
)
from gdq_pddl.experiments.collect import collect
from gdq_pddl.experiments.knowledge import (
    KNOWLEDGE_METHODS,
    knowledge_experiments,
    knowledge_instance,
    world_name,
)
from gdq_pddl.experiments.protocol import DEFAULT_METHODS, ProblemSpec
from gdq_pddl.experiments.runner import resumed_exploration
from gdq_pddl.experiments.work import load_pddl_instance
from gdq_pddl.learners import registry
from gdq_pddl.outputs import output_folder
from gdq_pddl.pddl.reachable import factored_reason

EXPLORE = ("auto", "enumerate", "online")
"""``gdq-pddl run --explore``: how a PPDDL problem's states are found."""


def register_run(sub) -> None:
    p = sub.add_parser("run", help="compare methods on one task",
                       description="Each method learns the task from scratch --runs times for "
                                   "--episodes episodes. Writes episodes.csv, figures and "
                                   "REPORT.md to --out.")
    task_args(p)
    pddl_args(p, "learn on it (a STRIPS domain needs --dynamics, a PPDDL domain is its "
              "own reality: docs/domains.md)", dynamics=True)
    run_args(p, "results/run-<task>, or results/run-<problem name> for --problem")
    p.add_argument("--explore", choices=EXPLORE, default="auto",
                   help="a PPDDL problem's states: 'enumerate' them all first (V* in the "
                        "report), find them 'online' as episodes reach them (any size; no "
                        "V*), or 'auto' (default): online only where they do not fit")
    p.add_argument("--knowledge-domain", type=Path, metavar="FILE",
                   help="a PPDDL run's knowledge: the learners plan on this domain file "
                        "(with --problem), the env simulates --domain; it must give "
                        "--domain's states and outcomes, its probabilities may differ "
                        "(default: --domain itself)")
    p.add_argument("--keep-learners", action="store_true",
                   help="save each run's final learner in --out/learners/<run>.npz "
                        "(gdq_pddl.load_learner reads it)")
    p.set_defaults(func=cmd_run)


def cmd_run(args: argparse.Namespace) -> int:
    if args.domain or args.problem or args.dynamics:
        return _run_pddl(args)
    refuse_given(args, ["--determinisation"], "is for a PPDDL domain (with --domain and "
                 "--problem); an office task has no determinisation to choose")
    refuse_given(args, ["--knowledge-domain"], "is for a PPDDL run (with --problem)")
    if args.explore != "auto":
        raise GdqError("--explore is for a PPDDL problem (with --problem); the office's "
                       "states are always enumerated")
    world, task = world_and_task(args)
    kw = experiment_kw(args)
    spec = task.name if task.name in world.tasks else f"{task.start}->{task.goal}"
    exp = Experiment("run", ((spec, args.episodes),), world=world_name(args.world), **kw)
    return execute([exp], args, f"run-{task.name}", keep_learners=args.keep_learners)


def _run_pddl(args: argparse.Namespace) -> int:
    if args.task or args.start or args.goal or args.world:
        raise GdqError("--task/--start/--goal/--world are for the office; a PDDL run takes "
                       "its start and goal from --problem")
    domain, problem, dynamics = pddl_files(args)
    if domain is None or problem is None:
        raise GdqError("a PDDL run needs --problem, and --domain unless the problem names a "
                       "shipped domain (and --dynamics for a STRIPS domain of your own)")
    spec = ProblemSpec(str(domain), str(problem), "" if dynamics is None else str(dynamics),
                       determinisation(args))
    explore = args.explore
    because = "`--explore online` was given"  # why a problem is explored online
    try:  # check the files (and size) before any worker
        instance = load_pddl_instance(spec)
        factored = factored_reason(instance.problem.learner_task, str(problem))
        if args.resume:  # as the run went, or refused, before any enumeration
            explore = resumed_exploration(out_folder(args, f"run-{instance.name}"), explore)
            if explore == "online" and args.explore == "auto":
                because = factored or "the run resumed went online under `--explore auto`"
        if explore == "online":
            spec = replace(spec, exploration="online")
            instance = OnlineInstance(instance)  # its own checks
        else:
            if explore == "auto" and instance.ppddl:  # it can go online
                instance.graph_or_give_up()
            instance.model  # noqa: B018
    except (MemoryError, TooManyStates) as exc:  # past the budget, or a `ulimit -v`
        if explore == "auto" and load_pddl_instance(spec).ppddl and \
                isinstance(exc, (TooManyStates, SizeError)):
            spec = replace(spec, exploration="online")
            instance = OnlineInstance(load_pddl_instance(spec))
            print(f"gdq-pddl: {exc}\ngdq-pddl: so {problem} is explored online: its states "
                  "are found as episodes reach them, and V* is not computed (--explore)",
                  file=sys.stderr)
            because = factored_reason(instance.task, str(problem)) or \
                f"`--explore auto` found that its states do not fit: {exc}"
        elif isinstance(exc, (SizeError, TooManyStates)):
            raise
        else:
            raise SizeError(f"{problem}: grounding the problem ran out of memory; give a "
                            "smaller problem") from None
    knowledge = None
    if args.knowledge_domain is not None:
        if spec.online:
            raise GdqError("--knowledge-domain needs the problem's states enumerated "
                           "(--explore enumerate): online, no knowledge file is read")
        knowledge = str(args.knowledge_domain.absolute())
        knowledge_instance(instance, spec, knowledge)  # same states and outcomes, or exit 2
    if instance.graph.is_goal[0]:
        print(f"gdq-pddl: warning: {problem}: the goal already holds in the initial state: "
              "every episode ends there before its first action (return 0), as mdpsim "
              "ends such a round at turn 0", file=sys.stderr)
    kw = experiment_kw(args)
    exp = Experiment("run", ((instance.name, args.episodes),), world="pddl", pddl=spec,
                     knowledge=knowledge, **kw)
    return execute([exp], args, f"run-{instance.name}", keep_learners=args.keep_learners,
                   collect=partial(collect, online_facts={"explored_because": because}),
                   options={"explore": args.explore})


def register_switch(sub) -> None:
    p = sub.add_parser("switch", help="change the task halfway (the paper's Hypothesis III)",
                       description="Learn --from for --episodes episodes, then --to for as many; "
                                   "GDQ keeps its learned model and replans for the new goal.")
    p.add_argument("--from", dest="first", default="C", help="first task (default C)")
    p.add_argument("--to", dest="second", default="D", help="second task (default D)")
    world_arg(p)
    run_args(p, "results/switch-<from>-<to>")
    p.set_defaults(func=cmd_switch)


def cmd_switch(args: argparse.Namespace) -> int:
    world = load_world_checked(args.world)
    first, second = world.task(args.first).name, world.task(args.second).name
    if first == second:  # task names are upper-cased: c and C are one task
        raise GdqError(f"--from and --to are the same task ({first}): a switch needs two")
    kw = experiment_kw(args)
    exp = switch_experiment(first, second, args.episodes, world=world_name(args.world), **kw)
    return execute([exp], args, exp.name)


def register_robot(sub) -> None:
    p = sub.add_parser("robot", help="the paper's real-robot protocol, simulated",
                       description="Task X on the office with area 5 forbidden, 10 actions per "
                                   "trial, R_max 1000, durations as costs, alpha 0.5.")
    run_args(p, "results/robot", methods=registry.built_in_names("robot"),
             episodes=30, runs=10)
    p.set_defaults(func=cmd_robot)


def cmd_robot(args: argparse.Namespace) -> int:
    kw = experiment_kw(args)
    exp = robot_experiment(runs=kw.pop("runs"), **kw)
    exp = replace(exp, schedule=(("X", args.episodes),))
    return execute([exp], args, "robot")


def register_reproduce(sub) -> None:
    p = sub.add_parser("reproduce", help="every experiment of the paper, with figures and report",
                       description="Tasks A-D (2500 episodes x 10 runs), the switches C->D and "
                                   "C->E (5000 episodes), the robot protocol; then figures, the "
                                   "area-visit table and REPORT.md in --out.")
    p.add_argument("--quick", action="store_true", help="300 episodes x 3 runs: a first look")
    p.add_argument("--seed", type=NONNEGATIVE, default=0, help="base seed")
    exec_args(p, "results/reproduce, or results/reproduce-quick with --quick")
    p.set_defaults(func=cmd_reproduce)


def cmd_reproduce(args: argparse.Namespace) -> int:
    name = "reproduce-quick" if args.quick else "reproduce"
    return execute(paper_protocol(quick=args.quick, seed=args.seed), args, name)


def register_knowledge(sub) -> None:
    p = sub.add_parser("knowledge", help="learn with PDDL knowledge that disagrees with the world",
                       description="Task C with a door locked in reality but usable in the "
                                   "knowledge (d3, d1), a corridor only reality has, a "
                                   "corridor only the knowledge has, and a control; each "
                                   "also with accurate knowledge; by default every method "
                                   "that reads the knowledge. Writes "
                                   "episodes.csv, figures and REPORT.md to --out.")
    size_args(p, KNOWLEDGE_METHODS, registry.names(), 1500, 10)
    exec_args(p, "results/knowledge")
    p.set_defaults(func=cmd_knowledge)


def cmd_knowledge(args: argparse.Namespace) -> int:
    exps = knowledge_experiments(args.episodes, args.runs, args.seed, checked_methods(args))
    command = f"gdq-pddl knowledge --episodes {args.episodes} --runs {args.runs} --seed {args.seed}"

    def report(out: Path) -> str:
        from gdq_pddl.analysis.knowledge import make_knowledge_report  # start-up time

        paths = make_knowledge_report(out, command)
        return f"wrote {len(paths)} figures and reports; read {out / 'REPORT.md'}"

    return execute(exps, args, "knowledge", report)


def register_report(sub) -> None:
    p = sub.add_parser("report", help="redraw figures, tables and REPORT.md of an output folder")
    p.add_argument("out", type=Path,
                   help="an output folder of run (office or PDDL), switch, robot, reproduce "
                        "or pairs")
    p.set_defaults(func=cmd_report)


def cmd_report(args: argparse.Namespace) -> int:
    from gdq_pddl.analysis import make_report  # start-up time: matplotlib and numba

    if args.out.is_dir():
        output_folder(args.out, "report")  # figures and REPORT.md go there
    paths = make_report(args.out)  # a missing folder: an error naming what it should hold
    print(f"wrote {len(paths) - 1} figures and tables; read {paths[-1]}")
    return 0


def register_scale(sub) -> None:
    p = sub.add_parser("scale", help="learning against building size (generated buildings)",
                       description="Run each --method on --buildings generated buildings of "
                                   "each size (building seeds --seed, --seed + 1, ...) and "
                                   "write scale.png/pdf and REPORT.md (episodes to "
                                   "convergence, mean returns, GDQ minus each method, env "
                                   "steps/s). Each finished run is saved in --out as it ends, "
                                   "so an interrupted run goes on with --resume.")
    p.add_argument("--sizes", type=POSITIVE, nargs="+", default=[100, 300, 1000],
                   help="building sizes in positions (default 100 300 1000)")
    p.add_argument("--buildings", type=POSITIVE, default=2,
                   help="buildings per size: building seeds --seed, --seed + 1, ... "
                        "(default 2, at most 1000)")
    size_args(p, DEFAULT_METHODS, registry.names(), 5000, 5,
              seed="the first building seed (each run derives its own seeds from its "
                   "building, size and run number)")
    exec_args(p, "results/scale")
    p.set_defaults(func=cmd_scale)


def cmd_scale(args: argparse.Namespace) -> int:
    from gdq_pddl.experiments import scale  # start-up time: it loads the learners

    exps = scale.scale_experiments(args.sizes, args.runs, args.episodes, args.seed,
                                   args.buildings, list(checked_methods(args)))
    return execute(exps, args, "scale", partial(scale_report, experiments=exps),
                   results="building-*.npz", **scale.runner_kw())


def scale_report(out: Path, experiments: list[Experiment]) -> str:
    """Figure and REPORT.md of the scale ``experiments`` in ``out``; returns what was
    written."""
    from gdq_pddl.analysis.scale import make_scale_report  # start-up time: matplotlib
    from gdq_pddl.experiments.scale import assemble  # start-up time, as above

    paths = make_scale_report([assemble(out, e) for e in experiments], experiments[0].runs,
                              experiments[0].episodes, out)
    return f"wrote {', '.join(p.name for p in paths)}; read {paths[-1]}"


def register_pairs(sub) -> None:
    p = sub.add_parser("pairs", help="every method on every ordered start/goal pair",
                       description="Each method learns each ordered (start, goal) pair of the "
                                   "world (342 in the office) --runs times for --episodes "
                                   "episodes, with the paper's hyperparameters and paired "
                                   "seeds. Writes runs.csv, a table of GDQ minus each "
                                   "baseline per pair, its figure and REPORT.md to --out.")
    world_arg(p)
    p.add_argument("--pairs", nargs="+", metavar="START->GOAL",
                   help="only these pairs (quote them: --pairs 'p3->p13 p10->p0')")
    p.add_argument("--sample", type=int, metavar="K",
                   help="only K pairs drawn at random with --seed")
    run_args(p, "results/pairs", episodes=300, runs=10)
    p.set_defaults(func=cmd_pairs)


def cmd_pairs(args: argparse.Namespace) -> int:
    world = load_world_checked(args.world)
    if args.pairs and args.sample is not None:
        raise GdqError("give --pairs or --sample, not both")
    if args.pairs:
        chosen = pairs.parse_pairs(world, args.pairs)
    elif args.sample is not None:
        chosen = pairs.sample_pairs(world, args.sample, args.seed)
    else:
        chosen = pairs.all_pairs(world)
    kw = experiment_kw(args)
    exps = pairs.pair_experiments(chosen, args.episodes, world=world_name(args.world), **kw)
    return execute(exps, args, "pairs", pairs_report, results="runs.csv",
                   work=pairs.run_pair_unit, collect=pairs.collect_pairs,
                   unit_arrays=pairs.PAIR_ARRAYS)


def pairs_report(out: Path) -> str:
    """Table, figure and REPORT.md of a pairs folder; returns what was written."""
    from gdq_pddl.analysis.pairs import make_pairs_report  # start-up time

    paths = make_pairs_report(out)
    return f"wrote {len(paths) - 1} tables and figures; read {paths[-1]}"
