"""Every example runs with a tiny budget (CI runs them all)."""

from __future__ import annotations

import subprocess
import sys

import pytest

from tests.helpers import REPO_ROOT

EXAMPLES = REPO_ROOT / "examples"
BUDGET = {"task_x.py": ["--trials", "5"]}


@pytest.mark.parametrize("script", sorted(p.name for p in [*EXAMPLES.glob("task_*.py"),
                                                           *EXAMPLES.glob("domain_*.py")]))
def test_example_runs(script):
    argv = BUDGET.get(script, ["--episodes", "20"])
    if script == "task_b.py" or script.startswith("domain_"):
        argv += ["--runs", "1"]
    result = subprocess.run([sys.executable, str(EXAMPLES / script), *argv],
                            capture_output=True, text=True, timeout=300)
    assert result.returncode == 0, result.stderr[-2000:]
    assert result.stdout.strip()


def test_there_is_an_example_per_task():
    assert {p.stem for p in EXAMPLES.glob("task_*.py")} == {f"task_{t}" for t in "abcdex"}
    assert (EXAMPLES / "planner_plugin" / "pyproject.toml").exists()
