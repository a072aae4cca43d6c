"""Learner benchmarks on Task C: speed (env steps per second) and learning results.

    python benchmarks/learners.py speed      # steps/s per method, fast path, median of 5
    python benchmarks/learners.py results    # 300 episodes x 5 runs, mean return per method
    python benchmarks/learners.py results --runs 100   # the same, with more runs
    python benchmarks/learners.py            # both
    python benchmarks/learners.py speed --method Q-learning Expected-SARSA   # any methods
    python benchmarks/learners.py cold       # a first run's user CPU, empty numba cache

Speed counts env steps (learner + env, compiled loop) after a JIT warm-up run; the methods
take turns, repeat by repeat, so a loaded machine slows each alike (compare ratios).
Cold runs ``gdq-pddl run --task C --method Q-learning --episodes 100 --runs 1 --jobs 1``
(report included) with an empty ``NUMBA_CACHE_DIR`` each time: the user CPU of a first run
(docs/reference/times.md), median of ``--runs`` (3 by default here).
Results use the paper's protocol (alpha 0.1, gamma 0.95, epsilon 0.1, 20 steps, R_max 20)
with the env seeded 1000 + run and the learner generator seeded 2000 + run.
"""

from __future__ import annotations

import argparse
import os
import resource
import statistics
import subprocess
import sys
import tempfile
import time

import gymnasium
import numpy as np

import gdq_pddl  # noqa: F401  (registers the env)
from gdq_pddl.learners import make_learner, office_task_context, run_episodes

METHODS = ("Q-learning", "Dyna-Q", "DARLING", "GDQ", "GDQ-literal", "GDQ-code")
"""The default methods (any ``--method`` spec, a plugin's included, may be given)."""
DIAGNOSTICS = (
    # not the paper: optimistic pairs end the episode instead of leading back to s0
    "GDQ-literal:optimistic_successor=terminal",
    # DARLING as the GDQ authors' released agent runs it (where the issue's ~231 comes from)
    "DARLING-code",
)


def _env_and_context(task: str = "C"):
    env = gymnasium.make("gdq_pddl/Office-v0", task=task)
    ctx = office_task_context(env.unwrapped.world, env.unwrapped.task)
    return env, ctx


def speed(task: str = "C", episodes: int = 2000, repeats: int = 5,
          methods: tuple[str, ...] = METHODS) -> dict[str, float]:
    """Median env steps per second of each method (fresh learner per repeat; the methods
    take turns within each repeat)."""
    env, ctx = _env_and_context(task)
    for method in methods:  # JIT warm-up
        env.reset(seed=0)
        run_episodes(make_learner(method, ctx), env, 5, np.random.default_rng(0))
    rates: dict[str, list[float]] = {m: [] for m in methods}
    for r in range(repeats):
        for method in methods:
            learner = make_learner(method, ctx)
            env.reset(seed=r)
            t0 = time.perf_counter()
            rec = run_episodes(learner, env, episodes, np.random.default_rng(r))
            rates[method].append(rec.steps.sum() / (time.perf_counter() - t0))
    out = {m: float(np.median(x)) for m, x in rates.items()}
    for m in methods:
        print(f"{m:16s} {out[m]:>12,.0f} steps/s  (median of {repeats} x {episodes} "
              f"episodes; {out[m] / out[methods[0]]:.2f} x {methods[0]})", flush=True)
    return out


def first_positive(returns: np.ndarray, window: int = 50) -> int | None:
    """1-based episode at which the ``window``-episode moving average first exceeds 0."""
    if len(returns) < window:
        return None
    avg = np.convolve(returns, np.ones(window) / window, mode="valid")
    hits = np.flatnonzero(avg > 0)
    return int(hits[0]) + window if len(hits) else None


