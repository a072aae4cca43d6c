"""The true model and its exact solution: probabilities, V*, and V* against Monte Carlo."""

from __future__ import annotations

from dataclasses import replace

import gymnasium
import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

import gdq_pddl  # noqa: F401  (registers the env)
from gdq_pddl.envs.model import compile_model, full_state
from gdq_pddl.envs.solve import (
    expected_area_visits,
    expected_costs,
    optimal_value,
    relevant_areas,
    solve,
    solve_task,
)
from gdq_pddl.envs.step import ModelArrays
from gdq_pddl.envs.variants import deterministic_world
from gdq_pddl.world import CostDist, parse_world
from tests.helpers import corridor_text

ENV_ID = "gdq_pddl/Office-v0"


@pytest.fixture(scope="module")
def office_model(office) -> ModelArrays:
    return compile_model(office)


def pair_sums(model: ModelArrays) -> np.ndarray:
    return np.add.reduceat(model.prob, model.ptr[:-1])


def test_office_probabilities_sum_to_one(office_model: ModelArrays) -> None:
    assert np.all(np.diff(office_model.ptr) > 0)
    assert np.all(office_model.prob > 0)
    np.testing.assert_allclose(pair_sums(office_model), 1.0, atol=1e-12)


door_probs = st.tuples(st.floats(0, 1), st.floats(0, 1)).map(
    lambda p: (p[0], min(p[1], 1.0 - p[0])))


@settings(max_examples=40, deadline=None)
@given(nav=st.floats(0, 1), doors=st.lists(door_probs, min_size=0, max_size=3),
       ring=st.booleans())
def test_probabilities_sum_to_one_property(nav: float, doors: list, ring: bool) -> None:
    model = compile_model(parse_world(corridor_text(nav, doors, ring), source="hypothesis"))
    assert np.all(np.diff(model.ptr) > 0)
    assert np.all(model.prob >= 0)
    np.testing.assert_allclose(pair_sums(model), 1.0, atol=1e-9)


def test_expected_costs_of_each_distribution() -> None:
    text = corridor_text(1.0, [(1.0, 0.0)], False) + """
[costs]
goto = 2.5
approach = { dist = "uniform", low = 1.0, high = 4.0 }
opendoor = { dist = "normal", mean = 1.0, sd = 2.0 }
gothrough = { dist = "normal", mean = 3.0, sd = 0.0 }
stay = 0
"""
    world = parse_world(text)
    n = len(world.positions)
    costs = expected_costs(compile_model(world))
    z = np.random.default_rng(0).standard_normal(2_000_000)
    clipped_normal = np.maximum(0.0, 1.0 + 2.0 * z).mean()
    per_verb = costs.reshape(5, n)
    np.testing.assert_allclose(per_verb[0], 2.5)
    np.testing.assert_allclose(per_verb[1], 2.5)
    np.testing.assert_allclose(per_verb[2], clipped_normal, atol=5e-3)
    assert per_verb[2, 0] > 1.0  # clipping at 0 raises the mean
    np.testing.assert_allclose(per_verb[3], 3.0)
    np.testing.assert_allclose(per_verb[4], 0.0)


def test_deterministic_office_value_is_the_shortest_plan(office) -> None:
    world = deterministic_world(office)
    model = compile_model(world)
    solution, s0 = solve_task(world, "C", model)
    assert solution.V[0, s0] == pytest.approx(20.0 - 7)  # 8 actions, the last one +20
    env = gymnasium.make(ENV_ID, world=world, task="C")
    _, info = env.reset(seed=0)
    for t in range(8):
        _, _, terminated, _, info = env.step(solution.policy[t, info["full_state"]])
    assert terminated and info["cause"] == "goal"


