"""Run a learner for a number of episodes and record what happened.

Two paths with identical results for the same seeds: a Python loop over any gymnasium
env of this package, through its wrappers, and a compiled loop (:func:`_episodes`) over
the env's true dynamics where it gives exactly what stepping the env gives
(:func:`why_not_compiled`). Both call the same compiled rules and first give the learner
the successor slots its learned model needs in this env. Environment randomness comes
from ``env.unwrapped.np_random`` (seed it with ``env.reset(seed=...)``), the learner's
from ``rng``; neither path draws anything else.
"""

from __future__ import annotations

import multiprocessing
import os
import types as types_
from collections.abc import Iterable
from dataclasses import dataclass

import gymnasium as gym
import numba
import numpy as np
from gymnasium.wrappers import OrderEnforcing, PassiveEnvChecker, TimeLimit
from numba import types
from numba.extending import overload

from gdq_pddl.envs.compact import CompactModel, compact_step, observe_state
from gdq_pddl.envs.identity import PROBLEM_KEYS
from gdq_pddl.envs.office import CompactEnv
from gdq_pddl.envs.online_env import OnlineEnv
from gdq_pddl.envs.pddl_env import PDDLEnv
from gdq_pddl.envs.solve_compact import successor_capacity
from gdq_pddl.envs.step import CAUSE_GOAL, ModelArrays, env_step
from gdq_pddl.errors import ConfigError
from gdq_pddl.learners import guards, registry
from gdq_pddl.learners.gdq import reverse_room
from gdq_pddl.learners.gdq_learner import GDQ
from gdq_pddl.learners.learned_model import OVERFLOW
from gdq_pddl.learners.online import Follower
from gdq_pddl.learners.saving import GreedyPolicy, check_identity, identity_of
from gdq_pddl.learners.tables import KIND_GDQ, Params, Tables
from gdq_pddl.learners.tabular import Learner, TabularLearner
from gdq_pddl.limits import check_count, check_memory, slow_progress


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
    """int64[n, n_areas]: column ``k - 1`` counts the steps of the episode that end in
    area ``k`` (the start position is not counted, a step that stays counts again)."""

    def __len__(self) -> int:
        return len(self.returns)

    @property
    def mean_return(self) -> float:
        """The mean of :attr:`returns`."""
        return float(self.returns.mean())

    @property
    def success_rate(self) -> float:
        """The share of episodes that reached the goal, in [0, 1]."""
        return float(self.success.mean())


def _empty_records(n_episodes: int, n_areas: int) -> tuple[np.ndarray, ...]:
    """The zeroed arrays of :class:`EpisodeRecords`, filled in by the loops."""
    return (np.zeros(n_episodes), np.zeros(n_episodes, dtype=np.int64),
            np.zeros(n_episodes, dtype=np.bool_), np.zeros((n_episodes, n_areas), dtype=np.int64))


def _n_areas(env: gym.Env) -> int:
    model = getattr(env.unwrapped, "model", None)
    if model is None:
        raise TypeError("run_episodes needs an env of this package (env.unwrapped.model)")
    return int(model.area_of_pos.max())


SAME_RESULTS_WRAPPERS = (PassiveEnvChecker, OrderEnforcing, TimeLimit)
"""The wrappers the compiled loop may look through (exact types, not subclasses):
``gymnasium.make``'s own checkers, and a ``TimeLimit`` no shorter than the env's own step
limit (the env ends every episode first, or at the same step)."""
COMPILED_LEARNERS = (GDQ,)
"""The learner classes the compiled loop runs although they override ``observe`` (exact
types): GDQ's only reserves room in its reverse index first, which the loop does itself.
Every other learner runs in it when its class keeps :class:`TabularLearner`'s ``act`` and
``observe``, which call its compiled ``act_rule`` and ``observe_rule`` as the loop does
(:func:`compiled_learner`)."""


