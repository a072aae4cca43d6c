"""The compiled true model of a world as the env steps it: its flat arrays
(:class:`ModelArrays`) and one compiled step (:func:`env_step`, :func:`env_act`).

The simulator's hidden state is the *full* state ``(position, which doors are open)``,
indexed ``position * 2**n_doors + door_mask``. For every (full state, offered action)
pair the model lists its outcomes (probability, next full state, stuck flag) in CSR form:
outcomes of pair ``i = full_state * width + column`` are ``ptr[i]:ptr[i+1]``. A PDDL
problem offers in each state its applicable ground actions (``acts``, the state graph's
``offered`` rows: column ``j`` of state ``fs`` is ground action ``acts[fs, j]``, -1 pads
a row to ``width``); the office offers every learner action everywhere (``acts`` empty:
column ``j`` is action ``j``, ``width = n_actions``).

The arrays are built by :func:`gdq_pddl.envs.model.compile_true_model`; the gymnasium
env and the fast episode runner both step them with :func:`env_step`, so there is
exactly one definition of a step (value iteration mirrors it outcome by outcome).
"""

from __future__ import annotations

from typing import NamedTuple

import numba
import numpy as np

CAUSE_NONE, CAUSE_STUCK, CAUSE_GOAL, CAUSE_TIMEOUT = 0, 1, 2, 3
CAUSES = ("", "stuck", "goal", "timeout")
"""Why an episode ended, indexed by the cause code :func:`env_step` returns."""


class ModelArrays(NamedTuple):
    """The compiled true model (see the module docstring for the layout)."""

    n_actions: int
    n_doors: int
    r_max: float
    step_limit: int
    ptr: np.ndarray  # int64[n_full * n_actions + 1]
    prob: np.ndarray  # float64[n_outcomes]
    next: np.ndarray  # int64[n_outcomes], full state
    stuck: np.ndarray  # bool[n_outcomes]
    cost_kind: np.ndarray  # int64[n_actions], codes of COST_KINDS
    cost_a: np.ndarray  # float64[n_actions]
    cost_b: np.ndarray  # float64[n_actions]
    obs_of: np.ndarray  # int64[n_full], learner state of a full state
    pos_of: np.ndarray  # int64[n_full], position index of a full state
    area_of_pos: np.ndarray  # int64[n_positions], area number (0: none)
    gain: np.ndarray = np.zeros(0)  # float64[n_outcomes]: the outcomes' rewards
    """What each outcome earns besides the action's cost: the rewards of a PPDDL file's
    effects, less its costs inside ``when``, ``forall`` or ``probabilistic``
    (:meth:`~gdq_pddl.pddl.grounding.GroundOutcome.gain`). Empty: none earns anything
    (on the goal scale only)."""
    acts: np.ndarray = np.zeros((0, 0), dtype=np.int64)  # int64[n_full, width]
    """The action of each column (module docstring); empty: every action, column = action."""
    own_scale: bool = False
    """The problem's own rewards, as the IPPC scores them (:func:`file_step`): each
    outcome's :attr:`gain` less the action's cost, and ``r_max`` once on reaching the goal;
    no penalty for a stuck or late end. False: the goal scale (:func:`finish_step`)."""


def width_of(model: ModelArrays | tuple) -> int:
    """Columns a state's row has in ``model`` (a :class:`ModelArrays`, or a compact model,
    which has no ``acts``): ``acts``' width, or every action when ``acts`` is empty."""
    acts = getattr(model, "acts", None)
    return int(acts.shape[1]) if acts is not None and acts.shape[0] else int(model.n_actions)


def pair_of(model: ModelArrays, fs: int, action: int) -> int | None:
    """The pair index of ``action`` in full state ``fs`` (its outcomes are
    ``ptr[i]:ptr[i + 1]``), or None where ``fs`` does not offer it."""
    if not model.acts.shape[0]:
        return fs * model.n_actions + action
    hits = np.flatnonzero(model.acts[fs] == action)
    return int(fs * model.acts.shape[1] + hits[0]) if len(hits) else None


@numba.njit(cache=True)
def sample_cost(kind: int, a: float, b: float, rng: np.random.Generator) -> float:
    """Draw one action cost (no draw at all for a constant)."""
    if kind == 0:
        return a
    if kind == 1:
        return a + (b - a) * rng.random()
    return max(0.0, a + b * rng.standard_normal())


