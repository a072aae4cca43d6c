"""The episode loops honour what wraps the env (issue 21 item 2): the compiled loop runs
only where it gives what stepping the env gives (``why_not_compiled``), else every step
goes through the wrappers."""

from __future__ import annotations

import gymnasium
import numpy as np
import pytest
from gymnasium.wrappers import RecordEpisodeStatistics, TimeLimit, TransformReward

from gdq_pddl.envs.office import CompactEnv
from gdq_pddl.errors import ConfigError
from gdq_pddl.learners import QLearning, make_learner, registry, run_compact
from gdq_pddl.learners.episodes import compiled_learner, why_not_compiled
from tests.helpers import run


def office(**kw):
    return gymnasium.make("gdq_pddl/Office-v0", task="C", **kw)


def test_transform_reward_is_what_the_loop_and_the_learner_see(ctx_c):
    env = TransformReward(office(), lambda r: -1.0)
    learner = make_learner("GDQ", ctx_c)
    assert "TransformReward" in why_not_compiled(learner, env)
    rec = run(learner, env, 20, 0)
    assert np.array_equal(rec.returns, -rec.steps.astype(float))
    with pytest.raises(ConfigError, match="fast=True: the env is wrapped in TransformReward"):
        run(make_learner("GDQ", ctx_c), env, 2, 0, fast=True)


def test_a_shorter_time_limit_ends_the_episodes(ctx_c):
    rec = run(QLearning(ctx_c), TimeLimit(office(), 5), 30, 0)
    assert rec.steps.max() == 5 and (rec.steps <= 5).all()
    bare = run(QLearning(ctx_c), office(), 30, 0)
    assert bare.steps.max() > 5  # without the wrapper they run longer


def test_gymnasium_makes_own_wrappers_keep_the_compiled_loop(ctx_c):
    """OrderEnforcing, PassiveEnvChecker and a TimeLimit of the env's own limit change
    nothing: the compiled loop runs, with the bare env's results."""
    limit = office().unwrapped.model.step_limit
    made = office(max_episode_steps=limit)
    assert why_not_compiled(QLearning(ctx_c), made) is None
    assert why_not_compiled(QLearning(ctx_c), TimeLimit(office(), limit - 1)) is not None
    a = run(QLearning(ctx_c), made, 40, 2)
    b = run(QLearning(ctx_c), office().unwrapped, 40, 2, fast=False)
    for f in ("returns", "steps", "success", "area_visits"):
        assert np.array_equal(getattr(a, f), getattr(b, f)), f


def test_record_episode_statistics_records_every_episode(ctx_c):
    env = RecordEpisodeStatistics(office())
    rec = run(QLearning(ctx_c), env, 12, 0)
    assert list(env.return_queue) == pytest.approx(rec.returns.tolist())
    assert list(env.length_queue) == rec.steps.tolist()


class Permuted(gymnasium.ObservationWrapper):
    """Shows learner state ``perm[s]`` for state ``s``."""

    def __init__(self, env, perm):
        super().__init__(env)
        self.perm = perm

    def observation(self, observation):
        return int(self.perm[observation])


def test_an_observation_wrapper_is_what_the_learner_sees(ctx_c):
    """Q-learning knows nothing of the task, so relabelling the states changes nothing but
    the rows of its table: the loop saw the wrapped observations."""
    perm = np.random.default_rng(0).permutation(ctx_c.n_states)
    wrapped, bare = QLearning(ctx_c), QLearning(ctx_c)
    rw = run(wrapped, Permuted(office(), perm), 40, 1)
    rb = run(bare, office(), 40, 1)
    assert np.array_equal(rw.returns, rb.returns) and np.array_equal(rw.steps, rb.steps)
    assert np.array_equal(wrapped.q[perm], bare.q)
    assert not np.array_equal(wrapped.q, bare.q)


def test_run_compact_honours_wrappers_too(ctx_c):
    env = TransformReward(CompactEnv(task="C"), lambda r: -1.0)
    env.reset(seed=0)
    rec = run_compact(QLearning(ctx_c), env, 10, np.random.default_rng(0))
    assert np.array_equal(rec.returns, -rec.steps.astype(float))


def test_a_reset_with_options_does_not_move_the_compiled_loops_start(ctx_c):
    """reset(options=...) holds for one episode: run_episodes' episodes then start where
    reset() without options starts them, on the compiled loop as on the Python loop."""
    recs = []
    for fast in (True, False):
        env = office()
        env.reset(options={"start": "p3"})
        recs.append(run(QLearning(ctx_c), env, 30, 2, fast=fast))
    for f in ("returns", "steps", "success", "area_visits"):
        assert np.array_equal(getattr(recs[0], f), getattr(recs[1], f)), f


def test_every_built_in_tabular_learner_runs_in_the_compiled_loop(ctx_c):
    """Each keeps TabularLearner's act and observe (or is one of COMPILED_LEARNERS, whose
    override the loop does itself): none falls back to the Python loop unnoticed."""
    names = [n for n in registry.built_in_names() if not registry.entry(n).requires]
    assert len(names) >= 13
    for name in names:
        assert compiled_learner(make_learner(name, ctx_c)), name