def compiled_learner(learner: Learner) -> bool:
    """Whether the compiled loop gives what ``learner``'s methods give: its class leaves
    ``act`` and ``observe`` to :class:`TabularLearner`, which call its compiled rules as
    the loop does, or is one of :data:`COMPILED_LEARNERS`."""
    cls = type(learner)
    return cls in COMPILED_LEARNERS or issubclass(cls, TabularLearner) and \
        cls.act is TabularLearner.act and cls.observe is TabularLearner.observe


def why_not_compiled(learner: Learner, env: gym.Env) -> str | None:
    """None when the compiled loop gives exactly what stepping ``env`` gives: ``env`` is a
    :class:`~gdq_pddl.envs.pddl_env.PDDLEnv` or :class:`~gdq_pddl.envs.office.CompactEnv`,
    bare or wrapped only in :data:`SAME_RESULTS_WRAPPERS`, and ``learner`` runs in the
    loop (:func:`compiled_learner`); otherwise the reason, in words."""
    base = env.unwrapped
    if type(base) not in (PDDLEnv, CompactEnv):
        return f"the env is a {type(base).__name__}, not a PDDLEnv or CompactEnv"
    if not compiled_learner(learner):
        return f"the learner is a {type(learner).__name__}, not a TabularLearner that " \
            "keeps its act and observe"
    while env is not base:
        if type(env) not in SAME_RESULTS_WRAPPERS or type(env) is TimeLimit and \
                env._max_episode_steps < base.model.step_limit:
            return f"the env is wrapped in {type(env).__name__}, which the compiled loop " \
                "would bypass"
        env = env.env
    return None


def run_episodes(learner: Learner, env: gym.Env, n_episodes: int,
                 rng: np.random.Generator, fast: bool | None = None) -> EpisodeRecords:
    """Run ``n_episodes`` episodes of ``learner`` in ``env`` (learning as it goes).

    ``fast=None`` picks the compiled loop where it gives the same results as stepping
    ``env`` (:func:`why_not_compiled`), else the Python loop, which calls ``env.reset``
    and ``env.step`` through every wrapper; ``True`` demands the compiled loop (a
    :class:`~gdq_pddl.errors.ConfigError` says why it cannot run), ``False`` forces the
    Python loop. Raises :class:`~gdq_pddl.errors.ConfigError` when ``rng`` is not a
    ``numpy.random.Generator`` or the learner's states and actions are not the env's, and
    :class:`~gdq_pddl.errors.ResultsError` when its task context is of another PDDL
    problem than the env's (same sizes) or of another instance explored online.

    A learner that runs its own episodes (a deep-RL agent, :mod:`gdq_pddl.learners.deep`:
    its ``run_own_episodes(env, n_episodes, rng)``) runs them so, with the same records.
    """
    own = getattr(learner, "run_own_episodes", None)
    if own is not None:
        check_count("n_episodes", n_episodes)
        guards.check_generator(rng)
        if fast:
            raise ConfigError(f"fast=True: the learner is a {type(learner).__name__}, "
                              "which runs its own episodes")
        return own(env, n_episodes, rng)
    return _run(learner, env, n_episodes, rng, fast, _n_areas(env))


def run_compact(learner: TabularLearner, env: CompactEnv, n_episodes: int,
                rng: np.random.Generator) -> EpisodeRecords:
    """:func:`run_episodes` in a :class:`~gdq_pddl.envs.office.CompactEnv` (seed ``env``
    with ``reset`` first), with at least one column of area visits."""
    if not isinstance(env.unwrapped, CompactEnv):
        raise ConfigError(f"run_compact needs a CompactEnv, got {type(env.unwrapped).__name__}")
    return _run(learner, env, n_episodes, rng, None, max(1, _n_areas(env)))


