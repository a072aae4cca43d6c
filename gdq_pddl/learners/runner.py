"""Run a learner for a number of episodes and record what happened.

Two paths with identical results for the same seeds:

- a generic Python loop over any gymnasium env of this package (``env.reset``,
  ``env.step``, ``learner.act`` / ``learner.observe``);
- a fast path, used when ``env.unwrapped`` is a :class:`~gdq_pddl.envs.base.ModelEnv`
  (the office, or a PDDL domain) and the learner one of
  :mod:`gdq_pddl.learners.agents`: one compiled loop calling
  :func:`gdq_pddl.envs.model.env_step` and the same :mod:`~gdq_pddl.learners.core` rules.

Environment randomness comes from ``env.unwrapped.np_random`` (seed it with
``env.reset(seed=...)`` before calling), learner randomness from ``rng``. Neither path
draws anything else, so for the same generators both consume the same numbers.
"""

from __future__ import annotations

from dataclasses import dataclass

import gymnasium as gym
import numba
import numpy as np

from gdq_pddl.envs.base import ModelEnv
from gdq_pddl.envs.model import CAUSE_GOAL, ModelArrays, env_step
from gdq_pddl.learners import core
from gdq_pddl.learners.agents import Learner, TabularLearner


@dataclass(frozen=True)
class EpisodeRecords:
    """Per-episode outcomes of a run."""

    returns: np.ndarray
    """float64[n]: undiscounted sum of the rewards of each episode."""
    steps: np.ndarray
    """int64[n]: actions taken in each episode."""
    success: np.ndarray
    """bool[n]: whether the episode reached the goal."""
    area_visits: np.ndarray
    """int64[n, n_areas]: column ``k - 1`` counts the steps of the episode whose resulting
    position lies in area ``k`` (the start position is not counted; a step that leaves the
    robot where it was counts again for that area)."""

    def __len__(self) -> int:
        return len(self.returns)


def _n_areas(env: gym.Env) -> int:
    model = getattr(env.unwrapped, "model", None)
    if model is None:
        raise TypeError("run_episodes needs an env of this package (env.unwrapped.model)")
    return int(model.area_of_pos.max())


def run_episodes(learner: Learner, env: gym.Env, n_episodes: int,
                 rng: np.random.Generator, fast: bool | None = None) -> EpisodeRecords:
    """Run ``n_episodes`` episodes of ``learner`` in ``env`` (learning as it goes).

    ``fast=None`` picks the compiled loop when possible; ``True`` demands it and
    ``False`` forces the Python loop (both give the same results).
    """
    can_fast = isinstance(env.unwrapped, ModelEnv) and isinstance(learner, TabularLearner)
    if fast is None:
        fast = can_fast
    if fast and not can_fast:
        raise TypeError("the fast path needs an env of this package (a ModelEnv) and a "
                        "TabularLearner")
    if fast:
        return _run_fast(learner, env, n_episodes, rng)  # type: ignore[arg-type]
    return _run_python(learner, env, n_episodes, rng)


def _run_python(learner: Learner, env: gym.Env, n_episodes: int,
                rng: np.random.Generator) -> EpisodeRecords:
    n_areas = _n_areas(env)
    returns = np.zeros(n_episodes)
    steps = np.zeros(n_episodes, dtype=np.int64)
    success = np.zeros(n_episodes, dtype=np.bool_)
    areas = np.zeros((n_episodes, n_areas), dtype=np.int64)
    for ep in range(n_episodes):
        s, _ = env.reset()
        done = False
        while not done:
            a = learner.act(s, rng)
            s2, r, terminated, truncated, info = env.step(a)
            learner.observe(s, a, r, s2, terminated, truncated, rng)
            returns[ep] += r
            steps[ep] += 1
            if info["area"] > 0:
                areas[ep, info["area"] - 1] += 1
            if terminated and info["cause"] == "goal":
                success[ep] = True
            done = terminated or truncated
            s = s2
    return EpisodeRecords(returns, steps, success, areas)


def _run_fast(learner: TabularLearner, env: gym.Env, n_episodes: int,
              rng: np.random.Generator) -> EpisodeRecords:
    office: ModelEnv = env.unwrapped  # type: ignore[assignment]
    n_areas = _n_areas(env)
    returns = np.zeros(n_episodes)
    steps = np.zeros(n_episodes, dtype=np.int64)
    success = np.zeros(n_episodes, dtype=np.bool_)
    areas = np.zeros((n_episodes, n_areas), dtype=np.int64)
    _episodes(office.model, int(office.start_state), int(office.goal_pos), learner.tables,
              learner.params, office.np_random, rng, returns, steps, success, areas)
    return EpisodeRecords(returns, steps, success, areas)


@numba.njit(cache=True)
def _episodes(m: ModelArrays, start: int, goal_pos: int, t: core.Tables, p: core.Params,
              env_rng: np.random.Generator, rng: np.random.Generator, returns: np.ndarray,
              steps: np.ndarray, success: np.ndarray, areas: np.ndarray) -> None:
    """The compiled episode loop (same calls, in the same order, as the Python loop)."""
    for ep in range(len(returns)):
        fs = start
        s = m.obs_of[fs]
        step = 0
        while True:
            a = core.act(t, p, s, rng)
            fs, r, terminated, truncated, cause = env_step(m, fs, a, step, goal_pos, env_rng)
            s2 = m.obs_of[fs]
            core.observe(t, p, s, a, r, s2, terminated, truncated, rng)
            step += 1
            returns[ep] += r
            area = m.area_of_pos[m.pos_of[fs]]
            if area > 0:
                areas[ep, area - 1] += 1
            if terminated or truncated:
                success[ep] = cause == CAUSE_GOAL
                break
            s = s2
        steps[ep] = step
