"""Every example runs with a tiny budget (CI runs them all)."""

from __future__ import annotations

import sys
from concurrent.futures import Future

import pytest

from tests.helpers import BACKGROUND, REPO_ROOT

EXAMPLES = REPO_ROOT / "examples"
BUDGET = {"task_x.py": ["--trials", "5"]}
SCRIPTS = sorted(p.name for p in [*EXAMPLES.glob("task_*.py"), *EXAMPLES.glob("domain_*.py")])


def start(item) -> Future:
    """The example as a user runs it: a fresh interpreter (nothing imported before it),
    queued when collection ends to run beside the other tests (``tests.helpers.Background``):
    each spends most of its time starting an interpreter and loading the compiled kernels."""
    script = item.callspec.params["script"]
    argv = BUDGET.get(script, ["--episodes", "20"])
    if script == "task_b.py" or script.startswith("domain_"):
        argv += ["--runs", "1"]
    return BACKGROUND.run(f"example {script}", [sys.executable, str(EXAMPLES / script), *argv],
                          timeout=300)


@pytest.mark.parametrize("script", SCRIPTS)
@pytest.mark.background.with_args(start)
def test_example_runs(script, request):
    result = start(request.node).result()
    assert result.returncode == 0, result.stderr[-2000:]
    assert result.stdout.strip()


def test_there_is_an_example_per_task():
    assert {p.stem for p in EXAMPLES.glob("task_*.py")} == {f"task_{t}" for t in "abcdex"}
    assert (EXAMPLES / "planner_plugin" / "pyproject.toml").exists()