def test_solution_shape_and_boundaries(office, office_model: ModelArrays) -> None:
    goal = office.index["p17"]
    s = solve(office_model, goal)
    n_full = office_model.obs_of.shape[0]
    assert s.V.shape == (21, n_full) and s.policy.shape == (20, n_full)
    assert s.Q.shape == (20, n_full, 95)
    assert np.all(s.V[20] == 0.0)
    far = full_state(office, "p14")
    assert s.V[19, far] == -20.0  # last action, goal out of reach: every action fails
    assert s.policy[19, far] == 0  # all tied: lowest index
    next_to_goal = full_state(office, "p18")
    # goto p17 works (0.95), else a random neighbour of p18: p13, p16 or p17 itself.
    assert s.V[19, next_to_goal] == pytest.approx(0.95 * 20 + 0.05 * (20 - 2 * 20) / 3)
    assert np.all(s.V[:, office_model.pos_of == goal] == 0.0)
    np.testing.assert_allclose(s.V[:20], s.Q.max(axis=2) * (office_model.pos_of != goal))
    # Bounds: at best +r_max at once; at worst every cost paid, then failure.
    assert np.all(s.V <= 20.0) and np.all(s.V >= -20.0 - 19 * 1.0)


def test_solve_is_fast(office_model: ModelArrays, office) -> None:
    import time

    start = time.perf_counter()
    solve(office_model, office.index["p18"])
    assert time.perf_counter() - start < 1.0


def test_task_c_prefers_the_easy_doors(office) -> None:
    """Spec 5.4: the best route for C is areas 1 -> 3 -> 2 -> 6 (doors d1 and d3)."""
    solution, s0 = solve_task(office, "C")
    env = gymnasium.make(ENV_ID, task="C").unwrapped
    assert env.spaces.action_name(int(solution.policy[0, s0])) == "approach p2"
    visits = expected_area_visits(office, "C")
    assert visits[3] > 1 and visits[2] > 1 and visits[6] > 1
    assert relevant_areas(office, "C", min_visits=0.05) == (1, 2, 3, 6)


def monte_carlo(episodes: int, seed: int, **make_kwargs) -> tuple[float, float, float]:
    """V*[0, s0], and the mean return and its standard error of the optimal policy."""
    env = gymnasium.make(ENV_ID, **make_kwargs)
    u = env.unwrapped
    solution = solve(u.model, u.instance.goal_pos)
    returns = np.empty(episodes)
    _, info = env.reset(seed=seed)
    for e in range(episodes):
        total, done = 0.0, False
        while not done:
            action = solution.policy[info["step"], info["full_state"]]
            _, reward, terminated, truncated, info = env.step(action)
            total += reward
            done = terminated or truncated
        returns[e] = total
        _, info = env.reset()
    return (solution.V[0, u.instance.start_state], returns.mean(),
            returns.std(ddof=1) / np.sqrt(episodes))


@pytest.mark.parametrize(("task", "seed"), [("C", 11), ("A", 12)])
def test_v_star_matches_monte_carlo(task: str, seed: int) -> None:
    v_star, mean, se = monte_carlo(3000, seed, task=task)
    assert abs(mean - v_star) < 4 * se, (v_star, mean, se)


def test_v_star_matches_monte_carlo_with_random_costs(office) -> None:
    """Uniform and clipped-normal costs: solve's expected costs agree with env_step's draws."""
    costs = dict(office.costs)
    costs["goto"] = CostDist("uniform", 0.5, 3.0)
    costs["approach"] = CostDist("normal", 0.5, 2.0)  # clipped at 0 about 40% of the time
    costs["opendoor"] = CostDist("normal", 2.0, 1.0)
    world = replace(office, costs=costs)
    v_star, mean, se = monte_carlo(3000, 13, world=world, task="D")
    assert abs(mean - v_star) < 4 * se, (v_star, mean, se)


def test_optimal_value_helper(office) -> None:
    v = {t: optimal_value(office, t) for t in "ABCD"}
    assert all(0 < x < 20 for x in v.values())
    assert optimal_value(office, office.tasks["C"]) == v["C"]
