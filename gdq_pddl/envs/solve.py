"""Ground truth: finite-horizon value iteration on the true model of a world.

An episode lasts at most ``step_limit`` actions and running out of them is a failure
(-r_max), so the optimal policy depends on the step counter as well as on the full state
(position, which doors are open). :func:`solve` computes, for ``t = 0 .. step_limit``,

- ``V[t, fs]``: the optimal expected return from full state ``fs`` with ``t`` actions
  already taken (``V[step_limit, :] = 0``; states at the goal are worth 0: the episode
  is over);
- ``Q[t, fs, a]`` and ``policy[t, fs]`` (greedy action, ties to the lowest index);
- ``goal[fs]``: the probability that this policy reaches the goal within the step limit
  from ``fs`` at step 0 (what V* means in probabilities: :func:`goal_chances` adds the
  most any policy has within the limit and with none, :mod:`gdq_pddl.envs.goal_chance`).

Expected rewards mirror :func:`gdq_pddl.envs.step.env_step` outcome by outcome: a stuck
outcome gives -r_max and ends the episode; reaching the goal gives +r_max and ends it;
any other outcome of the last allowed action gives -r_max; otherwise the reward is the
outcome's gain (:attr:`~gdq_pddl.envs.step.ModelArrays.gain`: a PPDDL file's rewards and
costs inside its effects) minus the mean cost of the action (for a normal cost, the mean
of the draw clipped at 0). On the problem's own scale
(:attr:`~gdq_pddl.envs.step.ModelArrays.own_scale`), every outcome pays its gain minus
the cost, and reaching the goal adds r_max once. Returns are
undiscounted by default (``gamma=1``), i.e. the expected cumulative reward
per episode that the experiments report.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np
from scipy.sparse import csr_matrix
from scipy.sparse.csgraph import shortest_path
from scipy.special import ndtr  # the normal CDF (scipy.stats costs 0.6 s of import)

from gdq_pddl.dynamics import COST_KINDS
from gdq_pddl.envs.goal_chance import best_within_limit, best_without_limit
from gdq_pddl.envs.model import compile_model, full_state
from gdq_pddl.envs.step import ModelArrays, width_of
from gdq_pddl.limits import check_memory, human_bytes, slow_progress
from gdq_pddl.world_types import Task, World

TIE_TOLERANCE = 1e-9
"""Actions whose value is within this of the best count as tied (lowest index wins)."""


@dataclass(frozen=True)
class Solution:
    """Optimal values and policy of one (model, goal) pair; see the module docstring."""

    V: np.ndarray  # float64[step_limit + 1, n_full]
    Q: np.ndarray  # float64[step_limit, n_full, n_actions]
    policy: np.ndarray  # int64[step_limit, n_full]
    goal_pos: int
    gamma: float
    goal: np.ndarray = field(default_factory=lambda: np.zeros(0))
    """float64[n_full]: the probability that the policy (``policy``, ties to the lowest
    index) reaches the goal within the step limit from each full state at step 0."""


def expected_costs(model: ModelArrays) -> np.ndarray:
    """Mean cost of every action (``float64[n_actions]``), as
    :func:`~gdq_pddl.envs.step.sample_cost` draws it."""
    kind, a, b = model.cost_kind, model.cost_a, model.cost_b
    out = a.astype(np.float64).copy()
    uniform = kind == COST_KINDS["uniform"]
    out[uniform] = (a[uniform] + b[uniform]) / 2
    normal = kind == COST_KINDS["normal"]
    mu, sd = a[normal], b[normal]
    with np.errstate(divide="ignore", invalid="ignore"):
        z = np.where(sd > 0, mu / np.where(sd > 0, sd, 1.0), 0.0)
        pdf = np.exp(-z**2 / 2.0) / np.sqrt(2 * np.pi)
        clipped = mu * ndtr(z) + sd * pdf  # E[max(0, X)], X ~ N(mu, sd^2)
    out[normal] = np.where(sd > 0, clipped, np.maximum(mu, 0.0))
    return out


def solve_bytes(model: ModelArrays, tables: bool = True) -> int:
    """Memory :func:`solve` needs at most: per outcome and per pair its work arrays, per
    step V (and, with ``tables``, Q and the policy)."""
    n_full, limit = model.obs_of.shape[0], model.step_limit
    per_step = n_full * ((width_of(model) + 2) if tables else 1) * 8
    return (limit + 1) * per_step + len(model.prob) * 8 * 6 + (len(model.ptr) - 1) * 8 * 3


def check_solvable(model: ModelArrays, where: str = "") -> None:
    """Raise :class:`~gdq_pddl.errors.SizeError` if :func:`solve` on ``model`` would need
    more memory than the machine has. ``where`` names the step limit's file and key (the
    message says ``step_limit = N`` otherwise)."""
    n_full, limit = model.obs_of.shape[0], model.step_limit
    check_memory(solve_bytes(model),
                 f"{where or 'step_limit'} = {limit}: V* by value iteration ({n_full} states x "
                 f"{width_of(model)} actions at each of the {limit} "
                 "steps)",
                 "use a smaller step_limit")


def solve(model: ModelArrays, goal_pos: int, gamma: float = 1.0,
          tables: bool = True) -> Solution:
    """Optimal values and time-dependent greedy policy for reaching position ``goal_pos``
    (``tables=False``: the values only; ``Q`` and ``policy`` are then empty). ``Q`` and
    ``policy`` are over the model's columns (an action where ``model.acts`` is empty).

    Raises :class:`~gdq_pddl.errors.SizeError` up front when the tables (``Q`` is
    ``step_limit x states x columns``) would not fit in memory."""
    if tables:
        check_solvable(model)
    width, limit, r = width_of(model), model.step_limit, model.r_max
    n_full = model.obs_of.shape[0]
    counts = np.diff(model.ptr)
    live = counts > 0 if model.acts.shape[0] else np.ones(len(counts), dtype=np.bool_)
    if np.any(counts[live] == 0) or not live.reshape(n_full, width).any(axis=1).all():
        raise ValueError("every (full state, action) pair needs at least one outcome")
    starts = model.ptr[:-1][live]
    pair = np.repeat(np.arange(n_full * width), counts)
    action = model.acts.ravel()[pair] if model.acts.shape[0] else pair % width
    cost = expected_costs(model)[action]
    del pair, action
    at_goal = model.pos_of[model.next] == goal_pos
    # Reward of ending outcomes (stuck, goal), and of the rest on the last allowed step.
    ending = model.stuck | at_goal
    end_reward = np.where(model.stuck, -r, np.where(at_goal, r, -r))
    if model.gain.size:  # what each outcome earns besides the action's cost
        cost = cost - model.gain
    if model.own_scale:  # the problem's own rewards (step.file_step): no penalty
        end_reward = -cost + np.where(at_goal & ~model.stuck, r, 0.0)
    goal_states = model.pos_of == goal_pos
    reached = (at_goal & ~model.stuck).astype(np.float64)  # the goal, by this outcome
    goal = np.zeros(n_full)  # the policy's goal probability from step t + 1 on

    V = np.zeros((limit + 1, n_full))
    Q = np.empty((limit if tables else 0, n_full, width))
    q = np.full(n_full * width, -np.inf)  # a padding column is never the best
    policy = np.empty((limit if tables else 0, n_full), dtype=np.int64)
    for t in slow_progress("value iteration", " steps", limit, range(limit - 1, -1, -1)):
        if t == limit - 1:
            value = end_reward
        else:
            value = np.where(ending, end_reward, -cost + gamma * V[t + 1, model.next])
        q[live] = np.add.reduceat(model.prob * value, starts)
        by_state = q.reshape(n_full, width)
        best = by_state.max(axis=1)
        choice = np.argmax(by_state >= best[:, None] - TIE_TOLERANCE, axis=1)
        if tables:
            Q[t] = by_state
            policy[t] = choice
        V[t] = np.where(goal_states, 0.0, best)
        goal = _chosen_goal(model, choice, width, reached,
                            None if t == limit - 1 else goal, goal_states)
    return Solution(V=V, Q=Q, policy=policy, goal_pos=int(goal_pos), gamma=float(gamma),
                    goal=goal if limit else goal_states.astype(np.float64))


def _chosen_goal(model: ModelArrays, choice: np.ndarray, width: int, reached: np.ndarray,
                 later: np.ndarray | None, goal_states: np.ndarray) -> np.ndarray:
    """float64[n_full]: each state's probability of the goal when it takes its column
    ``choice`` now: an outcome that reaches the goal (``reached``) counts 1, one that ends
    the episode otherwise (stuck) 0, any other the ``later`` probability of the state it
    leads to (None: the last step, when every outcome ends the episode)."""
    pair = np.arange(len(choice)) * width + choice
    lo = model.ptr[pair]
    length = model.ptr[pair + 1] - lo
    idx = np.repeat(lo - np.cumsum(length) + length, length) + np.arange(int(length.sum()))
    row = np.repeat(np.arange(len(choice)), length)
    chance = reached[idx]
    if later is not None:
        goes_on = ~model.stuck[idx] & (chance == 0)
        chance[goes_on] = later[model.next[idx][goes_on]]
    out = np.bincount(row, weights=model.prob[idx] * chance, minlength=len(choice))
    out[goal_states] = 1.0
    return out


@dataclass(frozen=True)
class Budget:
    """What computing V* may take before a run goes on without it: memory (bytes, of
    :func:`solve` without tables) and work (outcome updates: ``step_limit`` x outcomes;
    value iteration does some 10**7 to 10**8 a second)."""

    bytes: int = 1_000_000_000
    work: int = 100_000_000


VSTAR_BUDGET = Budget()
"""The budget :func:`value_within` keeps to unless given another."""


def value_within(model: ModelArrays, goal_pos: int, start: int,
                 budget: Budget = VSTAR_BUDGET) -> dict[str, float | str | None]:
    """``{"v_star": V* from ``start``, or None past ``budget``, "v_star_note": why not,
    "v_star_upper_bound": a bound on V* when not computed}``. The bound: no episode
    reaches the goal in fewer actions than reality's shortest path L (from
    :func:`reality_distances`) and each action before the last costs at least the least
    mean cost c (less the most an outcome earns, ``model.gain``), so V* <= max(r_max -
    (L - 1) c, -r_max). On the problem's own reward scale, or where a step may pay, no
    such bound holds: None."""
    need, work = solve_bytes(model, tables=False), model.step_limit * len(model.prob)
    if need <= budget.bytes and work <= budget.work:
        solution = solve(model, goal_pos, tables=False)
        return {"v_star": float(solution.V[0, start]),
                **goal_chances(model, goal_pos, start, solution, budget)}
    past = (f"not computed: value iteration would need {human_bytes(need)} and {work:.2g} "
            f"outcome updates, past the budget ({human_bytes(budget.bytes)}, "
            f"{budget.work:.2g}: gdq_pddl.envs.solve.VSTAR_BUDGET)")
    paid = float(model.gain.max()) if model.gain.size else 0.0  # the most an outcome pays
    least = float(expected_costs(model).min())
    if model.own_scale or paid > least:  # a step may pay: no cheap bound
        return {"v_star": None, "v_star_note": past, "v_star_upper_bound": None}
    fewest = reality_distances(model, start)[model.pos_of == goal_pos].min(initial=np.inf)
    c = max(0.0, least - paid)
    bound = -model.r_max if np.isinf(fewest) else max(model.r_max - (fewest - 1) * c,
                                                      -model.r_max)
    note = (f"{past}; V* <= {bound:g} "
            f"(r_max minus the least cost of the {int(fewest) if np.isfinite(fewest) else 'no'}"
            " actions of reality's shortest path to the goal)")
    return {"v_star": None, "v_star_note": note, "v_star_upper_bound": float(bound)}


def goal_chances(model: ModelArrays, goal_pos: int, start: int, solution: Solution,
                 budget: Budget = VSTAR_BUDGET) -> dict[str, float | bool]:
    """What V* means in probabilities, from ``start``
    (:mod:`~gdq_pddl.envs.goal_chance`): ``goal_v_star_policy``, the probability that
    V*'s policy (``solution``) reaches the goal within the step limit;
    ``goal_within_limit``, the most any policy has; ``goal_no_limit``, the most with no
    step limit (exact when ``goal_no_limit_exact``, else a lower bound: ``budget.work``
    ran out)."""
    unlimited = best_without_limit(model, goal_pos, budget.work)
    return {"goal_v_star_policy": float(solution.goal[start]),
            "goal_within_limit": float(best_within_limit(model, goal_pos)[start]),
            "goal_no_limit": float(unlimited.value[start]),
            "goal_no_limit_exact": unlimited.exact}


def reality_distances(model: ModelArrays, start: int = 0) -> np.ndarray:
    """``float64[n_states]``: the fewest actions from ``start`` to each state in the true
    model, over outcomes of positive probability that do not end the trial (inf: none
    reaches it). One breadth-first search over the model's arrays."""
    n = model.obs_of.shape[0]
    starts = model.ptr[::max(width_of(model), 1)]  # each state's first outcome
    src = np.repeat(np.arange(len(starts) - 1), np.diff(starts))
    keep = (model.prob > 0) & ~model.stuck & (model.next != src)
    graph = csr_matrix((np.ones(int(keep.sum())), (src[keep], model.next[keep])),
                       shape=(n, n))
    return shortest_path(graph, directed=True, unweighted=True, indices=start)


