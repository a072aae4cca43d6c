"""Task E (p17 -> p14), after task C: the goal changes and GDQ keeps what it learnt.

GDQ's model of the building (which moves work, which doors are hard) does not depend on
the goal, so after the switch it reruns OptInit for the new goal with that model; Q-learning
only has a Q table tuned to the old goal, and Dyna-Q keeps its model but has no OptInit
to replan with it.

    python examples/task_e.py --episodes 1000
"""

from __future__ import annotations

import argparse

import gymnasium
import numpy as np

import gdq_pddl  # noqa: F401
from gdq_pddl.learners import make_learner, office_task_context, run_episodes


def main(episodes: int, seed: int = 0) -> dict[str, float]:
    env_c = gymnasium.make("gdq_pddl/Office-v0", task="C")
    env_e = gymnasium.make("gdq_pddl/Office-v0", task="E")
    world = env_c.unwrapped.world
    context_c = office_task_context(world, "C")
    context_e = office_task_context(world, "E")
    after = {}
    for method in ("gdq", "dynaq", "qlearning"):
        rng = np.random.default_rng(seed)
        learner = make_learner(method, context_c)
        env_c.reset(seed=seed)
        run_episodes(learner, env_c, episodes, rng)
        learner.start_task(context_e)
        env_e.reset(seed=seed + 1)
        records = run_episodes(learner, env_e, episodes, rng)
        after[method] = float(records.returns[: max(1, episodes // 5)].mean())
        print(f"{method:10s} first {max(1, episodes // 5)} episodes after the switch: "
              f"mean return {after[method]:7.2f}")
    return after


if __name__ == "__main__":
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--episodes", type=int, default=1000)
    parser.add_argument("--seed", type=int, default=0)
    main(**vars(parser.parse_args()))
