"""Task X (p4 -> p17) on the robot's office: 30 trials, durations as costs.

The paper's real-robot protocol, simulated: area 5 is forbidden, a trial may take at most
10 actions, R_max is 1000, and each action costs the seconds it takes (door actions
wait for a person). GDQ against Dyna-Q, alpha 0.5, as in the paper.

    python examples/task_x.py --trials 30
"""

from __future__ import annotations

import argparse

import gymnasium
import numpy as np

import gdq_pddl  # noqa: F401
from gdq_pddl.learners import make_learner, office_task_context, run_episodes


def main(trials: int, seed: int = 0) -> dict[str, np.ndarray]:
    env = gymnasium.make("gdq_pddl/Office-v0", world="office_robot", task="X")
    context = office_task_context(env.unwrapped.world, "X")
    out = {}
    for method in ("gdq", "dynaq"):
        env.reset(seed=seed)
        learner = make_learner(method, context, alpha=0.5)
        records = run_episodes(learner, env, trials, np.random.default_rng(seed))
        out[method] = records.returns
        print(f"{method:6s} successes {int(records.success.sum()):2d}/{trials}, "
              f"return of each trial: {np.round(records.returns).astype(int).tolist()}")
    return out


if __name__ == "__main__":
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--trials", type=int, default=30)
    parser.add_argument("--seed", type=int, default=0)
    main(**vars(parser.parse_args()))
