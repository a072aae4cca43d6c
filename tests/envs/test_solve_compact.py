"""The reference value of large worlds: pessimistic value iteration over learner states."""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from gdq_pddl.buildings import building_world
from gdq_pddl.envs.compact import CompactModel, compile_compact
from gdq_pddl.envs.office import CompactEnv
from gdq_pddl.envs.solve import TIE_TOLERANCE, expected_costs, optimal_value
from gdq_pddl.envs.solve_compact import (
    reference_value,
    solve_compact,
    solve_compact_task,
)
from gdq_pddl.spaces import LearnerSpaces
from gdq_pddl.world import parse_world
from gdq_pddl.world_types import Task, World
from tests.helpers import corridor_text


def open_door_deficit(model: CompactModel, solution) -> float:
    """How much more any door side is ever worth closed than open (0 without doors): at
    most ``TIE_TOLERANCE`` means "the worse of the two" was always "closed"."""
    sides = np.flatnonzero(model.door_of_pos >= 0)
    if sides.size == 0:
        return 0.0
    closed, opened = model.state_of[sides, 0], model.state_of[sides, 1]
    return float(np.max(solution.V[:, closed] - solution.V[:, opened]))

def dense_values(world: World, goal: str, always_closed: bool = False):
    """The same model solved the slow way: every (state, action) pair with its outcomes
    spelled out (an empty pair: stay), next states derived from the verbs, Q tables as in
    :func:`gdq_pddl.envs.solve.solve`. ``always_closed``: a door side reached by walking
    counts as closed instead of the worse of closed and open. Returns ``(V, policy)``."""
    m = compile_compact(world)
    spaces = LearnerSpaces(world)
    n_states, n_actions, limit, r = spaces.n_states, m.n_actions, m.step_limit, m.r_max
    cost = expected_costs(m)
    g = world.index[goal]
    rows = []  # (pair, prob, next state if closed, next state if open, next pos, stuck)
    for s, (p, is_open) in enumerate(spaces.states):
        pi = world.index[p]
        for a in range(n_actions):
            i = s * n_actions + a
            if m.ptr[i] == m.ptr[i + 1]:
                rows.append((i, 1.0, s, s, pi, False))
            for k in range(m.ptr[i], m.ptr[i + 1]):
                q = int(m.next_pos[k])
                verb = spaces.action_parts(a)[0]
                if q == pi:  # stayed: the door is as it was, or opened now
                    known = spaces.state(p, is_open or bool(m.opens[k]))
                    rows.append((i, m.prob[k], known, known, q, m.stuck[k]))
                elif verb == "gothrough":
                    known = spaces.state(world.positions[q], True)
                    rows.append((i, m.prob[k], known, known, q, m.stuck[k]))
                else:
                    closed = spaces.state(world.positions[q], False)
                    other = closed if always_closed else spaces.state(world.positions[q], True)
                    rows.append((i, m.prob[k], closed, other, q, m.stuck[k]))
    pair, prob, closed, other, pos, stuck = (np.array(c) for c in zip(*rows, strict=True))
    starts = np.flatnonzero(np.r_[True, pair[1:] != pair[:-1]])
    assert len(starts) == n_states * n_actions
    at_goal = pos == g
    end_reward = np.where(stuck, -r, np.where(at_goal, r, -r))
    goal_states = m.pos_of_state == g
    V = np.zeros((limit + 1, n_states))
    policy = np.empty((limit, n_states), dtype=np.int64)
    for t in range(limit - 1, -1, -1):
        after = np.minimum(V[t + 1, closed], V[t + 1, other])
        value = end_reward if t == limit - 1 else np.where(
            stuck | at_goal, end_reward, -cost[pair % n_actions] + after)
        q = np.add.reduceat(prob * value, starts).reshape(n_states, n_actions)
        best = q.max(axis=1)
        policy[t] = np.argmax(q >= best[:, None] - TIE_TOLERANCE, axis=1)
        V[t] = np.where(goal_states, 0.0, best)
    return V, policy


def test_office_reference_is_v_star(office: World) -> None:
    """On the office the bound is tight: optimal policies never come back to a door they
    opened, so forgetting open doors costs nothing (equal to V* to 1e-9, tasks A-E)."""
    model = compile_compact(office)
    for task in "ABCDE":
        solution = solve_compact_task(office, task, model)
        v_star = optimal_value(office, task)
        assert solution.value == reference_value(office, task)
        assert solution.value <= v_star + 1e-9
        assert solution.value == pytest.approx(v_star, abs=1e-9)
        assert open_door_deficit(model, solution) <= TIE_TOLERANCE


@pytest.mark.parametrize("task", ["A", "C", "E"])
def test_compiled_solver_matches_the_dense_one(office: World, task: str) -> None:
    """The compiled loop (no-op pairs folded into one per state) gives the values and
    the lowest-index greedy actions of the plain Q-table computation."""
    V, policy = dense_values(office, office.task(task).goal)
    solution = solve_compact_task(office, task)
    np.testing.assert_allclose(solution.V, V, rtol=0, atol=1e-12)
    np.testing.assert_array_equal(solution.policy, policy)
    start = compile_compact(office).state_of[office.index[office.task(task).start], 0]
    assert solution.value == solution.V[0, start]
    assert solution.policy.shape == (office.step_limit, LearnerSpaces(office).n_states)


