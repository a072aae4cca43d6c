"""Task D (p0 -> p18): where each method spends its steps (the paper's Hypothesis II).

The paper calls areas 2 and 5 irrelevant to task D. This counts, per method, the steps
that end in each area over a run: the planner's guidance should keep GDQ out of them.

    python examples/task_d.py --episodes 500
"""

from __future__ import annotations

import argparse

import gymnasium
import numpy as np

import gdq_pddl  # noqa: F401
from gdq_pddl.learners import make_learner, office_task_context, run_episodes


def main(episodes: int, seed: int = 0) -> dict[str, np.ndarray]:
    env = gymnasium.make("gdq_pddl/Office-v0", task="D")
    office = env.unwrapped
    context = office_task_context(office.world, office.task)
    print("irrelevant areas (paper):", office.task.irrelevant_areas)
    print(f"{'method':10s}" + "".join(f"{'area ' + str(k):>9s}" for k in range(1, 8)))
    visits = {}
    for method in ("gdq", "darling", "dynaq", "qlearning"):
        env.reset(seed=seed)
        records = run_episodes(make_learner(method, context), env, episodes,
                               np.random.default_rng(seed))
        visits[method] = records.area_visits.sum(axis=0)
        print(f"{method:10s}" + "".join(f"{v:9d}" for v in visits[method]))
    return visits


if __name__ == "__main__":
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--episodes", type=int, default=500)
    parser.add_argument("--seed", type=int, default=0)
    main(**vars(parser.parse_args()))
