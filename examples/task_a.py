"""Task A (p14 -> p17): the gymnasium loop written out, with a GDQ learner.

What it shows: a GDQ agent is an ordinary object with act/observe; the env is an
ordinary gymnasium env. The plans the learner was given are printed first.

    python examples/task_a.py --episodes 300
"""

from __future__ import annotations

import argparse

import gymnasium
import numpy as np

import gdq_pddl  # noqa: F401  (registers gdq_pddl/Office-v0)
from gdq_pddl.learners import GDQ, office_task_context


def main(episodes: int, seed: int = 0) -> float:
    env = gymnasium.make("gdq_pddl/Office-v0", task="A")
    office = env.unwrapped
    context = office_task_context(office.world, office.task)
    for plan in context.plans.plans_from(context.s0):
        print("plan:", ", ".join(office.spaces.action_name(a) for _, a in plan))
    agent, rng = GDQ(context), np.random.default_rng(seed)
    returns = []
    obs, _ = env.reset(seed=seed)
    for _ in range(episodes):
        obs, _ = env.reset()
        total, done = 0.0, False
        while not done:
            action = agent.act(obs, rng)
            nxt, reward, terminated, truncated, info = env.step(action)
            agent.observe(obs, action, reward, nxt, terminated, truncated, rng)
            obs, total, done = nxt, total + reward, terminated or truncated
        returns.append(total)
    last = float(np.mean(returns[-50:]))
    print(f"GDQ on task A: mean return of the last 50 of {episodes} episodes: {last:.2f}")
    return last


if __name__ == "__main__":
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--episodes", type=int, default=300)
    parser.add_argument("--seed", type=int, default=0)
    main(**vars(parser.parse_args()))
