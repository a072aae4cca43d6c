"""Task C on the specialised office env and on the generic PDDL env: do they agree?

The generic env runs domains/office.pddl + problems/task-c.pddl under the world file
gdq_pddl/data/office.toml. Its true model is the office's (same V*: a test checks it to
1e-9), but the learner sees more: 828 full planner states (which doors are open anywhere)
instead of 31 observations, and the 58 ground actions instead of
95 verb x position actions. So learning curves differ; this script measures by how much.

    python benchmarks/office_generic.py --episodes 2500 --runs 10
"""

from __future__ import annotations

import argparse
import time

import numpy as np

from gdq_pddl.envs.office import OfficeEnv
from gdq_pddl.envs.pddl_env import PDDLEnv, PDDLInstance
from gdq_pddl.learners import make_learner, office_task_context, pddl_task_context, run_episodes
from gdq_pddl.resources import data_file
from gdq_pddl.world import load_world

METHODS = (("GDQ", "gdq", {}), ("GDQ-code", "gdq", {"variant": "code"}),
           ("DARLING", "darling", {}),
           ("Dyna-Q", "dynaq", {}), ("Q-learning", "qlearning", {}))


def returns(env, context, method: str, config: dict, episodes: int, runs: int) -> np.ndarray:
    """float[runs, episodes] of returns (env seed = run, learner seed = 1000 + run)."""
    out = np.zeros((runs, episodes))
    for run in range(runs):
        env.reset(seed=run)
        learner = make_learner(method, context, **config)
        out[run] = run_episodes(learner, env, episodes, np.random.default_rng(1000 + run)).returns
    return out


def main(episodes: int, runs: int) -> None:
    world = load_world()
    office = OfficeEnv(world=world, task="C")
    office_ctx = office_task_context(world, "C")
    instance = PDDLInstance.from_files(str(data_file("domains", "office.pddl")),
                                       str(data_file("problems", "task-c.pddl")),
                                       str(data_file("office.toml")))
    generic = PDDLEnv(instance=instance)
    generic_ctx = pddl_task_context(instance)
    first = min(300, episodes)
    print(f"Task C, {runs} runs x {episodes} episodes; mean return per episode, mean over runs"
          f" (SE); 'first {first}': episodes 1-{first}; last 500: the final 500")
    print(f"{'method':11s} {'env':8s} {'all':>14s} {f'first {first}':>14s} {'last 500':>14s}"
          f" {'time':>6s}")
    for label, method, config in METHODS:
        for name, env, ctx in (("office", office, office_ctx), ("generic", generic, generic_ctx)):
            t0 = time.perf_counter()
            r = returns(env, ctx, method, config, episodes, runs)
            cols = [r.mean(axis=1), r[:, :first].mean(axis=1), r[:, -500:].mean(axis=1)]
            text = " ".join(f"{c.mean():7.2f} ({c.std(ddof=1) / np.sqrt(runs):4.2f})"
                            for c in cols)
            print(f"{label:11s} {name:8s} {text} {time.perf_counter() - t0:5.1f}s")


if __name__ == "__main__":
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--episodes", type=int, default=2500)
    parser.add_argument("--runs", type=int, default=10)
    main(**vars(parser.parse_args()))
