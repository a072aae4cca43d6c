"""How GDQ's default settings were chosen: tasks A-D only, and the corridor case.

    python benchmarks/gdq_settings.py tasks            # each setting's return on A-D
    python benchmarks/gdq_settings.py corridor         # explore_all vs the corridor
    python benchmarks/gdq_settings.py                  # both
    python benchmarks/gdq_settings.py losses results/pairs   # explain GDQ's losses there
    python benchmarks/gdq_settings.py online DOMAIN PROBLEM  # the settings, explored online

``tasks``: every setting differs from the default in one field; for each, the mean
return per episode over the first 300 episodes of tasks A-D, minus DARLING's, paired
runs (env seeded 1000 + run, learner 2000 + run, as ``benchmarks/learners.py``).
``corridor``: reality has a corridor p8-p17 that the knowledge lacks (``gdq-pddl
knowledge``'s ``passage`` case, Task C); for each share of exploring steps that ignores
the knowledge, in how many runs the final greedy policy takes the corridor, and the mean
return over the run. Nothing else was tuned; ``docs/decisions.md`` quotes these figures.
``losses``: a diagnostic, not a tuning step: on the pairs a ``gdq-pddl pairs`` folder
counts as losses against DARLING, GDQ minus DARLING with the default, with
``explore_all = 0``, with ``explore_all_last_step = False``, with ``explore = "plans"``
and with ``explore_loops = True`` (same seeds as ``tasks``).
``online``: a diagnostic too: each setting on a PPDDL problem explored online
(``--explore online``), GDQ minus DARLING per run (paired, same seeds as ``tasks``;
a paired t-test's p), the share of the last 50 episodes that reach the goal and
the median length of those that do, per run: where GDQ settles on a longer route; last,
GDQ and DARLING with h_FF in place of h_add as the estimate of states not reached yet.
Each learner reads the estimates as the command line gives them (GDQ: ``ceil(1.25 h)``,
``GDQ.estimate_weight``).
"""

from __future__ import annotations

import argparse

import numpy as np

from gdq_pddl.envs.office import OfficeEnv
from gdq_pddl.learners import make_learner, office_task_context, run_episodes
from gdq_pddl.world import load_world
from gdq_pddl.world_types import Task, World

SETTINGS: dict[str, dict] = {
    "default": {},
    "m = 1": {"m": 1},
    "m = 3": {"m": 3},
    "prior_weight = 0": {"prior_weight": 0.0},
    "prior_weight = 0.5": {"prior_weight": 0.5},
    "prior_weight = 2": {"prior_weight": 2.0},
    "explore = plans": {"explore": "plans"},
    "explore = applicable": {"explore": "applicable"},
    "explore_loops = True": {"explore_loops": True},
    "explore_all = 0": {"explore_all": 0.0},
    "explore_all = 0.25": {"explore_all": 0.25},
    "n_backups = 1": {"n_backups": 1},
    "n_backups = 10": {"n_backups": 10},
    "n_backups = 40": {"n_backups": 40},
}
"""The default and its one-field variations (GDQConfig fields)."""


def mean_returns(world: World, real: World, task, method: str, config: dict,
                 runs: int, episodes: int) -> np.ndarray:
    """float[runs]: each run's mean return per episode (knowledge from ``world``, the env
    simulating ``real``; ``task`` a name or a :class:`~gdq_pddl.world_types.Task`)."""
    ctx = office_task_context(world, task)
    env = OfficeEnv(world=real, task=task) if isinstance(task, str) else \
        OfficeEnv(world=real, start=task.start, goal=task.goal)
    out = np.zeros(runs)
    for run in range(runs):
        env.reset(seed=1000 + run)
        learner = make_learner(method, ctx, **config)
        out[run] = run_episodes(learner, env, episodes, np.random.default_rng(2000 + run)
                                ).returns.mean()
    return out


def tasks(runs: int = 40, episodes: int = 300) -> None:
    world = load_world()
    names = ("A", "B", "C", "D")
    darling = {t: mean_returns(world, world, t, "darling", {}, runs, episodes) for t in names}
    print(f"Tasks A-D, {runs} runs x {episodes} episodes: mean return per episode minus "
          "DARLING's (paired s.e.)")
    print(f"{'setting':22s}" + "".join(f"{'task ' + t:>16s}" for t in names) + f"{'mean':>8s}")
    print(f"{'DARLING':22s}" + "".join(f"{darling[t].mean():>16.2f}" for t in names))
    for label, config in SETTINGS.items():
        diffs = [mean_returns(world, world, t, "gdq", config, runs, episodes) - darling[t]
                 for t in names]
        cells = "".join(f"{d.mean():>+9.2f} ({d.std(ddof=1) / np.sqrt(runs):.2f})"
                        for d in diffs)
        print(f"{label:22s}{cells}{np.mean([d.mean() for d in diffs]):>+8.2f}", flush=True)


def corridor(runs: int = 10, episodes: int = 3000) -> None:
    from gdq_pddl.experiments.knowledge import PASSAGE, derived_world
    from gdq_pddl.spaces import LearnerSpaces

    real, world = derived_world("office:passage"), load_world()
    spaces = LearnerSpaces(real)
    at, corridor_action = spaces.state(PASSAGE[0]), spaces.action("goto", PASSAGE[1])
    ctx = office_task_context(world, "C")
    env = OfficeEnv(world=real, task="C")
    print(f"Corridor {PASSAGE[0]}-{PASSAGE[1]} only reality has (Task C), {runs} runs x "
          f"{episodes} episodes: runs whose final greedy policy takes it; mean return")
    for label, method, config in (("Dyna-Q (no knowledge)", "dynaq", {}),
                                  *((f"GDQ, explore_all = {x:g}", "gdq", {"explore_all": x})
                                    for x in (0.0, 0.05, 0.1, 0.15, 0.2, 0.25, 0.5)),
                                  ("GDQ, 0.1, not last step", "gdq",
                                   {"explore_all_last_step": False})):
        found, means = 0, []
        for run in range(runs):
            env.reset(seed=1000 + run)
            learner = make_learner(method, ctx, **config)
            rec = run_episodes(learner, env, episodes, np.random.default_rng(2000 + run))
            found += int(learner.greedy_policy()[at] == corridor_action)
            means.append(rec.returns.mean())
        print(f"{label:26s} {found:>3d}/{runs}  {np.mean(means):7.2f}", flush=True)


