"""Helpers the learner tests share: a recording wrapper and a seeded episode run."""

from __future__ import annotations

import numpy as np

from gdq_pddl.learners import run_episodes


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
