"""Plain helpers the tests share (fixtures live in ``tests/conftest.py``).

Import them as ``from tests.helpers import ...``: ``tests`` and its layer folders are
packages, so pytest puts the repository root on ``sys.path`` wherever a test file lives.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

from gdq_pddl.learners import run_episodes

REPO_ROOT = Path(__file__).resolve().parent.parent
"""The repository checkout (``domains/``, ``problems/``, ``docs/``, ``examples/`` ...)."""
DYNAMICS = REPO_ROOT / "gdq_pddl" / "data" / "dynamics"
"""The shipped dynamics files (``keys.toml``, ``office.toml`` ...)."""


class Recording:
    """Wraps a learner and records the (state, action) pairs it executes."""

    def __init__(self, learner) -> None:
        self.learner, self.pairs = learner, []
        self.q = learner.q

    @property
    def states(self) -> list[int]:
        return [s for s, _ in self.pairs]

    @property
    def actions(self) -> list[int]:
        return [a for _, a in self.pairs]

    def act(self, s, rng):
        a = self.learner.act(s, rng)
        self.pairs.append((s, a))
        return a

    def observe(self, *args):
        self.learner.observe(*args)

    def start_task(self, ctx):
        self.learner.start_task(ctx)

    def greedy_policy(self):
        return self.learner.greedy_policy()


def run(learner, env, n, seed, fast=None):
    """``n`` episodes of ``learner`` on ``env`` reset with ``seed``, its draws from
    ``seed + 1``."""
    env.reset(seed=seed)
    return run_episodes(learner, env, n, np.random.default_rng(seed + 1), fast=fast)
