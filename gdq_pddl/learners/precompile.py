"""Compile the episode loop in a process of its own: ``python -m gdq_pddl.learners.precompile``.

The compiled episode loop is the package's largest kernel. The experiment runner starts
this module in a second process (:func:`start`) while it compiles the other kernels;
numba's on-disk cache hands the loop over, so on two cores a first run waits for the
longer of the two compiles, not their sum.
"""

from __future__ import annotations

import subprocess
import sys

import numpy as np

from gdq_pddl.envs.office import OfficeEnv
from gdq_pddl.learners.agents import make_learner
from gdq_pddl.learners.context import office_task_context
from gdq_pddl.learners.episodes import run_episodes
from gdq_pddl.world import builtin_world


def compile_loop() -> None:
    """Run one episode of a Q-learner on the office through the compiled loop (its
    signature is the same for every learner kind on any ``ModelArrays`` env)."""
    world = builtin_world("office")
    env = OfficeEnv(world=world, task="C")
    env.reset(seed=0)
    run_episodes(make_learner("Q-learning", office_task_context(world, "C")), env, 1,
                 np.random.default_rng(0), fast=True)


def start() -> subprocess.Popen | None:
    """Start :func:`compile_loop` in a new process (None if it cannot be started)."""
    try:
        return subprocess.Popen([sys.executable, "-m", __name__], stdin=subprocess.DEVNULL,
                                stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
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
