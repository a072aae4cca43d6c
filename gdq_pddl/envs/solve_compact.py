"""A reference value for worlds too large for V*: value iteration that forgets doors.

:func:`gdq_pddl.envs.solve.solve` needs the full state (position, set of open doors):
``2**n_doors`` door masks, out of reach for a generated building with 100+ doors. The
:class:`~gdq_pddl.envs.compact.CompactModel` lists outcomes per *learner* state
(position, is the door at this position open), which is all an action's outcomes depend
on; what it cannot say is whether the door at the position an outcome leads to is open,
since that depends on which doors the episode opened before. :func:`solve_compact`
forgets them and assumes the worst. After an outcome the next learner state is

- where the robot stayed (a failed action, a no-op): the same door state, except that a
  successful ``opendoor`` leaves its door open;
- after a successful ``gothrough`` (only possible through an open door): the other side
  of that door, open;
- anywhere else (``goto``, ``approach``, a navigation slip): whichever of "door closed"
  and "door open" is worth less at the next step. On the office and the generated
  buildings (unit costs) that is always "closed" (:func:`open_door_deficit` is 0, tested),
  so there this is the model of a robot whose doors close behind it.

On it runs the finite-horizon value iteration of :func:`~gdq_pddl.envs.solve.solve` over
``(t, learner state)`` with the same conventions: undiscounted by default,
``V[step_limit, :] = 0``, states at the goal worth 0, a stuck outcome -r_max, reaching
the goal +r_max, any other outcome of the last allowed action -r_max (timeout),
otherwise minus the mean cost of the action (:func:`~gdq_pddl.envs.solve.expected_costs`);
greedy actions, ties to the lowest index. A pair that lists no outcome (most of the
``5 * n_positions`` actions) leaves the robot where it is at the action's cost, so they
are handled once per state: only the cheapest matters. Time is linear in ``step_limit``
x (learner states + listed outcomes): 0.3 s for a 1000-position building.

Why ``value`` (``V[0]`` at the start, door closed, as every episode starts) is a lower
bound on V*: follow ``policy[t, observed learner state]`` in reality, a policy of the
full model, so worth at most V*. From any full state at step ``t`` it expects at least
``V[t, observed learner state]``, by induction down from ``t = step_limit`` (both 0):
the action's outcome probabilities and rewards depend only on the observed learner
state, so they are the same in both models; after an outcome, the real next learner
state is the one above where that is known (stayed, went through) and one of the two
door states otherwise, worth at least the smaller of their values. Where the smaller
is always "closed", the value is that of doors closing behind the robot, exact for
policies that never come back to a door side they opened. The office's optimal policies
never do (a robot that opened a door goes through it at once, and a failed
``gothrough`` leaves it at the open door): the value equals V* to 1e-9 on its five
tasks, and on the small generated buildings whose V* can be computed (tested).

Why not simply "closed": a door side is not always worth more open. When time has run
out, getting stuck (-r_max, nothing more to pay) beats waiting for the timeout, and if
``opendoor`` costs less than ``gothrough`` a closed door is the cheaper way to try; then
"always closed" can over-estimate V* (by 0.036 on a three-door corridor with opendoor
cost 0.97 and gothrough cost 1.78, task ``z0 -> z2``, step limit 9).
"""

from __future__ import annotations

from dataclasses import dataclass

import numba
import numpy as np

from gdq_pddl.envs.compact import CompactModel, compile_compact
from gdq_pddl.envs.model import ModelArrays, per_object
from gdq_pddl.envs.solve import TIE_TOLERANCE, _task, expected_costs
from gdq_pddl.limits import check_memory
from gdq_pddl.pddl.reachable import distinct
from gdq_pddl.world import Task, World


@dataclass(frozen=True)
class CompactSolution:
    """Pessimistic values and policy of one (compact model, goal) pair (module docstring)."""

    V: np.ndarray  # float64[step_limit + 1, n_states]
    policy: np.ndarray  # int64[step_limit, n_states]
    value: float  # V[0, learner state of the start with its door closed]
    start_pos: int
    goal_pos: int
    gamma: float


def next_states(model: CompactModel) -> tuple[np.ndarray, np.ndarray]:
    """The pessimistic next learner states of every outcome: ``(closed, other)``, both
    ``int64[n_outcomes]``, the value of an outcome being the smaller of theirs.

    The door state at the next position is known if it is the door of the position the
    action was taken at (the robot stayed there, or went through it): open if that door
    was open or the action opened it, and then ``other == closed``; otherwise ``closed``
    is the next position with its door closed and ``other`` with it open (the same state
    where there is no door).
    """
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
    """The most distinct next learner states of one (learner state, action) pair in a
    true model, at least 1: a :class:`~gdq_pddl.envs.model.ModelArrays` (exact: the
    union over the full states a learner state stands for) or a :class:`CompactModel`
    (an upper bound: an outcome whose next position has a door other than the one acted
    at may show it open or closed, :func:`next_states`; a pair with no outcome stays
    put). What the learners size their successor slots by; cached per model."""
    return per_object(model.ptr, "capacity", lambda: _capacity(model))


