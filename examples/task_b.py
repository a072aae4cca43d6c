"""Task B (p14 -> p18): the four methods side by side, with the fast episode runner.

What it shows: `run_episodes` runs any learner on any env of this package (compiled when
the env is the office), and every method shares one constructor signature.

    python examples/task_b.py --episodes 500 --runs 3
"""

from __future__ import annotations

import argparse

import gymnasium
import numpy as np

import gdq_pddl  # noqa: F401
from gdq_pddl.learners import make_learner, office_task_context, run_episodes


def main(episodes: int, runs: int) -> dict[str, float]:
    env = gymnasium.make("gdq_pddl/Office-v0", task="B")
    context = office_task_context(env.unwrapped.world, env.unwrapped.task)
    means = {}
    for method in ("gdq", "darling", "dynaq", "qlearning"):
        totals = []
        for run in range(runs):
            env.reset(seed=run)
            learner = make_learner(method, context)
            records = run_episodes(learner, env, episodes, np.random.default_rng(run))
            totals.append(records.returns.mean())
        means[method] = float(np.mean(totals))
        print(f"{method:10s} mean return per episode over {runs} runs: {means[method]:7.2f}")
    return means


if __name__ == "__main__":
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--episodes", type=int, default=500)
    parser.add_argument("--runs", type=int, default=3)
    main(**vars(parser.parse_args()))
