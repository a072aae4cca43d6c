"""A run builds what its learners read, and no more: no planner runs for a learner that
reads no plans (issue 35, "compile what is used")."""

from __future__ import annotations

import subprocess
import sys

import numpy as np
import pytest

from gdq_pddl.envs.office import OfficeInstance
from gdq_pddl.envs.pddl_env import PDDLInstance, load_instance
from gdq_pddl.experiments.checks import check_instance
from gdq_pddl.experiments.protocol import Unit, task_experiments
from gdq_pddl.experiments.work import run_unit
from gdq_pddl.learners.tables import KIND_DARLING, KIND_QLEARNING, Params, QTable, greedy


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


def test_the_command_and_its_report_import_no_scipy_stats_nor_networkx():
    """scipy.stats (0.6 s of CPU to import) is loaded only by a report that compares
    methods or tasks (bootstrap, Welch's t-test), networkx (0.2 s) only by the graph
    planner's search, not by every command."""
    code = ("import sys, gdq_pddl.cli, gdq_pddl.analysis; "
            "print([m for m in ('scipy.stats', 'networkx') if m in sys.modules])")
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True,
                         check=True)
    assert out.stdout.strip() == "[]"


def test_the_greedy_policy_is_the_lowest_allowed_action_of_maximal_q():
    """Plain numpy (no compile for a call made once per run), as the compiled loop it
    replaces: ties to the lowest action, a row with nothing allowed gives 0, DARLING reads
    its guide."""
    rng = np.random.default_rng(0)
    q = rng.integers(-2, 3, size=(200, 7)).astype(np.float64)  # many ties
    allowed, guide = rng.random((200, 7)) < 0.6, rng.random((200, 7)) < 0.6
    allowed[:5] = False
    for kind, mask in ((KIND_QLEARNING, allowed), (KIND_DARLING, guide)):
        table = QTable(q, q.max(axis=1), allowed, guide, guide.sum(axis=1),
                       np.zeros(200, dtype=np.bool_), np.full(200, 7))
        expected = [next((a for a in range(7) if mask[s, a] and q[s, a] == q[s][mask[s]].max()),
                         0) if mask[s].any() else 0 for s in range(200)]
        got = greedy(table, Params(kind, *[0] * (len(Params._fields) - 1)))
        assert got.dtype == np.int64 and got.tolist() == expected
    assert not hasattr(greedy, "py_func")  # not a numba dispatcher