def resolve_world_task(world: World, task: Task | str) -> Task:
    """``task`` itself, or the world's task of that name."""
    return world.task(task) if isinstance(task, str) else task


def solve_task(world: World, task: Task | str,
               model: ModelArrays | None = None) -> tuple[Solution, int]:
    """Solve ``task`` in ``world``; return the solution and the start full state."""
    t = resolve_world_task(world, task)
    model = compile_model(world) if model is None else model
    return solve(model, world.index[t.goal]), full_state(world, t.start)


def optimal_value(world: World, task: Task | str) -> float:
    """V*: the optimal expected return of ``task`` from its start, doors closed, step 0."""
    solution, s0 = solve_task(world, task)
    return float(solution.V[0, s0])


def occupancy(model: ModelArrays, solution: Solution, start: int) -> np.ndarray:
    """Where the optimal policy is: ``float64[step_limit + 1, n_full]``.

    Row 0 is the start; row ``t >= 1`` is the distribution of the full state observed
    right after action ``t`` (ending outcomes included: stuck, goal, timeout). Row ``t``
    sums to the probability that the episode lasts at least ``t`` actions.
    """
    limit, width = model.step_limit, width_of(model)
    n_full = model.obs_of.shape[0]
    out = np.zeros((limit + 1, n_full))
    running = np.zeros(n_full)
    out[0, start] = running[start] = 1.0
    for t in range(limit):
        after = np.zeros(n_full)
        for fs in np.flatnonzero(running):
            i = fs * width + solution.policy[t, fs]
            k = slice(model.ptr[i], model.ptr[i + 1])
            np.add.at(out[t + 1], model.next[k], running[fs] * model.prob[k])
            goes_on = ~model.stuck[k]
            np.add.at(after, model.next[k][goes_on], running[fs] * model.prob[k][goes_on])
        after[model.pos_of == solution.goal_pos] = 0.0
        running = after
    return out