def results(task: str = "C", episodes: int = 300, runs: int = 5,
            methods: tuple[str, ...] = METHODS + DIAGNOSTICS) -> dict[str, dict]:
    """Mean return per method over ``runs`` runs of ``episodes`` episodes."""
    env, ctx = _env_and_context(task)
    out = {}
    per_run_means: dict[str, np.ndarray] = {}
    print(f"Task {task}: {runs} runs x {episodes} episodes")
    print(f"{'method':40s} {'mean return':>12s} {'(s.e.)':>8s} {'last 50':>8s} "
          f"{'success':>8s} {'MA50 > 0 at':>12s}")
    for label in methods:
        curves = []
        for run in range(runs):
            learner = make_learner(label, ctx)
            env.reset(seed=1000 + run)
            rec = run_episodes(learner, env, episodes, np.random.default_rng(2000 + run))
            curves.append(rec)
        ret = np.array([c.returns for c in curves])
        per_run = ret.mean(axis=1)
        succ = np.mean([c.success.mean() for c in curves])
        cross = first_positive(ret.mean(axis=0))
        per_run_means[label] = per_run
        out[label] = {"mean": float(per_run.mean()),
                      "se": float(per_run.std(ddof=1) / np.sqrt(runs)) if runs > 1 else 0.0,
                      "last50": float(ret[:, -50:].mean()), "success": float(succ),
                      "first_positive": cross}
        r = out[label]
        print(f"{label:40s} {r['mean']:>12.2f} {r['se']:>8.2f} {r['last50']:>8.2f} "
              f"{r['success']:>8.2f} {str(cross) if cross else 'never':>12s}", flush=True)
    if runs > 1:  # run k of every method shares its env and learner seeds: paired
        for gdq in [m for m in ("GDQ", "GDQ-code") if m in per_run_means]:
            print(f"{gdq} minus each other method, mean over runs (paired s.e.):")
            for label, means in per_run_means.items():
                if label == gdq:
                    continue
                d = per_run_means[gdq] - means
                print(f"  - {label:28s} {d.mean():+8.2f} "
                      f"({d.std(ddof=1) / np.sqrt(runs):.2f})")
    return out


def cold(runs: int = 3, method: str = "Q-learning") -> float:
    """Median user CPU (s, the command and its children) of a first ``gdq-pddl run`` of
    ``method`` on Task C, each with an empty numba cache."""
    times = []
    for _ in range(runs):
        with tempfile.TemporaryDirectory() as cache, tempfile.TemporaryDirectory() as out:
            before = resource.getrusage(resource.RUSAGE_CHILDREN).ru_utime
            subprocess.run([sys.executable, "-m", "gdq_pddl.cli", "run", "--task", "C",
                            "--method", method, "--episodes", "100", "--runs", "1", "--jobs",
                            "1", "--out", os.path.join(out, "o")], check=True,
                           env={**os.environ, "NUMBA_CACHE_DIR": cache},
                           stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
            times.append(resource.getrusage(resource.RUSAGE_CHILDREN).ru_utime - before)
    print(f"first run of {method} on Task C, empty numba cache: user CPU "
          f"{', '.join(f'{t:.1f}' for t in times)} s, median {statistics.median(times):.1f} s")
    return statistics.median(times)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("what", nargs="?", choices=["speed", "results", "cold", "all"],
                        default="all")
    parser.add_argument("--task", default="C")
    parser.add_argument("--episodes", type=int, default=300)
    parser.add_argument("--runs", type=int, help="runs (default: 5 of results, 3 of cold)")
    parser.add_argument("--method", nargs="+", help="methods (specs) to measure, the first "
                        "the reference of the speed ratios (default: the built-in ones)")
    args = parser.parse_args()
    if args.what in ("speed", "all"):
        speed(args.task, methods=tuple(args.method or METHODS))
    if args.what == "cold":
        cold(args.runs or 3, (args.method or ["Q-learning"])[0])
    if args.what in ("results", "all"):
        results(args.task, args.episodes, args.runs or 5,
                tuple(args.method or METHODS + DIAGNOSTICS))


if __name__ == "__main__":
    main()
