"""Experiments: the paper's protocol, run in parallel, resumable, collected as CSV/JSON."""

from gdq_pddl.experiments.interrupts import RunInterrupted
from gdq_pddl.experiments.protocol import (
    DEFAULT_METHODS,
    METHODS,
    PAPER_METHODS,
    Experiment,
    Hyper,
    ProblemSpec,
    Unit,
    paper_protocol,
    robot_experiment,
    switch_experiment,
    task_experiments,
)
from gdq_pddl.experiments.runner import ResultsError, run_experiments

__all__ = ["DEFAULT_METHODS", "METHODS", "PAPER_METHODS", "Experiment", "Hyper", "ProblemSpec",
           "ResultsError", "RunInterrupted", "Unit", "paper_protocol", "robot_experiment",
           "run_experiments", "switch_experiment", "task_experiments"]