def evaluate_policy(env: gym.Env, policy: GreedyPolicy | TabularLearner, episodes: int = 100,
                    seed: int = 0) -> EpisodeRecords:
    """Run ``policy`` (a :class:`~gdq_pddl.learners.saving.GreedyPolicy`, or a learner's
    greedy policy now) for ``episodes`` episodes in ``env`` without learning, stepping
    it through its wrappers, after ``env.reset(seed=seed)``. The records' ``mean_return``
    and ``success_rate`` summarise them. Refused: ``episodes`` below 1
    (:class:`~gdq_pddl.errors.ConfigError`), and an env whose states are numbered otherwise
    than the policy's task (another problem, or another instance of a problem explored
    online: :class:`~gdq_pddl.errors.ResultsError` naming what differs)."""
    if isinstance(policy, TabularLearner):
        policy = GreedyPolicy.of(policy)
    if not isinstance(policy, GreedyPolicy):
        raise ConfigError(f"evaluate_policy takes a GreedyPolicy or a learner, got "
                          f"{type(policy).__name__}")
    check_count("episodes", episodes)
    if episodes < 1:
        raise ConfigError(f"evaluate_policy: episodes must be at least 1, got {episodes} (a "
                          "mean return over no episode is undefined)")
    guards.check_env(len(policy.actions), policy.n_actions, env)
    policy.check_env(env)
    check_count("seed", seed)
    env.reset(seed=seed)
    return _run(policy, env, episodes, np.random.default_rng(seed), False,  # type: ignore
                _n_areas(env))


def _run(learner: Learner, env: gym.Env, n_episodes: int, rng: np.random.Generator,
         fast: bool | None, n_areas: int) -> EpisodeRecords:
    check_count("n_episodes", n_episodes)
    guards.check_generator(rng)
    check_memory(n_episodes * (17 + 8 * n_areas), f"n_episodes = {n_episodes:,}: the "
                 "episode records", "run fewer episodes at a time")
    if isinstance(learner, TabularLearner):
        guards.check_env(len(learner.q), learner.context.n_env_actions, env)
        # another problem of the same size, or another instance explored online: refused
        check_identity("the learner", "learner", identity_of(learner.context),
                       identity_of(getattr(env.unwrapped, "instance", None)), "the env",
                       PROBLEM_KEYS)
    reason = why_not_compiled(learner, env)
    if fast and reason is not None:
        raise ConfigError(f"fast=True: {reason}")
    if fast is False or reason is not None:
        return _run_python(learner, env, n_episodes, rng, n_areas)
    base = env.unwrapped
    own = base._given  # every episode starts as reset() without options starts it
    if isinstance(base, CompactEnv):
        args = base.model, own.start_pos, own.goal_pos, base.doors
    else:
        args = base.model, int(own.start_state), int(own.goal_pos), _NO_DOORS
    return run_compiled(*args, learner, base.np_random, n_episodes, rng,  # type: ignore
                        n_areas)


def _run_python(learner: Learner, env: gym.Env, n_episodes: int,
                rng: np.random.Generator, n_areas: int) -> EpisodeRecords:
    online = isinstance(env.unwrapped, OnlineEnv) and isinstance(learner, TabularLearner)
    follow = Follower(learner, env.unwrapped.instance) if online else None
    if isinstance(learner, TabularLearner) and not online:
        learner.reserve_successors(successor_capacity(env.unwrapped.model))
    returns, steps, success, areas = _empty_records(n_episodes, n_areas)
    bar = _online_progress(env, n_episodes) if online else None
    for ep in range(n_episodes):
        if bar is not None:
            bar.update(ep - bar.n)
            bar.set_postfix(states=env.unwrapped.instance.graph.n_states, refresh=False)
        s, info = env.reset()
        done = success[ep] = info["cause"] == "goal"  # over before any action
        while not done:
            a = learner.act(s, rng)
            s2, r, terminated, truncated, info = env.step(a)
            if follow is not None:  # rows the step found, before the learner reads them
                follow()
            learner.observe(s, a, r, s2, terminated, truncated, rng)
            returns[ep] += r
            steps[ep] += 1
            if info["area"] > 0:
                areas[ep, info["area"] - 1] += 1
            if terminated and info["cause"] == "goal":
                success[ep] = True
            done = terminated or truncated
            s = s2
        if follow is not None:
            follow.episode_end()
    if bar is not None:
        bar.update(n_episodes - bar.n)
        bar.close()
    return EpisodeRecords(returns, steps, success, areas)


