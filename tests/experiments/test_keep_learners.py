"""``gdq-pddl run --keep-learners`` saves each run's final learner, and it loads."""

from __future__ import annotations

import numpy as np

from gdq_pddl.learners import load_generators, load_learner, office_task_context
from tests.helpers import cli


def test_run_keeps_each_runs_final_learner(capsys, tmp_path, office):
    out = tmp_path / "out"
    code, text = cli(capsys, "run", "--task", "C", "--episodes", "4", "--runs", "1",
                     "--method", "GDQ", "Q-learning", "--jobs", "1",
                     "--no-report", "--keep-learners", "--out", out)
    assert code == 0, text
    ctx = office_task_context(office, "C")
    saved = sorted((out / "learners").glob("*.npz"))
    assert len(saved) == 2
    for path in saved:
        with np.load(out / "units" / path.name, allow_pickle=False) as unit:
            policy = unit["policy"]
        learner = load_learner(path, ctx)
        assert type(learner).__name__ == ("GDQ" if "__GDQ__" in path.name else "QLearning")
        assert np.array_equal(learner.greedy_policy(), policy)
        assert set(load_generators(path)) == {"rng", "env"}
