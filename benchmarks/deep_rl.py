"""Deep-RL agents against GDQ and Q-shaping: greedy success by env steps (issue 37).

On each problem, every method learns as in ``gdq-pddl run``: the learners made through
the registry (``PPO:shaping=distance`` is the spec ``gdq-pddl run --method`` takes), the
env and knowledge made as there, the seeds of a run drawn as there and the same for
every method (paired runs).
After every ``--eval-every`` env steps (a tabular learner: at the end of the episode that
gets there), its greedy policy plays ``--eval-episodes`` evaluation episodes (the same
evaluation seeds for every method of a run), with no learning and no exploration. Each
run's curve is appended to ``curves.csv`` as soon as it has finished (``--resume`` skips
the runs that are there), then ``summary.csv``, ``deep-rl.md`` (the table) and
``deep-rl.png`` (success by steps, IQM over runs with a 95% bootstrap band) are written
from it.

Per problem and method: the steps to ``--target`` greedy success (the first checkpoint at
or above it; a run that never gets there counts as its last checkpoint, at least
``--steps``, censored: the table says how many runs got there, and marks an IQM that
censored runs enter with ``≥``, a lower bound), and the greedy success after ``--steps``
steps; the IQM over runs (interquartile mean: the mean of the middle 50%, Agarwal et al.
2021) with a 95% percentile bootstrap interval over runs (numpy; :func:`iqm`,
:func:`bootstrap_ci`).

Needs the ``sb3`` extra for the deep agents (docs/python.md: the CPU-only torch)::

    python benchmarks/deep_rl.py --out results/deep-rl           # the measured table
    python benchmarks/deep_rl.py --out results/deep-rl --report  # table and figure again
    python benchmarks/deep_rl.py --problems keys-2 --methods GDQ PPO --runs 2 --steps 5000
"""

from __future__ import annotations

import argparse
import csv
import sys
import time
from collections.abc import Callable, Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

PROBLEMS: dict[str, tuple[str, ...]] = {
    "task-c": ("office", "C"),
    "keys-2": ("keys", "keys-2", "keys"),
    "delivery-2": ("delivery", "delivery-2", "delivery"),
    "keys-ppddl-2": ("keys-ppddl", "keys-ppddl-2", ""),
    "lift-2": ("lift", "lift-2", ""),
}
"""Problem label -> ``(world, task)`` of the office, or ``(domain, problem, dynamics)``
as ``gdq-pddl run --domain --problem --dynamics`` takes them (shipped names or files)."""

DEEP = ("MaskablePPO", "PPO", "DQN")
KNOWLEDGE = ("", ":shaping=distance", ":obs=facts")
METHODS: tuple[str, ...] = ("GDQ", "Q-shaping",
                            *(f"{agent}{k}" for agent in DEEP for k in KNOWLEDGE))
"""The methods compared: the deep agents plain, shaped by the goal distance, and seeing
the state's facts."""

FIELDS = ("problem", "method", "run", "steps", "success", "seconds")
"""The columns of ``curves.csv``: one row per checkpoint of a run."""


# -- statistics (numpy only: tests/benchmarks/test_deep_rl_stats.py runs them without torch)

def iqm(values: Sequence[float] | np.ndarray) -> float:
    """The interquartile mean: the mean of the middle 50% of ``values`` (the sorted values
    from position ``n/4`` to ``3n/4``, the end ones weighted by the fraction inside), as
    scipy's ``trim_mean(values, 0.25)`` for ``n`` divisible by 4."""
    x = np.sort(np.asarray(values, dtype=np.float64))
    n = x.size
    if n == 0:
        return float("nan")
    lo, hi = n / 4, 3 * n / 4
    edges = np.arange(n + 1, dtype=np.float64)  # value i covers [i, i + 1)
    weight = np.clip(np.minimum(edges[1:], hi) - np.maximum(edges[:-1], lo), 0.0, None)
    return float(np.sum(weight * x) / np.sum(weight))