def _online_progress(env: gym.Env, n_episodes: int):
    """A run's episodes on a problem explored online, with the states found so far
    (:func:`~gdq_pddl.limits.slow_progress`: after 2 s, on a terminal), in the main
    process only (workers' bars would draw over each other); None in a worker."""
    if multiprocessing.parent_process() is not None:
        return None
    name = env.unwrapped.instance.name
    return slow_progress(f"{name} (online)", " episodes", n_episodes)


_NO_DOORS = np.zeros(1, dtype=np.uint8)  # a ModelArrays state carries its doors itself


def run_compiled(dynamics: ModelArrays | CompactModel, start: int, goal_pos: int,
                 doors: np.ndarray, learner: TabularLearner, env_rng: np.random.Generator,
                 n_episodes: int, rng: np.random.Generator, n_areas: int) -> EpisodeRecords:
    """The compiled loop over either kind of true dynamics: ``start`` is a full state of a
    :class:`ModelArrays` (``doors`` unused) or a position of a
    :class:`~gdq_pddl.envs.compact.CompactModel` (``doors``: its open-door array,
    cleared at the start of every episode); ``n_areas`` columns of area visits (at least
    the dynamics' areas)."""
    check_count("n_episodes", n_episodes)
    guards.check_generator(rng)
    guards.check_generator(env_rng, "the env's generator")
    n_s, n_a = learner.q.shape
    most = guards.check_dynamics(dynamics, start, doors, n_s, n_a, learner.context.columns)
    check_count("n_areas", n_areas)
    if n_areas < most:
        raise ConfigError(f"n_areas is {n_areas}, the env's dynamics have {most}")
    learner.reserve_successors(successor_capacity(dynamics))
    returns, steps, success, areas = _empty_records(n_episodes, n_areas)
    # GDQ's reverse index grows between episodes: the loop stops before an episode that
    # might not fit (one episode adds at most `room` entries) and is called again.
    room = reverse_room(learner.max_successors, int(dynamics.step_limit))
    reserve = getattr(learner, "reserve_reverse", None)
    ep = 0
    while ep < n_episodes:
        if reserve is not None:
            reserve(room)
        guards.check_tables(learner.tables, learner.params)
        ep = _loop_of(learner)(dynamics, start, goal_pos, doors, learner.tables,
                               learner.params, env_rng, rng, returns, steps, success, areas,
                               ep, room)
        if ep < 0:
            raise ValueError(OVERFLOW)
    return EpisodeRecords(returns, steps, success, areas)


def loop_cached(markers: Iterable[type]) -> bool:
    """Whether numba's on-disk cache holds the compiled episode loop of each rules class of
    ``markers`` (:meth:`TabularLearner.loop_marker
    <gdq_pddl.learners.tabular.TabularLearner.loop_marker>`; True where it cannot tell):
    False on a first use, when a run compiles before it starts."""
    try:
        return all(os.path.isfile(_cached_loop(m)._cache._cache_file._index_path)
                   for m in markers)
    except AttributeError:  # numba's internals moved: say nothing
        return True


def loops_cached(methods: Iterable[str]) -> bool:
    """:func:`loop_cached` for the learners of ``methods`` (``--method`` specs) that run in
    one of the package's cached loops (a deep-RL agent, or a learner of another package
    with rules of its own, runs none)."""
    markers = set()
    for method in methods:
        parsed = registry.parse_method(method)
        if parsed.entry.requires:  # a deep-RL agent: no loop (nor its extra imported here)
            continue
        cls = parsed.entry.learner_class()
        if isinstance(cls, type) and issubclass(cls, TabularLearner):
            marker = _cached_marker(cls, parsed.entry.config(**parsed.config_kwargs()))
            if marker is not None:
                markers.add(marker)
    return loop_cached(markers)


