"""A grid with keys and locked doors, run through the command line's machinery.

What it shows: an `Experiment` with `pddl=ProblemSpec(domain, problem, dynamics)` runs on any PDDL
problem through the same runner as the office (parallel, resumable, one seed per run),
and `report_text` summarises it. The red door is nearer, but its lock jams
and can end the trial; the best route fetches the blue key (on keys-2 that is not a
shortest plan).

    python examples/domain_keys.py --episodes 300 --runs 3 --problem keys-2
"""

from __future__ import annotations

import argparse
import tempfile
from pathlib import Path

from gdq_pddl.analysis import report_text
from gdq_pddl.experiments import Experiment, ProblemSpec, run_experiments
from gdq_pddl.resources import data_file


def shipped(*parts: str) -> str:
    return str(data_file(*parts))


def main(episodes: int, runs: int, problem: str) -> str:
    spec = ProblemSpec(shipped("domains", "keys.pddl"), shipped("problems", f"{problem}.pddl"),
                       shipped("dynamics", "keys.toml"))
    exp = Experiment("keys", ((problem, episodes),), runs=runs, world="pddl", pddl=spec,
                     methods=("GDQ", "GDQ-code", "DARLING", "Dyna-Q", "Q-learning"))
    with tempfile.TemporaryDirectory() as tmp:
        out = run_experiments([exp], Path(tmp), jobs=1, progress=False)
        report = report_text(out)
    print(report)
    return report


if __name__ == "__main__":
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--episodes", type=int, default=300)
    parser.add_argument("--runs", type=int, default=3)
    parser.add_argument("--problem", default="keys-2", help="keys-1 or keys-2")
    main(**vars(parser.parse_args()))