@numba.njit(cache=True, inline="always")
def draw_outcome(ptr: np.ndarray, prob: np.ndarray, i: int, rng: np.random.Generator) -> int:
    """Draw one uniform and return the index of the outcome of pair ``i`` it selects from
    the CSR arrays ``ptr``/``prob`` (-1 if the pair lists no outcome).

    The one outcome draw of both model kinds (:func:`env_step`,
    :func:`gdq_pddl.envs.compact.compact_step`).
    """
    k, end = ptr[i], ptr[i + 1]
    u = rng.random()
    if end == k:
        return -1
    acc = prob[k]
    while u >= acc and k < end - 1:
        k += 1
        acc += prob[k]
    return k


@numba.njit(cache=True, inline="always")
def finish_step(m, action: int, nxt: int, stuck: bool, at_goal: bool, t: int,
                rng: np.random.Generator, gain: float = 0.0
                ) -> tuple[int, float, bool, bool, int]:
    """Draw the cost of ``action`` and return ``(nxt, reward, terminated, truncated, cause)``
    for a step that led to ``nxt``: the reward and episode-end rule of the goal scale, of
    both model kinds (``m``: :class:`ModelArrays` or
    :class:`~gdq_pddl.envs.compact.CompactModel`): the outcome's ``gain`` less the cost
    (``-(cost - gain)``: exactly ``-cost`` where the gain is 0), or ``r_max`` at the goal
    and ``-r_max`` on a failed trial or the last allowed step instead."""
    cost = sample_cost(m.cost_kind[action], m.cost_a[action], m.cost_b[action], rng)
    if stuck:
        return nxt, -m.r_max, True, False, CAUSE_STUCK
    if at_goal:
        return nxt, m.r_max, True, False, CAUSE_GOAL
    if t + 1 >= m.step_limit:
        return nxt, -m.r_max, False, True, CAUSE_TIMEOUT
    return nxt, -(cost - gain), False, False, CAUSE_NONE


@numba.njit(cache=True, inline="always")
def env_step(m: ModelArrays, fs: int, column: int, t: int, goal_pos: int,
             rng: np.random.Generator) -> tuple[int, float, bool, bool, int]:
    """Take the action of ``column`` (module docstring) in full state ``fs`` at step
    ``t`` (0-based) of an episode.

    Returns ``(next full state, reward, terminated, truncated, cause)``. Draws exactly
    one uniform for the outcome, then one cost draw if the cost is not constant.
    """
    if m.acts.shape[0]:
        action = m.acts[fs, column]
        k = draw_outcome(m.ptr, m.prob, fs * m.acts.shape[1] + column, rng)
    else:
        action = column
        k = draw_outcome(m.ptr, m.prob, fs * m.n_actions + column, rng)  # never -1 here
    nxt = m.next[k]
    gain = m.gain[k] if m.gain.shape[0] else 0.0
    if m.own_scale:
        return file_step(m, action, gain, nxt, m.stuck[k], m.pos_of[nxt] == goal_pos, t, rng)
    return finish_step(m, action, nxt, m.stuck[k], m.pos_of[nxt] == goal_pos, t, rng, gain)


@numba.njit(cache=True)
def env_act(m: ModelArrays, fs: int, action: int, t: int, goal_pos: int,
            rng: np.random.Generator) -> tuple[int, float, bool, bool, int]:
    """:func:`env_step` of an action: its column in ``fs``, or, where ``fs`` does not
    offer it (its preconditions fail), a step that changes nothing at the action's cost
    (one uniform drawn for the outcome all the same)."""
    if not m.acts.shape[0]:
        return env_step(m, fs, action, t, goal_pos, rng)
    for j in range(m.acts.shape[1]):
        if m.acts[fs, j] == action:
            return env_step(m, fs, j, t, goal_pos, rng)
    rng.random()
    if m.own_scale:
        return file_step(m, action, 0.0, fs, False, False, t, rng)
    return finish_step(m, action, fs, False, False, t, rng, 0.0)


@numba.njit(cache=True, inline="always")
def file_step(m: ModelArrays, action: int, gain: float, nxt: int, stuck: bool, at_goal: bool,
              t: int, rng: np.random.Generator) -> tuple[int, float, bool, bool, int]:
    """:func:`finish_step` on the problem's own scale: the outcome's ``gain``
    (:attr:`ModelArrays.gain`) less the action's cost."""
    reward = gain - sample_cost(m.cost_kind[action], m.cost_a[action], m.cost_b[action], rng)
    if stuck:
        return nxt, reward, True, False, CAUSE_STUCK
    if at_goal:
        return nxt, reward + m.r_max, True, False, CAUSE_GOAL
    return nxt, reward, False, t + 1 >= m.step_limit, \
        CAUSE_TIMEOUT if t + 1 >= m.step_limit else CAUSE_NONE