def _cached_marker(cls: type[TabularLearner], config) -> type | None:
    """The rules class whose cached loop runs a learner of ``cls`` with ``config``: one of
    this package's (:meth:`TabularLearner.loop_marker`), else None (its own rules: an
    uncached copy)."""
    marker = cls.loop_marker(config)
    return marker if marker is not None and \
        marker.__module__.startswith(__package__ + ".") else None


def _loop_of(learner: TabularLearner):
    """The compiled episode loop of ``learner``: :func:`_episodes` calling its rules. For a
    learner whose rules are this package's, the copy of its rules class
    (:meth:`TabularLearner.loop_marker`), cached by numba under the class's name; else a
    copy calling the learner's own ``act_rule`` and ``observe_rule``, compiled once per
    process and pair of rules, not cached (numba's cache keys a function by its code and
    argument types, not by the functions it calls, nor by another package's source)."""
    marker = _cached_marker(type(learner), learner.config)
    if marker is not None:
        return _cached_loop(marker)
    pair = (learner.act_rule, learner.observe_rule)
    if pair not in _PLUGIN_LOOPS:
        _PLUGIN_LOOPS[pair] = numba.njit(_loop_copy(*pair, "_plugin_episodes"))
    return _PLUGIN_LOOPS[pair]


_PLUGIN_LOOPS: dict[tuple, object] = {}
"""The episode loops of learners from other packages, by their pair of rules."""
_LOOPS: dict[type, object] = {}
"""The cached episode loops of this package's rules classes, by class."""


def _cached_loop(marker: type):
    """The loop of the rules class ``marker``: a copy of :func:`_episodes` whose ``act``
    and ``observe`` are the class's, named ``_episodes_<class>`` (numba's cache file and
    index are by name: one per rules class, holding one learner's code)."""
    if marker not in _LOOPS:
        name = f"_episodes_{marker.__module__.rpartition('.')[2]}_{marker.__name__}"
        _LOOPS[marker] = numba.njit(cache=True)(_loop_copy(marker.act, marker.observe, name))
    return _LOOPS[marker]


def _loop_copy(act, observe, name: str) -> types_.FunctionType:
    """:func:`_episodes` (its Python code) as a function ``name`` calling ``act`` and
    ``observe``."""
    code = _episodes.__code__.replace(co_name=name, co_qualname=name)
    scope = {**_episodes.__globals__, "act": act, "observe": observe}
    return types_.FunctionType(code, scope, name)


def compile_loop(learner: TabularLearner, env: PDDLEnv) -> None:
    """Compile (or load from numba's cache) the episode loop of ``learner`` with the
    argument types it has in ``env`` (the same for every learner on any ``ModelArrays``
    env); nothing runs."""
    base = env.unwrapped
    records = _empty_records(1, 1)
    args = (base.model, int(base._given.start_state), int(base._given.goal_pos), _NO_DOORS,
            learner.tables, learner.params, base.np_random, np.random.default_rng(0),
            *records, 0, 1)
    _loop_of(learner).compile(tuple(numba.typeof(x) for x in args))


# What the loop needs of a kind of dynamics, one overload per kind, picked by numba from
# the dynamics' type (inlined for speed: docs/learners.md): the hidden state an episode
# starts in, the learner state it shows, whether the goal holds there, one step, the area
# of a state.
def _restart(m, start, doors):
    raise NotImplementedError  # compiled code only (see the overloads below)


def _observe(m, state, doors):
    raise NotImplementedError


def _at_goal(m, state, goal_pos):
    raise NotImplementedError


def _step(m, state, doors, action, t, goal_pos, rng):
    raise NotImplementedError


def _area(m, state):
    raise NotImplementedError


def act(table, visits, prior, p, s, rng):
    raise NotImplementedError  # each copy of _episodes calls a learner's own (_loop_copy)


