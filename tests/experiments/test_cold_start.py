"""A run builds what its learners read, and no more: no planner runs for a learner that
reads no plans (issue 35, "compile what is used")."""

from __future__ import annotations

import subprocess
import sys

import pytest

from gdq_pddl.envs.office import OfficeInstance
from gdq_pddl.envs.pddl_env import PDDLInstance, load_instance
from gdq_pddl.experiments.checks import check_instance
from gdq_pddl.experiments.protocol import Unit, task_experiments
from gdq_pddl.experiments.work import run_unit


@pytest.fixture
def no_plan_table(monkeypatch):
    """Any plan table built fails the test."""
    def refuse(self, *args, **kwargs):
        raise AssertionError("a plan table was built")

    for cls in (OfficeInstance, PDDLInstance):
        monkeypatch.setattr(cls, "plan_table", refuse)


def test_the_checks_before_a_run_build_no_plan_table(no_plan_table):
    check_instance(OfficeInstance.of("C"))
    check_instance(load_instance("keys-ppddl", "keys-ppddl-2"))


@pytest.mark.parametrize("method", ["Q-learning", "Dyna-Q", "R-max", "GDQ"])
def test_a_learner_that_reads_no_plans_runs_without_a_plan_table(no_plan_table, method):
    (exp,) = task_experiments(tasks=("C",), episodes=2, runs=1, methods=(method,))
    assert len(run_unit(Unit(exp, method, 0))["returns"]) == 2


def test_the_command_and_its_report_import_no_scipy_stats():
    """scipy.stats (0.6 s of CPU to import) is loaded only by a report that compares
    methods or tasks (bootstrap, Welch's t-test), not by every command."""
    code = "import sys, gdq_pddl.cli, gdq_pddl.analysis; print('scipy.stats' in sys.modules)"
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True,
                         check=True)
    assert out.stdout.strip() == "False"