def _capacity(model: ModelArrays | CompactModel) -> int:
    n_pairs = len(model.ptr) - 1
    pair = np.repeat(np.arange(n_pairs, dtype=np.int64), np.diff(model.ptr))
    if isinstance(model, CompactModel):
        n_states = len(model.pos_of_state)
        first, second = next_states(model)  # the two door states an outcome may show
        keys = np.concatenate([pair * n_states + first, pair * n_states + second])
    else:
        n_states = int(model.obs_of.max()) + 1
        learner_pair = model.obs_of[pair // model.n_actions] * model.n_actions + \
            pair % model.n_actions
        keys = learner_pair * n_states + model.obs_of[model.next]
        if np.array_equal(model.obs_of, np.arange(len(model.obs_of))):  # seen as it is:
            keys = keys[(np.diff(model.ptr) > 1)[pair]]  # one outcome, one successor
    per_pair = np.bincount(distinct(keys) // n_states) if len(keys) else np.zeros(1)
    return max(1, int(per_pair.max()))


def _stay_actions(model: CompactModel, cost: np.ndarray) -> tuple[np.ndarray, ...]:
    """Per learner state: the lowest-index pair without outcomes (``first``), the
    lowest-index one of least mean cost (``cheapest``) and that cost; -1 / inf where
    every action lists outcomes."""
    n_states, n_actions = model.pos_of_state.shape[0], model.n_actions
    listed = (np.diff(model.ptr) > 0).reshape(n_states, n_actions)
    by_cost = np.lexsort((np.arange(n_actions), cost))  # cost, then index
    first = np.full(n_states, -1, dtype=np.int64)
    cheapest = np.full(n_states, -1, dtype=np.int64)
    for s in range(n_states):
        free = np.flatnonzero(~listed[s])
        if free.size:
            first[s] = free[0]
            cheapest[s] = by_cost[np.argmax(~listed[s][by_cost])]
    stay_cost = np.where(cheapest >= 0, cost[np.maximum(cheapest, 0)], np.inf)
    return first, cheapest, stay_cost


@numba.njit(cache=True)
def _value_iteration(ptr: np.ndarray, prob: np.ndarray, closed: np.ndarray,
                     other: np.ndarray, ending: np.ndarray, end_reward: np.ndarray,
                     app_ptr: np.ndarray, app_action: np.ndarray, cost: np.ndarray,
                     first_stay: np.ndarray, cheapest_stay: np.ndarray, stay_cost: np.ndarray,
                     at_goal: np.ndarray, r_max: float, gamma: float, tol: float, V: np.ndarray,
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
                    stay_q = -stay_cost[s] + gamma * V[t + 1, s]
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
                        total += prob[k] * (-cost[a] + gamma * after)
                q[j - lo] = total
                best = max(best, total)
            choice = stay_a if stay_a >= 0 and stay_q >= best - tol else n_actions
            for j in range(lo, hi):
                if q[j - lo] >= best - tol and app_action[j] < choice:
                    choice = app_action[j]
            policy[t, s] = choice
            V[t, s] = 0.0 if at_goal[s] else best


def solve_compact(model: CompactModel, start_pos: int, goal_pos: int,
                  gamma: float = 1.0) -> CompactSolution:
    """Pessimistic values and time-dependent greedy policy for reaching ``goal_pos``.

    ``policy[t, s]`` is the action to take in learner state ``s`` after ``t`` actions;
    ``value`` is ``V[0]`` at ``start_pos`` with its door closed. Time is linear in
    ``step_limit`` x (learner states + listed outcomes); see the module docstring.
    """
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
                     stay_cost, model.pos_of_state == goal_pos, float(r), float(gamma),
                     TIE_TOLERANCE, V, policy)
    start = int(model.state_of[start_pos, 0])
    return CompactSolution(V=V, policy=policy, value=float(V[0, start]),
                           start_pos=int(start_pos), goal_pos=int(goal_pos),
                           gamma=float(gamma))


def open_door_deficit(model: CompactModel, solution: CompactSolution) -> float:
    """How much more any door side is ever worth closed than open:
    ``max(V[t, (p, closed)] - V[t, (p, open)])`` over steps and door sides, or 0.

    At most 0 (or ``TIE_TOLERANCE``, for rounding): "the smaller of the two" was always
    "closed", so ``solution`` is that of the doors-close-behind model (module docstring).
    """
    sides = np.flatnonzero(model.door_of_pos >= 0)
    if sides.size == 0:
        return 0.0
    closed, opened = model.state_of[sides, 0], model.state_of[sides, 1]
    return float(np.max(solution.V[:, closed] - solution.V[:, opened]))


def solve_compact_task(world: World, task: Task | str,
                       model: CompactModel | None = None) -> CompactSolution:
    """:func:`solve_compact` for ``task`` in ``world`` (compiling the model if not given)."""
    t = _task(world, task)
    model = compile_compact(world) if model is None else model
    return solve_compact(model, world.index[t.start], world.index[t.goal])


def reference_value(world: World, task: Task | str) -> float:
    """The pessimistic value of ``task`` from its start, doors closed, step 0: a lower
    bound on V* (see the module docstring) for worlds of any number of doors."""
    return solve_compact_task(world, task).value
