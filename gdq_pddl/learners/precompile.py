"""Compile the episode loop in a process of its own: ``python -m gdq_pddl.learners.precompile
METHOD ...``.

The compiled episode loop is the package's largest kernel. The experiment runner starts
this module in a second process (:func:`start`) while it compiles the other kernels;
numba's on-disk cache hands the loop over, so on two cores a first run waits for the
longer of the two compiles, not their sum.
"""

from __future__ import annotations

import subprocess
import sys
from collections.abc import Sequence

from gdq_pddl.envs.office import OfficeEnv
from gdq_pddl.learners import episodes
from gdq_pddl.learners.agents import QLearning
from gdq_pddl.learners.context import office_task_context
from gdq_pddl.world import builtin_world


def compile_loop() -> None:
    """Compile the built-in learners' episode loop (or load it from numba's cache), with
    the argument types of a Q-learner on the office (the same for every built-in learner
    on any ``ModelArrays`` env); nothing runs."""
    world = builtin_world("office")
    env = OfficeEnv(world=world, task="C")
    env.reset(seed=0)
    episodes.compile_loop(QLearning(office_task_context(world, "C")), env)


def start(methods: Sequence[str] = ()) -> subprocess.Popen | None:
    """Start :func:`compile_loop` in a new process (None if it cannot be started);
    ``methods``: the run's (the loop is the same for every built-in one)."""
    try:
        return subprocess.Popen([sys.executable, "-m", __name__],
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
    compile_loop()