def bootstrap_ci(values: Sequence[float] | np.ndarray, stat: Callable[[np.ndarray], float]
                 = iqm, n_boot: int = 2000, level: float = 0.95,
                 rng: np.random.Generator | None = None) -> tuple[float, float]:
    """The percentile bootstrap interval of ``stat`` over ``values`` (resampled with
    replacement ``n_boot`` times) at ``level``."""
    x = np.asarray(values, dtype=np.float64)
    if x.size == 0:
        return float("nan"), float("nan")
    rng = rng if rng is not None else np.random.default_rng(0)
    picks = rng.integers(0, x.size, size=(n_boot, x.size))
    stats = np.array([stat(x[p]) for p in picks])
    tail = (1 - level) / 2 * 100
    low, high = np.percentile(stats, [tail, 100 - tail])
    return float(low), float(high)


def steps_to_threshold(steps: Sequence[int] | np.ndarray, success: Sequence[float]
                       | np.ndarray, threshold: float) -> int | None:
    """The steps of the first checkpoint whose greedy success is at least ``threshold``
    (checkpoints in order of steps); None if there is none."""
    for n, s in zip(steps, success, strict=True):
        if s >= threshold - 1e-12:
            return int(n)
    return None


def success_at(steps: Sequence[int] | np.ndarray, success: Sequence[float] | np.ndarray,
               budget: int) -> float:
    """The greedy success of the last checkpoint at or before ``budget`` steps (the first
    checkpoint if all are after it, as a PPO rollout may end past the budget)."""
    steps, success = np.asarray(steps), np.asarray(success, dtype=np.float64)
    before = np.flatnonzero(steps <= budget)
    return float(success[before[-1]] if before.size else success[0])


@dataclass(frozen=True)
class Summary:
    """One problem's and method's numbers over its runs."""

    problem: str
    method: str
    runs: int
    reached: int
    """Runs that got to the target."""
    steps_iqm: float
    steps_ci: tuple[float, float]
    final_iqm: float
    final_ci: tuple[float, float]


def summarise(curves: dict[tuple[str, str, int], tuple[np.ndarray, np.ndarray]],
              target: float, budget: int, n_boot: int = 2000) -> list[Summary]:
    """Per problem and method, the steps to ``target`` (unreached: censored at the run's
    last checkpoint, at least ``budget``)
    and the success after ``budget`` steps: IQM and 95% bootstrap interval over runs."""
    groups: dict[tuple[str, str], list[tuple[np.ndarray, np.ndarray]]] = {}
    for (problem, method, _run), curve in sorted(curves.items(), key=_order(curves)):
        groups.setdefault((problem, method), []).append(curve)
    out = []
    for (problem, method), runs in groups.items():
        reached = [steps_to_threshold(s, v, target) for s, v in runs]
        # a run that never got there: censored at its last checkpoint (at least the budget)
        to_target = np.array([max(budget, int(s[-1])) if r is None else r
                              for r, (s, _) in zip(reached, runs, strict=True)],
                             dtype=np.float64)
        final = np.array([success_at(s, v, budget) for s, v in runs])
        rng = np.random.default_rng(0)
        out.append(Summary(problem, method, len(runs), sum(r is not None for r in reached),
                           iqm(to_target), bootstrap_ci(to_target, iqm, n_boot, rng=rng),
                           iqm(final), bootstrap_ci(final, iqm, n_boot, rng=rng)))
    return out


def _order(curves: dict[tuple[str, str, int], Any]) -> Callable[[tuple], tuple]:
    """A sort key of ``curves``' items: problems as they first come, methods in the
    order of :data:`METHODS` (others after, by name), then runs."""
    problems = list(dict.fromkeys(p for p, _, _ in curves))

    def key(item: tuple) -> tuple:
        problem, method, run = item[0]
        rank = METHODS.index(method) if method in METHODS else len(METHODS)
        return problems.index(problem), rank, method, run

    return key


