"""The keys grid written in PPDDL: a domain that is its own reality.

What it shows: a PPDDL domain (probabilistic effects, an outcome that makes `(stuck)`
true, action costs, a goal reward) runs with no dynamics file, through the same runner
as every other domain; the planner knows its all-outcomes determinisation (or
`--determinisation most-likely`). A small overlay adds what PPDDL cannot say (the step
limit, the mud's cost as a distribution), and then the true model is that of
`domains/keys.pddl` with `keys.toml`: the same V*.

    python examples/domain_keys_ppddl.py --episodes 300 --runs 3
"""

from __future__ import annotations

import argparse
import tempfile
from pathlib import Path

from gdq_pddl.analysis import report_text
from gdq_pddl.envs.pddl_env import GOAL_POS, PDDLInstance
from gdq_pddl.envs.solve import solve
from gdq_pddl.experiments import DEFAULT_METHODS, Experiment, ProblemSpec, run_experiments
from gdq_pddl.resources import data_file


def shipped(*parts: str) -> str:
    return str(data_file(*parts))


def v_star(instance: PDDLInstance) -> float:
    return float(solve(instance.model, GOAL_POS).V[0, 0])


def main(episodes: int, runs: int, determinisation: str) -> str:
    domain = shipped("domains", "keys-ppddl.pddl")
    problem = shipped("problems", "keys-ppddl-2.pddl")
    alone = PDDLInstance.from_files(domain, problem, determinisation=determinisation)
    exact = PDDLInstance.from_files(domain, problem, shipped("dynamics", "keys-ppddl.toml"))
    toml = PDDLInstance.from_files(shipped("domains", "keys.pddl"),
                                   shipped("problems", "keys-2.pddl"),
                                   shipped("dynamics", "keys.toml"))
    print(f"V*: PPDDL alone {v_star(alone):.4f} (step limit {alone.dynamics.step_limit}), "
          f"with the overlay {v_star(exact):.10f}, keys.pddl + keys.toml {v_star(toml):.10f}")
    exp = Experiment("keys-ppddl", ((alone.name, episodes),), runs=runs, world="pddl",
                     pddl=ProblemSpec(domain, problem, determinisation=determinisation),
                     methods=DEFAULT_METHODS)
    with tempfile.TemporaryDirectory() as tmp:
        out = run_experiments([exp], Path(tmp), jobs=1, progress=False)
        report = report_text(out)
    print(report)
    return report


if __name__ == "__main__":
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--episodes", type=int, default=300)
    parser.add_argument("--runs", type=int, default=3)
    parser.add_argument("--determinisation", default="all-outcomes",
                        choices=("all-outcomes", "most-likely"))
    main(**vars(parser.parse_args()))
