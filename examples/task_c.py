"""Task C (p0 -> p17): the best route is not a shortest plan.

Both shortest plans cross a difficult door (d0 or d2); the best route goes through the
easy doors d1 and d3, one step longer (areas 1 -> 3 -> 2 -> 6). Value iteration on the
true model says so; this script prints that route, then the route the learner's final
greedy policy takes.

    python examples/task_c.py --episodes 1000
"""

from __future__ import annotations

import argparse

import gymnasium
import numpy as np

import gdq_pddl  # noqa: F401
from gdq_pddl.envs.solve import solve_task
from gdq_pddl.learners import GDQ, office_task_context, run_episodes


def likely_route(env, choose) -> list[str]:
    """Positions visited when each action has its most likely outcome."""
    office = env.unwrapped
    m, fs = office.model, office.instance.start_state
    route = [office.world.positions[m.pos_of[fs]]]
    for t in range(office.world.step_limit):
        i = fs * m.n_actions + choose(t, fs)
        lo, hi = m.ptr[i], m.ptr[i + 1]
        fs = m.next[lo + int(np.argmax(m.prob[lo:hi]))]
        route.append(office.world.positions[m.pos_of[fs]])
        if m.pos_of[fs] == office.instance.goal_pos:
            break
    return route


def areas(env, route: list[str]) -> list[int]:
    """The areas a route passes through, each stay in an area counted once."""
    sequence = [env.unwrapped.world.area_of[p] for p in route]
    return [a for i, a in enumerate(sequence) if i == 0 or a != sequence[i - 1]]


def main(episodes: int, seed: int = 0) -> list[int]:
    env = gymnasium.make("gdq_pddl/Office-v0", task="C")
    office = env.unwrapped
    best, _ = solve_task(office.world, office.task, office.model)
    optimal = likely_route(env, lambda t, fs: int(best.policy[t, fs]))
    print("optimal route:", " ".join(optimal), " areas", areas(env, optimal))
    learner = GDQ(office_task_context(office.world, office.task))
    env.reset(seed=seed)
    run_episodes(learner, env, episodes, np.random.default_rng(seed))
    policy = learner.greedy_policy()
    learnt = likely_route(env, lambda t, fs: int(policy[office.model.obs_of[fs]]))
    print("GDQ's route:  ", " ".join(learnt), " areas", areas(env, learnt))
    return areas(env, learnt)


if __name__ == "__main__":
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--episodes", type=int, default=1000)
    parser.add_argument("--seed", type=int, default=0)
    main(**vars(parser.parse_args()))