def expected_area_visits(world: World, task: Task | str) -> dict[int, float]:
    """Expected visits per area in one episode of the optimal policy.

    A visit is the position observed after an action (the start is not counted); every
    area of the world is a key (0 collects positions in no area, if there are any).
    """
    t = resolve_world_task(world, task)
    model = compile_model(world)
    solution, s0 = solve_task(world, t, model)
    per_pos = np.zeros(len(world.positions))
    np.add.at(per_pos, model.pos_of, occupancy(model, solution, s0)[1:].sum(axis=0))
    out = {a: 0.0 for a in sorted(world.areas)}
    for i, v in enumerate(per_pos):
        a = int(model.area_of_pos[i])
        out[a] = out.get(a, 0.0) + float(v)
    return out


def relevant_areas(world: World, task: Task | str, min_visits: float = 0.0) -> tuple[int, ...]:
    """Areas whose expected visits under the optimal policy exceed ``min_visits``.

    With the default 0 this is "visited with non-zero probability"; since a failed
    ``goto`` can drop the robot anywhere nearby, that is often every reachable area,
    so a small threshold (e.g. 0.05 visits per episode) is the more telling figure.
    """
    visits = expected_area_visits(world, task)
    return tuple(a for a, v in visits.items() if a != 0 and v > min_visits)