def corridor(nav: float, doors: list[tuple[float, float]], costs: dict[str, float],
             step_limit: int) -> World:
    """x0 - y0 | z0 - x1 - y1 | z1 - x2 ... (a door between each y and z)."""
    cost_lines = "\n".join(f"{verb} = {c!r}" for verb, c in costs.items())
    return parse_world(corridor_text(nav, doors, world=f"step_limit = {step_limit}\n"
                                     "r_max = 10.0\n", sections=f"[costs]\n{cost_lines}\n\n"),
                       source="corridor")


def test_always_closed_would_over_estimate() -> None:
    """Why a door side reached on foot counts as the worse of closed and open: with
    opendoor cheaper than gothrough and time running out, a closed door is the cheaper
    way to get stuck (-r_max, no more costs), and "always closed" exceeds V*."""
    world = corridor(0.513, [(0.749, 0.132), (0.379, 0.302), (0.901, 0.093)],
                     {"goto": 1.073, "approach": 1.715, "opendoor": 0.966,
                      "gothrough": 1.783, "stay": 1.014}, step_limit=9)
    task = Task("T", "z0", "z2")
    v_star = optimal_value(world, task)
    start = compile_compact(world).state_of[world.index["z0"], 0]
    closed_only = dense_values(world, "z2", always_closed=True)[0][0, start]
    assert closed_only > v_star + 0.03
    solution = solve_compact_task(world, task)
    assert solution.value <= v_star + 1e-9
    assert open_door_deficit(compile_compact(world), solution) > 0.5


door_probs = st.tuples(st.floats(0.05, 1), st.floats(0, 1)).map(
    lambda p: (p[0], p[1] * (1.0 - p[0])))
verb_costs = st.fixed_dictionaries(
    {v: st.floats(0, 3) for v in ("goto", "approach", "opendoor", "gothrough", "stay")})


@settings(max_examples=25, deadline=None)
@given(nav=st.floats(0.2, 1), doors=st.lists(door_probs, min_size=1, max_size=3),
       costs=verb_costs, step_limit=st.integers(2, 20), data=st.data())
def test_reference_is_a_lower_bound_property(nav, doors, costs, step_limit, data) -> None:
    """Whatever the costs and probabilities: reference <= V* (computable on a corridor)."""
    world = corridor(nav, doors, costs, step_limit)
    start, goal = data.draw(st.lists(st.sampled_from(world.positions), min_size=2,
                                     max_size=2, unique=True))
    task = Task("T", start, goal)
    assert reference_value(world, task) <= optimal_value(world, task) + 1e-9


def test_small_building_reference_is_v_star() -> None:
    world = building_world(40, 1)  # 5 doors: V* is computable
    model = compile_compact(world)
    for task in world.tasks:
        solution = solve_compact_task(world, task, model)
        assert solution.value == pytest.approx(optimal_value(world, task), abs=1e-9)


def stay_put_return(model: CompactModel) -> float:
    """The return of doing nothing until the timeout at the cheapest action."""
    return -model.r_max - (model.step_limit - 1) * float(expected_costs(model).min())


@pytest.mark.parametrize("n", [40, 60, 80])
def test_building_references_are_sane(n: int) -> None:
    """Between doing nothing until the timeout and +r_max; the worse door state of a
    side reached on foot is always "closed" (the value of doors closing behind)."""
    for seed in range(3):
        world = building_world(n, seed)
        model = compile_compact(world)
        for task in world.tasks:
            solution = solve_compact_task(world, task, model)
            assert stay_put_return(model) <= solution.value <= model.r_max
            assert open_door_deficit(model, solution) <= TIE_TOLERANCE
            assert np.all(solution.V[:, model.pos_of_state == solution.goal_pos] == 0.0)


def test_policy_in_reality_does_at_least_as_well() -> None:
    """Doors stay open in reality, which can only help: Monte Carlo of ``policy`` in
    :class:`CompactEnv` (the real dynamics) is at least ``value`` - 4 standard errors."""
    world = building_world(40, 0)
    env = CompactEnv(task="A", world=world)
    solution = solve_compact(env.model, env.instance.start_pos, env.instance.goal_pos)
    returns = []
    for episode in range(1500):
        s, _ = env.reset(seed=episode)
        total, t, done = 0.0, 0, False
        while not done:
            s, reward, terminated, truncated, _ = env.step(solution.policy[t, s])
            total, t, done = total + reward, t + 1, terminated or truncated
        returns.append(total)
    mean, se = np.mean(returns), np.std(returns, ddof=1) / np.sqrt(len(returns))
    assert mean >= solution.value - 4 * se


def test_large_building_solves() -> None:
    world = building_world(1000, 0)
    model = compile_compact(world)
    solution = solve_compact_task(world, "A", model)
    assert solution.V.shape == (world.step_limit + 1, model.pos_of_state.size)
    assert stay_put_return(model) <= solution.value <= model.r_max
