"""A reference value for worlds too large for V*: value iteration that forgets doors.

The :class:`~gdq_pddl.envs.compact.CompactModel` cannot say whether the door at an
outcome's next position is open: :func:`solve_compact` assumes the worse of the two
(:func:`next_states`) and otherwise runs :func:`~gdq_pddl.envs.solve.solve`'s
finite-horizon value iteration over ``(t, learner state)``. Its ``value`` is a lower
bound on V*, equal to it on the office and the small buildings (tested; why:
docs/decisions.md, "Generated buildings"), in time linear in the model's size.
"""

from __future__ import annotations

from dataclasses import dataclass

import numba
import numpy as np

from gdq_pddl.envs.compact import CompactModel, compile_compact
from gdq_pddl.envs.model import per_object
from gdq_pddl.envs.solve import TIE_TOLERANCE, expected_costs, resolve_world_task
from gdq_pddl.envs.step import ModelArrays
from gdq_pddl.limits import check_memory
from gdq_pddl.pddl.distances import distinct
from gdq_pddl.world_types import Task, World


@dataclass(frozen=True)
class CompactSolution:
    """Pessimistic values and policy of one (compact model, goal) pair (module docstring)."""

    V: np.ndarray  # float64[step_limit + 1, n_states]
    policy: np.ndarray  # int64[step_limit, n_states]
    value: float  # V[0, learner state of the start with its door closed]
    goal_pos: int


