"""A problem far too large to enumerate, explored online: 23 blocks that crack.

What it shows: `cracking-1` (gdq_pddl's own `cracking-blocks` domain) has more states
than any memory, so its states are found as the episodes reach them
(`gdq_pddl.envs.online`); the knowledge's distances are h_add estimates. First one
learner by hand (the API), then GDQ, DARLING and Q-learning through the experiment runner,
with the report. The command line does the same: `gdq-pddl run --domain cracking-blocks
--problem cracking-1` (online by itself once the states do not fit).

    python examples/domain_cracking.py --episodes 100 --runs 2
"""

from __future__ import annotations

import argparse
import tempfile
from pathlib import Path

import numpy as np

from gdq_pddl.analysis import report_text
from gdq_pddl.envs.online import OnlineInstance
from gdq_pddl.envs.online_env import OnlineEnv
from gdq_pddl.envs.pddl_env import PDDLInstance
from gdq_pddl.experiments import Experiment, ProblemSpec, run_experiments
from gdq_pddl.learners import GDQ, make_learner, run_episodes
from gdq_pddl.learners.online import online_context
from gdq_pddl.resources import data_file


def main(episodes: int, runs: int) -> str:
    domain = str(data_file("domains", "cracking-blocks.pddl"))
    problem = str(data_file("problems", "cracking-1.pddl"))
    # GDQ reads a state not reached yet as ceil(1.25 h) actions from the goal, as the
    # experiment runner gives it (GDQ.estimate_weight; DARLING reads h itself)
    instance = OnlineInstance(PDDLInstance.from_files(domain, problem),
                              estimate_weight=GDQ.estimate_weight)
    learner = make_learner("GDQ", online_context(instance))
    env = OnlineEnv(instance)
    env.reset(seed=0)
    records = run_episodes(learner, env, episodes, np.random.default_rng(0))
    found = int(instance.graph.expanded.sum())
    print(f"GDQ alone: mean return {records.mean_return:.2f}, success "
          f"{records.success_rate:.0%}; {found} states expanded, "
          f"{instance.graph.n_states} found (the estimate from the start: "
          f"{instance.h_start} actions, step limit {instance.dynamics.step_limit})")
    exp = Experiment("cracking", ((instance.name, episodes),), runs=runs, world="pddl",
                     pddl=ProblemSpec(domain, problem, exploration="online"),
                     methods=("GDQ", "DARLING", "Q-learning"))
    with tempfile.TemporaryDirectory() as tmp:
        out = run_experiments([exp], Path(tmp), jobs=1, progress=False)
        report = report_text(out)
    print(report)
    return report


if __name__ == "__main__":
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--episodes", type=int, default=100)
    parser.add_argument("--runs", type=int, default=2)
    main(**vars(parser.parse_args()))
