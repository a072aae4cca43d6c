"""Every example runs with a tiny budget (CI runs them all)."""

from __future__ import annotations

import subprocess
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


def _ppo_argv(*argv: str, prelude: str = "") -> list[str]:
    code = (f"import runpy, sys; {prelude}sys.argv = ['maskable_ppo.py', *{list(argv)}]; "
            f"runpy.run_path({str(EXAMPLES / 'maskable_ppo.py')!r}, run_name='__main__')")
    return [sys.executable, "-c", code]


def _maskable_ppo(*argv: str, prelude: str = "") -> subprocess.CompletedProcess:
    return subprocess.run(_ppo_argv(*argv, prelude=prelude), capture_output=True, text=True,
                          timeout=600)


def start_without_sb3(item) -> Future:
    """The example without sb3_contrib, in the Background queue (an interpreter start)."""
    return BACKGROUND.run("maskable_ppo without sb3",
                          _ppo_argv(prelude="sys.modules['sb3_contrib'] = None; "))


@pytest.mark.background.with_args(start_without_sb3)
def test_maskable_ppo_example_says_what_it_needs(request):
    result = start_without_sb3(request.node).result()
    assert result.returncode == 1 and "pip install 'gdq_pddl[sb3]'" in result.stderr


@pytest.mark.slow  # torch: a minute to import and train on a busy machine
def test_maskable_ppo_example_runs():
    pytest.importorskip("sb3_contrib")  # the [sb3] extra, not in the test install
    result = _maskable_ppo("--steps", "2048", "--eval-every", "1024", "--eval-episodes", "5")
    assert result.returncode == 0, result.stderr[-2000:]
    assert "MaskablePPO" in result.stdout and "GDQ" in result.stdout
