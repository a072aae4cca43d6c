"""The courier and the lift: two PPDDL domains of the IPPC's language, learnt with GDQ.

What it shows: `domains/courier.pddl` states IPPC rewards (`(decrease (reward) X)`, an
`(increase (reward) X)` under `(when ...)`, `(:goal-reward 20)`, `(:metric maximize
(reward))`) and a goal with alternatives, so its returns are on the problem's own scale:
what the IPPC would score. `domains/lift.pddl` has conditional effects under `forall`
and a disjunctive precondition, on the goal scale (+r_max at the goal, minus costs).
Neither needs a dynamics file. V* of courier-1 (30.75) and lift-1 (161/9) are derived by
hand in tests/envs/test_own_domains.py.

    python examples/domain_courier.py --episodes 300 --runs 3
"""

from __future__ import annotations

import argparse
import tempfile
from pathlib import Path

from gdq_pddl.analysis import report_text
from gdq_pddl.envs.pddl_env import PDDLInstance
from gdq_pddl.experiments import Experiment, ProblemSpec, run_experiments
from gdq_pddl.resources import data_file

METHODS = ("GDQ", "DARLING", "Dyna-Q", "Q-learning")


def main(episodes: int, runs: int) -> str:
    experiments = []
    for domain, problem in (("courier", "courier-2"), ("lift", "lift-2")):
        spec = ProblemSpec(str(data_file("domains", f"{domain}.pddl")),
                           str(data_file("problems", f"{problem}.pddl")))
        instance = PDDLInstance.from_files(spec.domain, spec.problem)
        print(f"{problem}: {instance.n_states} states, {instance.n_actions} ground actions, "
              f"returns on the {instance.reward_scale} scale, V* = "
              f"{instance.optimal()['v_star']:.4f}")
        experiments.append(Experiment(problem, ((instance.name, episodes),), runs=runs,
                                      world="pddl", pddl=spec, methods=METHODS))
    with tempfile.TemporaryDirectory() as tmp:
        report = report_text(run_experiments(experiments, Path(tmp), jobs=1, progress=False))
    print(report)
    return report


if __name__ == "__main__":
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--episodes", type=int, default=300)
    parser.add_argument("--runs", type=int, default=3)
    main(**vars(parser.parse_args()))