def observe(table, model, plans, prior, queue, own, p, s, a, r, s2, terminated, truncated,
            rng):
    raise NotImplementedError


def _kind(m) -> type | None:
    return m.instance_class if isinstance(m, types.BaseNamedTuple) else None


@overload(_restart, inline="always")
def _restart_impl(m, start, doors):
    if _kind(m) is ModelArrays:
        return lambda m, start, doors: start
    if _kind(m) is CompactModel:
        def restart(m, start, doors):
            doors[:] = 0
            return start
        return restart
    return None


@overload(_observe, inline="always")
def _observe_impl(m, state, doors):
    if _kind(m) is ModelArrays:
        return lambda m, state, doors: m.obs_of[state]
    if _kind(m) is CompactModel:
        return lambda m, state, doors: observe_state(m, state, doors)
    return None


@overload(_step, inline="always")
def _step_impl(m, state, doors, action, t, goal_pos, rng):
    if _kind(m) is ModelArrays:
        return lambda m, state, doors, action, t, goal_pos, rng: env_step(
            m, state, action, t, goal_pos, rng)
    if _kind(m) is CompactModel:
        return lambda m, state, doors, action, t, goal_pos, rng: compact_step(
            m, state, doors, action, t, goal_pos, rng)
    return None


@overload(_at_goal, inline="always")
def _at_goal_impl(m, state, goal_pos):
    if _kind(m) is ModelArrays:
        return lambda m, state, goal_pos: m.pos_of[state] == goal_pos
    if _kind(m) is CompactModel:
        return lambda m, state, goal_pos: state == goal_pos
    return None


@overload(_area, inline="always")
def _area_impl(m, state):
    if _kind(m) is ModelArrays:
        return lambda m, state: m.area_of_pos[m.pos_of[state]]
    if _kind(m) is CompactModel:
        return lambda m, state: m.area_of_pos[state]
    return None


def _episodes(m, start: int, goal_pos: int, doors: np.ndarray, t: Tables, p: Params,
              env_rng: np.random.Generator, rng: np.random.Generator, returns: np.ndarray,
              steps: np.ndarray, success: np.ndarray, areas: np.ndarray, first: int,
              room: int) -> int:
    """The compiled episode loop (same calls, in the same order, as the Python loop) from
    episode ``first``, over the env's true dynamics ``m``. Returns the number of episodes
    when all are done; -1 when the learner's model ran out of successor slots (the loop
    stops there); an episode index when GDQ's reverse index has less than ``room`` free
    entries before that episode (the caller grows it and calls again from there). Trusts
    its arguments: :func:`run_compiled` checks them. Not compiled itself: ``act`` and
    ``observe`` are a learner's rules, and each rules class
    (:data:`gdq_pddl.learners.rules.KIND_RULES`) runs a copy calling its own, compiled
    and cached for it alone (:func:`_loop_of`), as a learner from another package runs a
    copy calling its own."""
    table, model, plans, prior, queue, own = t
    for ep in range(first, len(returns)):
        if p.kind == KIND_GDQ and len(prior.rev_pair) - prior.rev_n[0] < room:
            return ep
        state = _restart(m, start, doors)
        if _at_goal(m, state, goal_pos):  # over before any action, as the env's reset says
            success[ep] = True
            continue
        s = _observe(m, state, doors)
        step = 0
        while True:
            a = act(table, model.visits, prior, p, s, rng)
            state, r, terminated, truncated, cause = _step(m, state, doors, a, step, goal_pos,
                                                           env_rng)
            s2 = _observe(m, state, doors)
            if not observe(table, model, plans, prior, queue, own, p, s, a, r, s2,
                           terminated, truncated, rng):
                return -1
            step += 1
            returns[ep] += r
            area = _area(m, state)
            if area > 0:
                areas[ep, area - 1] += 1
            if terminated or truncated:
                success[ep] = cause == CAUSE_GOAL
                break
            s = s2
        steps[ep] = step
    return len(returns)

