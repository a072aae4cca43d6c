"""A PDDL domain of its own: a delivery robot, GDQ (and GDQ-code) against the baselines.

What it shows: any STRIPS+typing domain becomes an env with a dynamics file
(`PDDLEnv`), its learner states are the reachable planner states, and the learners and
`run_episodes` (compiled loop included) work on it unchanged. The shortest delivery
goes through a fire door that jams; value iteration on the true model (V*) takes the
long corridor, and so should the learners.

    python examples/domain_delivery.py --episodes 300 --runs 3 --problem delivery-2
"""

from __future__ import annotations

import argparse
from pathlib import Path

import numpy as np

from gdq_pddl.envs.pddl_env import GOAL_POS, PDDLEnv, PDDLInstance
from gdq_pddl.envs.solve import solve
from gdq_pddl.learners import make_learner, pddl_task_context, run_episodes
from gdq_pddl.resources import data_file


def shipped(*parts: str) -> Path:
    return Path(str(data_file(*parts)))


def main(episodes: int, runs: int, problem: str, domain: str = "delivery") -> dict[str, float]:
    instance = PDDLInstance.from_files(shipped("domains", f"{domain}.pddl"),
                                       shipped("problems", f"{problem}.pddl"),
                                       shipped("dynamics", f"{domain}.toml"))
    context = pddl_task_context(instance)
    env = PDDLEnv(instance=instance)
    v_star = solve(instance.model, GOAL_POS).V[0, 0]
    print(f"{problem}: {instance.n_states} states, {instance.n_actions} ground actions, "
          f"shortest plan {instance.graph.distances[0]} actions, V* = {v_star:.2f}")
    means = {}
    for method, config in (("gdq", {}), ("gdq", {"variant": "code"}), ("darling", {}),
                           ("dynaq", {}), ("qlearning", {})):
        totals = []
        for run in range(runs):
            env.reset(seed=run)
            learner = make_learner(method, context, **config)
            records = run_episodes(learner, env, episodes, np.random.default_rng(run))
            totals.append(records.returns.mean())
        name = "gdq-code" if config else method
        means[name] = float(np.mean(totals))
        print(f"{name:10s} mean return per episode over {runs} runs: {means[name]:7.2f}")
    return means


if __name__ == "__main__":
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--episodes", type=int, default=300)
    parser.add_argument("--runs", type=int, default=3)
    parser.add_argument("--problem", default="delivery-1", help="delivery-1 or delivery-2")
    main(**vars(parser.parse_args()))