def band(curves: list[tuple[np.ndarray, np.ndarray]], grid: np.ndarray, n_boot: int = 1000
         ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """IQM and 95% bootstrap band over runs of the success on ``grid`` (each run's last
    checkpoint at or before the grid point; 0 before its first)."""
    values = np.array([[success_at(s, v, g) if s[0] <= g else 0.0 for g in grid]
                       for s, v in curves])
    mid = np.array([iqm(values[:, j]) for j in range(grid.size)])
    rng = np.random.default_rng(0)
    picks = rng.integers(0, len(curves), size=(n_boot, len(curves)))
    boot = np.array([[iqm(values[p, j]) for j in range(grid.size)] for p in picks])
    low, high = np.percentile(boot, [2.5, 97.5], axis=0)
    return mid, low, high


# -- reading and writing

def read_curves(path: Path) -> dict[tuple[str, str, int], tuple[np.ndarray, np.ndarray]]:
    """``curves.csv``: (problem, method, run) -> (steps, success) of its checkpoints."""
    rows: dict[tuple[str, str, int], list[tuple[int, float]]] = {}
    if path.exists():
        with path.open(newline="") as f:
            for row in csv.DictReader(f):
                key = (row["problem"], row["method"], int(row["run"]))
                rows.setdefault(key, []).append((int(row["steps"]), float(row["success"])))
    return {k: (np.array([n for n, _ in v]), np.array([s for _, s in v]))
            for k, v in rows.items()}


def table(summaries: list[Summary], target: float, budget: int) -> str:
    """The Markdown table of ``summaries``."""
    lines = [f"| problem | method | steps to {target:.0%} greedy success, IQM [95% CI] "
             f"| runs there | greedy success after {budget:,} steps, IQM [95% CI] |",
             "|---|---|---:|---:|---:|"]
    for s in summaries:
        # past a quarter of the runs censored, some enter the IQM: it is a lower bound
        censored = "≥" if s.runs - s.reached > s.runs / 4 else ""
        lines.append(f"| {s.problem} | {s.method} | {censored}{s.steps_iqm:,.0f} "
                     f"[{s.steps_ci[0]:,.0f}, {s.steps_ci[1]:,.0f}] | {s.reached}/{s.runs} "
                     f"| {s.final_iqm:.2f} [{s.final_ci[0]:.2f}, {s.final_ci[1]:.2f}] |")
    return "\n".join(lines) + "\n"


def figure(curves: dict[tuple[str, str, int], tuple[np.ndarray, np.ndarray]], budget: int,
           path: Path) -> None:
    """Greedy success by env steps, one panel per problem, IQM with its 95% band."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    from gdq_pddl.learners.registry import colour

    colours = {"MaskablePPO": "#1f78b4", "PPO": "#33a02c", "DQN": "#6a3d9a"}  # darker
    problems = list(dict.fromkeys(p for p, _, _ in curves))
    methods = list(dict.fromkeys(m for _, m, _ in curves))
    grid = np.linspace(0, budget, 41)
    fig, axes = plt.subplots(1, len(problems), figsize=(3.6 * len(problems), 3.4),
                             squeeze=False, sharey=True)
    styles = {"": "-", ":shaping=distance": "--", ":obs=facts": ":"}
    for ax, problem in zip(axes[0], problems, strict=True):
        for method in methods:
            runs = [c for (p, m, _), c in sorted(curves.items()) if p == problem and m == method]
            if not runs:
                continue
            mid, low, high = band(runs, grid)
            base, _, setting = method.partition(":")
            style = styles.get(f":{setting}" if setting else "", "-")
            line, = ax.plot(grid, mid, style, label=method, lw=1.4,
                            color=colours.get(base) or colour(base))
            ax.fill_between(grid, low, high, color=line.get_color(), alpha=0.12, lw=0)
        ax.set_title(problem)
        ax.set_xlabel("env steps")
        ax.set_ylim(-0.03, 1.03)
    axes[0][0].set_ylabel("greedy success (IQM, 95% band)")
    handles, labels = axes[0][0].get_legend_handles_labels()
    fig.tight_layout()
    fig.legend(handles, labels, loc="upper center", bbox_to_anchor=(0.5, 0.0), ncol=4,
               fontsize=7, frameon=False)
    fig.savefig(path, dpi=110, bbox_inches="tight")
    plt.close(fig)


# -- learning

class _Problem:
    """One problem's instance, task context and env maker, as ``gdq-pddl run`` makes
    them, and the experiment whose seeds its runs take."""

    def __init__(self, label: str, spec: tuple[str, ...]) -> None:
        from gdq_pddl.envs.pddl_env import PDDLEnv
        from gdq_pddl.experiments.protocol import Experiment, ProblemSpec
        from gdq_pddl.experiments.work import context_of, instance_of

        if len(spec) == 2:  # the office: world and task
            self.exp = Experiment("run", ((spec[1], 1),), world=spec[0])
            task = spec[1]
        else:
            from gdq_pddl.cli.common import resolve_pddl
            from gdq_pddl.experiments.knowledge import load_pddl_instance

            domain, problem, dynamics = resolve_pddl(spec[0], spec[1], spec[2] or None)
            files = ProblemSpec(str(domain), str(problem),
                                "" if dynamics is None else str(dynamics))
            task = load_pddl_instance(files).name
            self.exp = Experiment("run", ((task, 1),), world="pddl", pddl=files)
        self.label = label
        self.instance = instance_of(self.exp, task)
        self.context = context_of(self.exp, self.instance)
        self._env = PDDLEnv

    def env(self) -> Any:
        """A fresh env of the problem."""
        return self._env(instance=self.instance)

    def seeds(self, method: str, run: int) -> tuple[np.random.Generator, int]:
        """The learner's Generator and env seed of run ``run``, drawn as ``gdq-pddl run``
        draws them (the same for every method: paired runs)."""
        from gdq_pddl.experiments.protocol import Unit

        return Unit(self.exp, method, run).seeds()


def greedy_success(envs: list[Any], act: Callable[[np.ndarray, np.ndarray], np.ndarray],
                   seed: int) -> float:
    """The share of ``envs`` (one episode each, reset with ``seed + i``) whose episode
    reaches the goal when ``act(observations, masks)`` picks the actions of all at once."""
    obs, done, won = [], np.zeros(len(envs), dtype=bool), np.zeros(len(envs), dtype=bool)
    for i, env in enumerate(envs):
        o, info = env.reset(seed=seed + i)
        obs.append(o)
        done[i] = won[i] = info.get("cause") == "goal"
    while not done.all():
        live = np.flatnonzero(~done)
        masks = np.stack([np.asarray(envs[i].unwrapped.action_masks(), dtype=bool)
                          for i in live])
        actions = act(np.stack([np.asarray(obs[i]) for i in live]), masks)
        for i, a in zip(live, actions, strict=True):
            obs[i], _, terminated, truncated, info = envs[i].step(int(a))
            if terminated or truncated:
                done[i], won[i] = True, terminated and info.get("cause") == "goal"
    return float(won.mean())


def learn(problem: _Problem, method: str, run: int, budget: int, every: int,
          eval_episodes: int) -> list[tuple[int, float, float]]:
    """One run of ``method``: ``[(steps, greedy success, seconds)]`` at its checkpoints."""
    from gdq_pddl.experiments.work import make_learner
    from gdq_pddl.learners.episodes import run_episodes

    rng, env_seed = problem.seeds(method, run)
    eval_seed = 1_000_000 + 1_000 * run  # the same for every method of a run
    learner = make_learner(method, problem.context, problem.exp.hyper)
    env = problem.env()
    env.reset(seed=env_seed)
    start, curve = time.perf_counter(), []
    if hasattr(learner, "train_steps"):  # a deep agent
        envs = [learner.wrap(problem.env()) for _ in range(eval_episodes)]

        def checkpoint(done: int) -> None:
            curve.append((done, greedy_success(envs, learner.greedy_actions, eval_seed),
                          time.perf_counter() - start))

        learner.train_steps(env, budget, rng, every, checkpoint)
        if curve[-1][0] % every:
            checkpoint(int(learner.model.num_timesteps))
        return curve
    envs = [problem.env() for _ in range(eval_episodes)]

    def tabular(done: int) -> None:
        q = learner.greedy_policy()
        curve.append((done, greedy_success(envs, lambda o, m: q[o], eval_seed),
                      time.perf_counter() - start))

    tabular(0)
    done = 0
    while done < budget:
        done += int(run_episodes(learner, env, 1, rng).steps.sum())
        if done >= every * len(curve) or done >= budget:
            tabular(done)
    return curve


def report(out: Path, target: float, budget: int) -> str:
    """Write ``summary.csv``, ``deep-rl.md`` and ``deep-rl.png`` from ``curves.csv``."""
    curves = read_curves(out / "curves.csv")
    summaries = summarise(curves, target, budget)
    with (out / "summary.csv").open("w", newline="") as f:
        w = csv.writer(f)
        w.writerow(["problem", "method", "runs", "reached", "steps_iqm", "steps_low",
                    "steps_high", "final_iqm", "final_low", "final_high"])
        for s in summaries:
            w.writerow([s.problem, s.method, s.runs, s.reached, s.steps_iqm, *s.steps_ci,
                        s.final_iqm, *s.final_ci])
    text = table(summaries, target, budget)
    (out / "deep-rl.md").write_text(text)
    figure(curves, budget, out / "deep-rl.png")
    return text


def main(argv: Sequence[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--out", type=Path, default=Path("results/deep-rl"))
    parser.add_argument("--problems", nargs="*", default=list(PROBLEMS), choices=list(PROBLEMS))
    parser.add_argument("--pddl", nargs=3, action="append", default=[],
                        metavar=("LABEL", "DOMAIN", "PROBLEM"),
                        help="a PPDDL problem of your own (files), e.g. one of pddlgym's, "
                             "measured after --problems (repeatable)")
    parser.add_argument("--methods", nargs="+", default=list(METHODS))
    parser.add_argument("--runs", type=int, default=5)
    parser.add_argument("--steps", type=int, default=4_096, help="env steps per run")
    parser.add_argument("--eval-every", type=int, default=512)
    parser.add_argument("--eval-episodes", type=int, default=30)
    parser.add_argument("--target", type=float, default=0.9)
    parser.add_argument("--report", action="store_true",
                        help="only write the table and figure from curves.csv")
    args = parser.parse_args(argv)
    args.out.mkdir(parents=True, exist_ok=True)
    path = args.out / "curves.csv"
    if not args.report:
        done = set(read_curves(path))
        specs = [(label, PROBLEMS[label]) for label in args.problems] + \
            [(label, (domain, problem, "")) for label, domain, problem in args.pddl]
        for label, spec in specs:  # a cut keeps the problems done with all their runs
            problem = _Problem(label, spec)
            for run in range(args.runs):  # then whole runs: every method of a seed
                for method in args.methods:
                    if (label, method, run) in done:
                        continue
                    curve = learn(problem, method, run, args.steps, args.eval_every,
                                  args.eval_episodes)
                    new = not path.exists()
                    with path.open("a", newline="") as f:
                        w = csv.writer(f)
                        if new:
                            w.writerow(FIELDS)
                        w.writerows((label, method, run, n, f"{s:.4f}", f"{t:.2f}")
                                    for n, s, t in curve)
                    print(f"{label} {method} run {run}: success {curve[-1][1]:.2f} after "
                          f"{curve[-1][0]} steps, {curve[-1][2]:.0f} s", flush=True)
    print(report(args.out, args.target, args.steps))
    return 0


if __name__ == "__main__":
    sys.exit(main())