def losses(folder: str, runs: int = 10, episodes: int = 300) -> None:
    import csv
    from pathlib import Path

    with (Path(folder) / "tables" / "pairs.csv").open() as fh:
        rows = [r for r in csv.DictReader(fh) if r["outcome_DARLING"] == "loss"]
    if not rows:
        print("GDQ loses to DARLING on no pair there")
        return
    world = load_world()
    lengths = [int(r["shortest_plan"]) for r in rows]
    print(f"{len(rows)} pairs where GDQ loses to DARLING; shortest plan: median "
          f"{np.median(lengths):g}, longest {max(lengths)}; {runs} runs x {episodes} episodes")
    for label, config in (("default", {}), ("explore_all = 0", {"explore_all": 0.0}),
                          ("explore_all_last_step = False", {"explore_all_last_step": False}),
                          ("explore = plans", {"explore": "plans"}),
                          ("explore_loops = True", {"explore_loops": True})):
        diffs = []
        for r in rows:
            t = Task(f"{r['start']}->{r['goal']}", r["start"], r["goal"])
            diffs.append((mean_returns(world, world, t, "gdq", config, runs, episodes)
                          - mean_returns(world, world, t, "darling", {}, runs, episodes)).mean())
        d = np.array(diffs)
        print(f"GDQ ({label}) minus DARLING: mean {d.mean():+.3f}, below 0 on "
              f"{(d < 0).sum()} of {len(d)}", flush=True)


def _online_run(job: tuple) -> tuple[float, float, float]:
    from gdq_pddl.envs.online import OnlineInstance
    from gdq_pddl.envs.online_env import OnlineEnv
    from gdq_pddl.envs.pddl_env import load_instance
    from gdq_pddl.learners.agents import learner_class
    from gdq_pddl.learners.online import online_context

    domain, problem, method, config, estimate, run, episodes = job
    instance = OnlineInstance(load_instance(domain, problem), estimate=estimate,
                              estimate_weight=learner_class(method).estimate_weight)
    env = OnlineEnv(instance)
    env.reset(seed=1000 + run)
    rec = run_episodes(make_learner(method, online_context(instance), **config), env,
                       episodes, np.random.default_rng(2000 + run))
    tail = rec.success[-50:]
    return (float(rec.returns.mean()), float(tail.mean()),
            float(np.median(rec.steps[-50:][tail])) if tail.any() else float("nan"))


def online(domain: str, problem: str, runs: int = 10, episodes: int = 300) -> None:
    from concurrent.futures import ProcessPoolExecutor

    from scipy import stats

    print(f"{problem} explored online, {runs} runs x {episodes} episodes: GDQ minus DARLING "
          "(paired s.e., p); last 50 episodes: success, median steps of each run")
    cases = [("DARLING", "darling", {}, "h_add")] + \
        [(k, "gdq", c, "h_add") for k, c in SETTINGS.items()] + \
        [("estimate = h_FF", "gdq", {}, "h_FF"), ("DARLING, h_FF", "darling", {}, "h_FF")]
    with ProcessPoolExecutor(2) as pool:
        results = {label: list(pool.map(_online_run, [(domain, problem, method, config, h,
                                                        r, episodes) for r in range(runs)]))
                   for label, method, config, h in cases}
    darling = np.array([r[0] for r in results["DARLING"]])
    for label, rows in results.items():
        means = np.array([r[0] for r in rows])
        d = means - darling
        p = stats.ttest_rel(means, darling).pvalue if label != "DARLING" else np.nan
        test = f"{d.mean():+7.2f} ({d.std(ddof=1) / np.sqrt(runs):.2f}, p {p:.3f})" \
            if label != "DARLING" else f"{means.mean():7.2f} (its mean)"
        steps = " ".join("-" if np.isnan(r[2]) else f"{r[2]:g}" for r in rows)
        print(f"{label:22s}{test:>28s}  {np.mean([r[1] for r in rows]):.2f}  {steps}",
              flush=True)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("what", nargs="?", default="all",
                        choices=["tasks", "corridor", "losses", "online", "all"])
    parser.add_argument("files", nargs="*", help="losses: a gdq-pddl pairs output folder "
                        "(default results/pairs); online: a PPDDL domain and problem")
    parser.add_argument("--runs", type=int, help="runs per setting (tasks 40, corridor 10)")
    parser.add_argument("--episodes", type=int, help="episodes per run (300 / 3000)")
    args = parser.parse_args()
    if args.what in ("tasks", "all"):
        tasks(args.runs or 40, args.episodes or 300)
    if args.what in ("corridor", "all"):
        corridor(args.runs or 10, args.episodes or 3000)
    if args.what == "losses":
        losses((args.files or ["results/pairs"])[0], args.runs or 10, args.episodes or 300)
    if args.what == "online":
        if len(args.files) != 2:
            parser.error("online takes a PPDDL domain and a problem")
        online(*args.files, args.runs or 10, args.episodes or 300)


if __name__ == "__main__":
    main()