def next_states(model: CompactModel) -> tuple[np.ndarray, np.ndarray]:
    """The pessimistic next learner states of every outcome, ``(closed, other)``: the next
    position's closed and open states, or twice the known one where the robot stayed at,
    or went through, the door it acted at (an outcome is worth the smaller value)."""
    n_states = model.pos_of_state.shape[0]
    counts = np.diff(model.ptr)
    state = np.repeat(np.arange(n_states * model.n_actions) // model.n_actions, counts)
    pos = model.pos_of_state[state]
    door = model.door_of_pos[pos]
    was_open = (door >= 0) & (state == model.state_of[pos, 1])
    nxt = model.next_pos
    known = (door >= 0) & (model.door_of_pos[nxt] == door)
    closed = model.state_of[nxt, (known & (was_open | model.opens)).astype(np.int64)]
    return closed, np.where(known, closed, model.state_of[nxt, 1])


def successor_capacity(model: ModelArrays | CompactModel) -> int:
    """The most distinct next learner states of one (learner state, action) pair, at least
    1 (a bound for a :class:`CompactModel`): what the learners size successor slots by."""
    return per_object(model.ptr, "capacity", lambda: _capacity(model))


def _capacity(model: ModelArrays | CompactModel) -> int:
    if isinstance(model, ModelArrays) and np.array_equal(model.obs_of,
                                                         np.arange(len(model.obs_of))):
        n_states = len(model.obs_of)  # seen as it is: one outcome, one successor, so only
        counts = np.diff(model.ptr)  # the pairs of several outcomes count (and are made)
        several = np.flatnonzero(counts > 1)
        counts = counts[several]
        at = np.repeat(model.ptr[several] - np.cumsum(counts) + counts, counts) + \
            np.arange(counts.sum())
        keys = np.repeat(several, counts) * n_states + model.next[at]
        return _most(keys, n_states)
    pair = np.repeat(np.arange(len(model.ptr) - 1, dtype=np.int64), np.diff(model.ptr))
    if isinstance(model, CompactModel):
        n_states = len(model.pos_of_state)
        first, second = next_states(model)  # the two door states an outcome may show
        keys = np.concatenate([pair * n_states + first, pair * n_states + second])
    else:
        n_states = int(model.obs_of.max()) + 1
        learner_pair = model.obs_of[pair // model.n_actions] * model.n_actions + \
            pair % model.n_actions
        keys = learner_pair * n_states + model.obs_of[model.next]
    return _most(keys, n_states)


def _most(keys: np.ndarray, n_states: int) -> int:
    per_pair = np.bincount(distinct(keys) // n_states) if len(keys) else np.zeros(1)
    return max(1, int(per_pair.max()))


def _stay_actions(model: CompactModel, cost: np.ndarray) -> tuple[np.ndarray, ...]:
    """Per learner state: the first pair without outcomes, the first of least mean cost
    among them and that cost (-1, -1, inf where every action lists outcomes)."""
    n_states, n_actions = model.pos_of_state.shape[0], model.n_actions
    free = (np.diff(model.ptr) == 0).reshape(n_states, n_actions)
    by_cost = np.lexsort((np.arange(n_actions), cost))  # cost, then index
    some = free.any(axis=1)
    first = np.where(some, free.argmax(axis=1), -1)
    cheapest = np.where(some, by_cost[free[:, by_cost].argmax(axis=1)], -1)
    stay_cost = np.where(cheapest >= 0, cost[np.maximum(cheapest, 0)], np.inf)
    return first, cheapest, stay_cost


@numba.njit(cache=True)
def _value_iteration(ptr: np.ndarray, prob: np.ndarray, closed: np.ndarray,
                     other: np.ndarray, ending: np.ndarray, end_reward: np.ndarray,
                     app_ptr: np.ndarray, app_action: np.ndarray, cost: np.ndarray,
                     first_stay: np.ndarray, cheapest_stay: np.ndarray, stay_cost: np.ndarray,
                     at_goal: np.ndarray, r_max: float, tol: float, V: np.ndarray,
                     policy: np.ndarray) -> None:
    """Fill ``V[:-1]`` and ``policy`` backwards in time (``V[-1]`` is 0)."""
    limit, n_states = policy.shape
    n_actions = cost.shape[0]
    q = np.empty(max(1, np.max(np.diff(app_ptr))))
    for t in range(limit - 1, -1, -1):
        last = t == limit - 1
        for s in range(n_states):
            # The pairs without outcomes: stay at s (at the goal: the episode ends there).
            stay_a, stay_q = -1, -np.inf
            if first_stay[s] >= 0:
                if at_goal[s] or last:
                    stay_a, stay_q = first_stay[s], r_max if at_goal[s] else -r_max
                else:
                    stay_a = cheapest_stay[s]
                    stay_q = -stay_cost[s] + V[t + 1, s]
            best = stay_q
            lo, hi = app_ptr[s], app_ptr[s + 1]
            for j in range(lo, hi):
                a = app_action[j]
                i = s * n_actions + a
                total = 0.0
                for k in range(ptr[i], ptr[i + 1]):
                    if last or ending[k]:
                        total += prob[k] * end_reward[k]
                    else:
                        after = min(V[t + 1, closed[k]], V[t + 1, other[k]])
                        total += prob[k] * (-cost[a] + after)
                q[j - lo] = total
                best = max(best, total)
            choice = stay_a if stay_a >= 0 and stay_q >= best - tol else n_actions
            for j in range(lo, hi):
                if q[j - lo] >= best - tol and app_action[j] < choice:
                    choice = app_action[j]
            policy[t, s] = choice
            V[t, s] = 0.0 if at_goal[s] else best


def solve_compact(model: CompactModel, start_pos: int, goal_pos: int) -> CompactSolution:
    """Pessimistic undiscounted values and time-dependent greedy policy (``policy[t, s]``:
    the action in learner state ``s`` after ``t`` actions) for reaching ``goal_pos``;
    ``value`` is ``V[0]`` at ``start_pos`` with its door closed."""
    n_states, n_actions, limit = model.pos_of_state.shape[0], model.n_actions, model.step_limit
    check_memory((limit + 1) * n_states * 16,
                 f"step_limit = {limit}: the reference value ({n_states} states at each of "
                 f"the {limit} steps)", "use a smaller step_limit")
    cost = expected_costs(model)  # reads only cost_kind, cost_a and cost_b
    first_stay, cheapest_stay, stay_cost = _stay_actions(model, cost)
    pairs = np.flatnonzero(np.diff(model.ptr) > 0)
    app_ptr = np.searchsorted(pairs // n_actions, np.arange(n_states + 1)).astype(np.int64)
    at_goal_next = model.next_pos == goal_pos
    ending = model.stuck | at_goal_next
    r = model.r_max
    end_reward = np.where(model.stuck, -r, np.where(at_goal_next, r, -r))
    V = np.zeros((limit + 1, n_states))
    policy = np.empty((limit, n_states), dtype=np.int64)
    _value_iteration(model.ptr, model.prob, *next_states(model), ending, end_reward, app_ptr,
                     (pairs % n_actions).astype(np.int64), cost, first_stay, cheapest_stay,
                     stay_cost, model.pos_of_state == goal_pos, float(r), TIE_TOLERANCE,
                     V, policy)
    start = int(model.state_of[start_pos, 0])
    return CompactSolution(V=V, policy=policy, value=float(V[0, start]),
                           goal_pos=int(goal_pos))


def solve_compact_task(world: World, task: Task | str,
                       model: CompactModel | None = None) -> CompactSolution:
    """:func:`solve_compact` for ``task`` in ``world`` (compiling the model if not given)."""
    t = resolve_world_task(world, task)
    model = compile_compact(world) if model is None else model
    return solve_compact(model, world.index[t.start], world.index[t.goal])


def reference_value(world: World, task: Task | str) -> float:
    """The pessimistic value of ``task`` from its start: a lower bound on V* for worlds of
    any number of doors."""
    return solve_compact_task(world, task).value
