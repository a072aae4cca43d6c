"""Compile the episode loop in a process of its own: ``python -m gdq_pddl.learners.precompile
METHOD ...``.

The compiled episode loop is the package's largest kernel, compiled once per pair of a
learner's rules (``TabularLearner.rules_for``). The experiment runner starts this module
in a second process (:func:`start`) for the methods it runs while it compiles the other
kernels; numba's on-disk cache hands the loops over, so on two cores a first run waits
for the longer of the two compiles, not their sum.
"""

from __future__ import annotations

import subprocess
import sys
from collections.abc import Sequence

from gdq_pddl.envs.office import OfficeEnv
from gdq_pddl.learners import episodes, registry
from gdq_pddl.learners.agents import QLearning
from gdq_pddl.learners.context import office_task_context
from gdq_pddl.world import builtin_world


def rules_of(method: str) -> tuple:
    """``(act_rule, observe_rule)`` of ``method`` (a name or a spec), without making it."""
    parsed = registry.parse_method(method)
    config = parsed.entry.config(**parsed.config_kwargs())
    return parsed.entry.learner_class().rules_for(config)


def compile_loop(methods: Sequence[str] = ()) -> None:
    """Compile the episode loop for the rules of ``methods`` (none: a Q-learner's), with
    the argument types of a Q-learner on the office (the same for every learner on any
    ``ModelArrays`` env); nothing runs."""
    world = builtin_world("office")
    env = OfficeEnv(world=world, task="C")
    env.reset(seed=0)
    learner = QLearning(office_task_context(world, "C"))
    pairs = {rules_of(m) for m in methods} or {(learner.act_rule, learner.observe_rule)}
    episodes.compile_loop(learner, env, pairs)


def start(methods: Sequence[str] = ()) -> subprocess.Popen | None:
    """Start :func:`compile_loop` of ``methods`` in a new process (None if it cannot be
    started)."""
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
