"""Every example runs with a tiny budget (CI runs them all)."""

from __future__ import annotations

import json
import subprocess
import sys
from concurrent.futures import Future

import pytest

from tests.helpers import BACKGROUND, REPO_ROOT

EXAMPLES = REPO_ROOT / "examples"
BUDGET = {"task_x.py": ["--trials", "5"]}
SCRIPTS = sorted(p.name for p in [*EXAMPLES.glob("task_*.py"), *EXAMPLES.glob("domain_*.py")])


RUN_EXAMPLES = """
import json, os, runpy, sys, tempfile, traceback
from gdq_pddl.learners.precompile import compile_loop
# the package imported and the episode loops the examples run loaded once, before the forks
compile_loop(("GDQ", "GDQ-code", "DARLING", "Dyna-Q", "Q-learning"))
done = {}
for script, *argv in json.loads(sys.argv[1]):
    out, err = tempfile.TemporaryFile("w+"), tempfile.TemporaryFile("w+")
    pid = os.fork()
    if pid == 0:  # the example as a script: its own __main__, argv and output
        os.dup2(out.fileno(), 1)
        os.dup2(err.fileno(), 2)
        sys.argv, code = [script, *argv], 0
        try:
            runpy.run_path(script, run_name="__main__")
        except SystemExit as exc:
            code = exc.code if isinstance(exc.code, int) else 1
        except BaseException:
            traceback.print_exc()
            code = 1
        sys.stdout.flush()
        sys.stderr.flush()
        os._exit(code)
    status = os.waitstatus_to_exitcode(os.waitpid(pid, 0)[1])
    out.seek(0)
    err.seek(0)
    done[os.path.basename(script)] = [status, out.read(), err.read()]
print(json.dumps(done))
"""
"""Runs every example, each in a process forked from one that imported the package once:
an example spends most of its time starting an interpreter and loading the compiled
kernels, and the examples run one after another on the second core."""


def argv_of(script: str) -> list[str]:
    argv = BUDGET.get(script, ["--episodes", "20"])
    if script == "task_b.py" or script.startswith("domain_"):
        argv += ["--runs", "1"]
    return argv


def start(item=None) -> Future:
    """Every example, queued when collection ends to run beside the other tests
    (``tests.helpers.Background``); the future's stdout maps a script to
    ``[exit status, stdout, stderr]``."""
    jobs = [[str(EXAMPLES / script), *argv_of(script)] for script in SCRIPTS]
    return BACKGROUND.run("examples", [sys.executable, "-c", RUN_EXAMPLES, json.dumps(jobs)],
                          timeout=600)


@pytest.mark.parametrize("script", SCRIPTS)
@pytest.mark.background.with_args(start)
def test_example_runs(script, request):
    result = start(request.node).result()
    assert result.returncode == 0, result.stderr[-2000:]
    status, out, err = json.loads(result.stdout)[script]
    assert status == 0, err[-2000:]
    assert out.strip()


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
