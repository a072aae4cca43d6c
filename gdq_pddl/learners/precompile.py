"""Compile the episode loops in a process of its own: ``python -m gdq_pddl.learners.precompile
METHOD ...``.

A learner's compiled episode loop is its largest kernel. The experiment runner starts
this module in a second process (:func:`start`) while it compiles the other kernels;
numba's on-disk cache hands the loop over, so on two cores a first run waits for the
longer of the two compiles, not their sum.
"""

from __future__ import annotations

import subprocess
import sys
from collections.abc import Sequence

from gdq_pddl.envs.office import OfficeEnv
from gdq_pddl.learners import episodes, registry
from gdq_pddl.learners.context import office_task_context
from gdq_pddl.learners.tabular import TabularLearner
from gdq_pddl.world import builtin_world


def compile_loop(methods: Sequence[str]) -> None:
    """Compile the episode loops of ``methods`` (or load them from numba's cache), with the
    argument types of their learners on the office (the same on any ``ModelArrays`` env);
    nothing runs. A method whose learner cannot be made on the office is left out."""
    world = builtin_world("office")
    env = OfficeEnv(world=world, task="C")
    env.reset(seed=0)
    context = office_task_context(world, "C")
    for method in methods:
        try:
            learner = registry.make_learner(method, context)
        except Exception:  # noqa: BLE001  # not on the office: the run compiles it itself
            continue
        if isinstance(learner, TabularLearner):
            episodes.compile_loop(learner, env)


def start(methods: Sequence[str] = ()) -> subprocess.Popen | None:
    """Start :func:`compile_loop` of ``methods`` in a new process (None if it cannot be
    started, or nothing to compile)."""
    if not methods:
        return None
    try:
        return subprocess.Popen([sys.executable, "-m", __name__, *methods],
                                stdin=subprocess.DEVNULL, stdout=subprocess.DEVNULL,
                                stderr=subprocess.DEVNULL)
    except OSError:
        return None


def wait(process: subprocess.Popen | None, timeout: float = 600.0) -> None:
    """Wait for a process from :func:`start` (killed past ``timeout`` seconds: the caller
    then compiles the loop itself, which is always correct)."""
    if process is None:
        return
    try:
        process.wait(timeout)
    except subprocess.TimeoutExpired:
        process.kill()
        process.wait()


if __name__ == "__main__":
    compile_loop(sys.argv[1:])
