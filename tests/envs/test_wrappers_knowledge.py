"""The planner's knowledge for any Gymnasium agent (issue 37, gdq_pddl.wrappers): every
env's ``info["plan_action"]`` is the context's shortest plan's first action; the
wrappers pass ``check_env`` on both env ids and run in vector envs; the shaping terms
telescope on random episodes and the potentials are the context's distances; the fact
and distance observations say what the env's instance and context say; a problem
explored online reads its estimates, or is refused with one line."""

from __future__ import annotations

import functools
import math
import warnings

import gymnasium
import numpy as np
import pytest
from gymnasium.utils.env_checker import check_env
from hypothesis import example, given, settings
from hypothesis import strategies as st

import gdq_pddl  # noqa: F401  (registers the envs)
from gdq_pddl.abstraction.prior import first_plan_columns, prior_distances
from gdq_pddl.envs.office import CompactEnv, OfficeInstance
from gdq_pddl.envs.online import OnlineInstance
from gdq_pddl.envs.online_env import OnlineEnv
from gdq_pddl.envs.pddl_env import PDDLEnv, PDDLInstance, load_instance
from gdq_pddl.errors import ConfigError
from gdq_pddl.learners import pddl_task_context
from gdq_pddl.wrappers import DistanceObservation, FactObservation, KnowledgeShaping

ENVS = {"office": ("gdq_pddl/Office-v0", {"task": "C"}),
        "keys": ("gdq_pddl/PDDL-v0", {"domain": "keys", "problem": "keys-2"}),
        "keys-ppddl": ("gdq_pddl/PDDL-v0", {"domain": "keys-ppddl", "problem": "keys-ppddl-1"})}

# A PPDDL problem with a dead end: jumping lands in the pit, where nothing applies and
# from which the knowledge reaches no goal (the episode runs on to the step limit).
CLIFF_DOMAIN = """(define (domain cliff)
  (:requirements :strips :probabilistic-effects)
  (:predicates (at ?p) (path ?a ?b) (edge ?a ?b))
  (:action walk :parameters (?a ?b) :precondition (and (at ?a) (path ?a ?b))
    :effect (probabilistic 0.8 (and (at ?b) (not (at ?a)))))
  (:action jump :parameters (?a ?b) :precondition (and (at ?a) (edge ?a ?b))
    :effect (and (at ?b) (not (at ?a)))))
"""
CLIFF_PROBLEM = """(define (problem cliff-1) (:domain cliff)
  (:objects a b c pit)
  (:init (at a) (path a b) (path b c) (edge a pit) (edge b pit))
  (:goal (at c)))
"""

WRAPPERS = {"shaping-distance": KnowledgeShaping,
            "shaping-plan-step": functools.partial(KnowledgeShaping, gamma=0.9,
                                                   potential="plan-step", scale=0.5),
            "facts": FactObservation,
            "distance": DistanceObservation,
            "distance-flat": lambda env: gymnasium.wrappers.FlattenObservation(
                DistanceObservation(env, plan_action=False))}


@functools.cache
def cliff() -> PDDLInstance:
    return PDDLInstance.from_texts(CLIFF_DOMAIN, CLIFF_PROBLEM)


def make(name: str, **kw) -> gymnasium.Env:
    if name == "cliff":
        return PDDLEnv(instance=cliff(), **kw)
    env_id, args = ENVS[name]
    return gymnasium.make(env_id, **args, **kw)


@functools.cache
def context(name: str):
    """The learners' context of env ``name`` (what GDQ reads)."""
    return pddl_task_context(cliff() if name == "cliff" else make(name).unwrapped.instance)


def expected_plan_action(ctx, s: int) -> int:
    """The lowest env action of a column that starts a shortest plan from ``s`` (-1: none)."""
    cols = np.flatnonzero(ctx.plans.first_actions[s])
    actions = [ctx.action_of(s, int(c)) for c in cols]
    return min(actions) if actions else -1


@pytest.mark.parametrize("name", [*ENVS, "cliff"])
def test_every_state_plan_action_and_distance_are_the_contexts(name: str) -> None:
    instance, ctx = make(name).unwrapped.instance, context(name)
    for s in range(ctx.n_states):
        assert instance.goal_distance(s) == ctx.plans.length[s]
        a = instance.plan_action(s)
        assert a == expected_plan_action(ctx, s)
        if a >= 0:  # one action closer, in the prior GDQ plans on
            col = ctx.column_of(s, a)
            nxt = ctx.prior.next_state[s, col]
            assert ctx.plans.length[nxt] == ctx.plans.length[s] - 1
            assert instance.mask_table[s, a] == 1


@pytest.mark.parametrize("name", [*ENVS, "cliff"])
def test_info_says_plan_action_at_reset_and_every_step(name: str) -> None:
    env, ctx = make(name), context(name)
    rng = np.random.default_rng(3)
    obs, info = env.reset(seed=3)
    for _ in range(60):
        assert info["plan_action"] == expected_plan_action(ctx, obs)
        if info["cause"]:
            obs, info = env.reset()
            continue
        obs, _, _, _, info = env.step(int(rng.integers(env.action_space.n)))


def test_the_office_distances_are_the_prior_breadth_first() -> None:
    for task in "ABCDE":
        instance = OfficeInstance.of(task=task)
        distance = prior_distances(instance.prior, instance.learner_goal)
        table = instance.plan_table()
        assert np.array_equal(distance, table.length)
        first = first_plan_columns(instance.prior, distance)
        assert all(table.first_actions[s, first[s]] for s in np.flatnonzero(first >= 0))
        assert np.array_equal(first < 0, table.length <= 0)


@pytest.mark.parametrize("wrapper", list(WRAPPERS))
@pytest.mark.parametrize("name", ["office", "keys"])
def test_check_env(name: str, wrapper: str) -> None:
    env = WRAPPERS[wrapper](make(name))
    with warnings.catch_warnings():
        warnings.filterwarnings("ignore", message=".*different from the unwrapped version")
        check_env(env, skip_render_check=True)


@pytest.mark.parametrize("wrapper", list(WRAPPERS))
@pytest.mark.parametrize("name", ["office", "keys"])
def test_vector_env(name: str, wrapper: str) -> None:
    env_id, args = ENVS[name]
    envs = gymnasium.make_vec(env_id, num_envs=3, vectorization_mode="sync",
                              wrappers=[WRAPPERS[wrapper]], **args)
    envs.action_space.seed(0)
    obs, info = envs.reset(seed=0)
    assert obs in envs.observation_space
    assert info["plan_action"].shape == (3,)
    masks = envs.call("action_masks")  # what MaskablePPO asks, through the wrappers
    assert all(np.array_equal(m, info["action_mask"][i]) for i, m in enumerate(masks))
    ended = 0
    for _ in range(60):
        obs, reward, terminated, truncated, info = envs.step(envs.action_space.sample())
        assert obs in envs.observation_space
        ended += int(np.sum(terminated | truncated))
        if wrapper.startswith("shaping") and "shaping" in info:  # not where all reset
            live = info["_shaping"]
            assert np.allclose(reward[live], info["unshaped_reward"][live] +
                               info["shaping"][live])
    assert ended > 0  # the episodes went through the vector env's resets too
    envs.close()


def discounted_shaping(env: KnowledgeShaping, seed: int, actions: list[int],
                       follow: list[bool]) -> tuple[float, float, float, int, list]:
    """One episode of ``env`` (a plan action where ``follow``, else ``actions``):
    ``(sum gamma^t F_t, phi(s_0), phi(s_T), T, [(s_t, phi_t, terminated) for t >= 1])``."""
    _, info = env.reset(seed=seed)
    phi0, total, t, phi, seen = info["potential"], 0.0, 0, info["potential"], []
    done = info["cause"] == "goal"
    while not done:
        a = info["plan_action"] if follow[t % len(follow)] and info["plan_action"] >= 0 \
            else actions[t % len(actions)] % env.action_space.n
        _, reward, terminated, truncated, info = env.step(a)
        assert reward == pytest.approx(info["unshaped_reward"] + info["shaping"])
        total += env.gamma ** t * info["shaping"]
        phi, t = info["potential"], t + 1
        seen.append((env.unwrapped.learner_state(), phi, terminated))
        done = terminated or truncated
    return total, phi0, phi, t, seen


def phi_of(ctx, potential: str, scale: float, s: int, s0: int, step_limit: int,
           r_max: float) -> float:
    """The potential as the module docstring defines it, from the context's plans."""
    def d(x: int) -> int:
        return int(ctx.plans.length[x]) if ctx.plans.length[x] >= 0 else step_limit
    if potential == "distance":
        return -scale * d(s)
    length = d(s0)
    return 0.0 if length == 0 else scale * r_max / length * max(0, length - d(s))


@settings(max_examples=40, deadline=None)
@example(name="cliff", potential="distance", gamma=0.9, scale=1.0, seed=0, actions=[0, 3],
         follow=[False])  # walks, then jumps into the pit: a dead end until truncation
@example(name="cliff", potential="plan-step", gamma=1.0, scale=2.0, seed=1, actions=[2],
         follow=[False])
@given(name=st.sampled_from([*ENVS, "cliff"]), potential=st.sampled_from(["distance", "plan-step"]),
       gamma=st.floats(0.5, 1.0), scale=st.floats(0.01, 10.0),
       seed=st.integers(0, 2**16), actions=st.lists(st.integers(0, 10**4), min_size=1,
                                                    max_size=30),
       follow=st.lists(st.booleans(), min_size=1, max_size=8))
def test_shaping_terms_telescope_on_random_episodes(name, potential, gamma, scale, seed,
                                                    actions, follow) -> None:
    env = KnowledgeShaping(make(name), gamma=gamma, potential=potential, scale=scale)
    total, phi0, phi_t, t, seen = discounted_shaping(env, seed, actions, follow)
    assert total == pytest.approx(gamma ** t * phi_t - phi0, abs=1e-9 * (1 + abs(phi0)))
    # the potentials are the context's: phi(s_0) at reset, 0 where the episode terminated
    base, ctx = env.unwrapped, context(name)
    s0 = base.instance.learner_start
    expect = functools.partial(phi_of, ctx, potential, scale, s0=s0,
                               step_limit=int(base.model.step_limit), r_max=base.instance.r_max)
    assert phi0 == pytest.approx(expect(s0))
    for s, phi, terminated in seen:
        assert phi == (0.0 if terminated else pytest.approx(expect(s)))


def test_unshaped_rewards_are_the_envs() -> None:
    shaped, plain = KnowledgeShaping(make("keys"), gamma=0.95), make("keys")
    shaped.reset(seed=7)
    plain.reset(seed=7)
    rng = np.random.default_rng(7)
    for _ in range(40):
        a = int(rng.integers(shaped.action_space.n))
        out, ref = shaped.step(a), plain.step(a)
        assert out[4]["unshaped_reward"] == ref[1] and out[0] == ref[0] and out[2:4] == ref[2:4]
        if out[2] or out[3]:
            shaped.reset()
            plain.reset()


def test_truncation_keeps_the_last_potential_and_the_goal_has_zero() -> None:
    env = KnowledgeShaping(make("office"), gamma=1.0)
    _, info = env.reset(seed=0)
    phi0 = -context("office").plans.length[context("office").s0]
    assert info["potential"] == phi0 < 0
    stay = env.unwrapped.spaces.action("stay", "p0")
    while True:  # staying never ends in the goal: the step limit truncates
        _, _, terminated, truncated, info = env.step(stay)
        if terminated or truncated:
            break
    assert truncated and not terminated and info["potential"] == phi0 and info["shaping"] == 0
    env = KnowledgeShaping(make("office"), gamma=0.9, potential="plan-step")
    _, info = env.reset(seed=0, options={"start": "p16", "goal": "p18"})
    assert info["potential"] == 0.0  # the plan's first step
    _, reward, terminated, _, info = env.step(info["plan_action"])  # goto p18: the goal
    assert terminated and info["cause"] == "goal" and info["potential"] == 0.0
    assert info["shaping"] == 0.0 and reward == info["unshaped_reward"]


def test_fact_observation_is_the_true_state() -> None:
    env = FactObservation(make("keys"))
    obs, _ = env.reset(seed=0)
    instance = env.unwrapped.instance
    assert env.atom_names == instance.graph.task.facts and "(at c11)" in env.atom_names
    rng = np.random.default_rng(0)
    for _ in range(40):
        s = env.unwrapped.learner_state()
        assert {env.atom_names[j] for j in np.flatnonzero(obs)} == instance.atoms(s)
        obs, _, terminated, truncated, _ = env.step(int(rng.integers(env.action_space.n)))
        if terminated or truncated:
            obs, _ = env.reset()


def test_fact_observation_of_the_office_is_its_positions_and_doors() -> None:
    env = FactObservation(make("office"))
    world = env.unwrapped.world
    assert env.atom_names == tuple(f"(at {p})" for p in world.positions) + tuple(
        f"(open {d.name})" for d in world.doors)
    obs, info = env.reset(seed=0)
    spaces = env.unwrapped.spaces
    for verb, where in [("approach", "p1"), ("opendoor", "p1"), ("gothrough", "p2")]:
        obs, _, _, _, info = env.step(spaces.action(verb, where))
        position, opened = env.unwrapped.decode(info["full_state"])
        true = {env.atom_names[j] for j in np.flatnonzero(obs)}
        assert true == {f"(at {position})"} | {f"(open {d})" for d in opened}
        assert position == info["position"]
    compact = CompactEnv(task="C")  # the same atoms from the compact model's state
    compact.reset(seed=0)
    assert compact.facts()[world.index["p0"]] == 1 and compact.facts().sum() == 1


def test_distance_observation_is_the_contexts() -> None:
    env, ctx = DistanceObservation(make("keys")), context("keys")
    assert env.observation_space["plan_action"].n == env.action_space.n + 1
    obs, info = env.reset(seed=1)
    rng = np.random.default_rng(1)
    for _ in range(40):
        s = obs["observation"]
        assert obs["distance"][0] == ctx.plans.length[s]
        assert obs["plan_action"] == (info["plan_action"] if info["plan_action"] >= 0
                                      else env.action_space.n)
        obs, _, terminated, truncated, info = env.step(int(rng.integers(env.action_space.n)))
        if terminated or truncated:
            obs, info = env.reset()
    plain = DistanceObservation(make("office"), plan_action=False)
    assert set(plain.observation_space) == {"observation", "distance"}


def test_wrappers_stack() -> None:
    env = KnowledgeShaping(DistanceObservation(FactObservation(make("keys"))))
    obs, info = env.reset(seed=0)
    assert obs in env.observation_space and obs["observation"].dtype == np.int8
    assert obs["distance"][0] == -info["potential"]


def online_env(estimate: str | None = "h_add") -> OnlineEnv:
    base = load_instance("keys-ppddl", "keys-ppddl-1")
    return OnlineEnv(OnlineInstance(base, dynamics=base.dynamics, estimate=estimate))


def test_online_wrappers_read_the_estimates_of_the_plan_table() -> None:
    env = DistanceObservation(FactObservation(online_env()))
    shaped = KnowledgeShaping(env)
    obs, info = shaped.reset(seed=0)
    instance = env.unwrapped.instance
    rng = np.random.default_rng(0)
    for _ in range(40):
        row = env.unwrapped.learner_state()
        table = instance.plan_table()
        assert obs["distance"][0] == table.length[row]
        first = np.flatnonzero(table.first_actions[row])
        assert info["plan_action"] == (instance.columns[row, first[0]] if len(first) else -1)
        assert {instance.atom_names[j] for j in np.flatnonzero(obs["observation"])} == \
            instance.atoms(row)
        if info["cause"]:
            obs, info = shaped.reset()
            continue
        obs, _, _, _, info = shaped.step(int(rng.integers(shaped.action_space.n - 1)))


def test_online_without_estimates_is_refused_in_one_line() -> None:
    env = online_env(estimate=None)
    for wrapper in (KnowledgeShaping, DistanceObservation):
        with pytest.raises(ConfigError, match=rf"^{wrapper.__name__}: .*explored online "
                           r"without distance estimates \(estimate=None\)[^\n]*$"):
            wrapper(env)
    FactObservation(env).reset(seed=0)  # the facts need no knowledge


def test_an_env_without_knowledge_is_refused() -> None:
    with pytest.raises(ConfigError, match="^FactObservation: FrozenLakeEnv is not an env "
                       "of gdq_pddl"):
        FactObservation(gymnasium.make("FrozenLake-v1"))


@pytest.mark.parametrize("kw,message", [
    ({"gamma": 0.0}, r"gamma=0.0: expected a number in \(0, 1\]"),
    ({"gamma": math.nan}, "gamma=nan"),
    ({"gamma": True}, "gamma=True"),
    ({"scale": -1}, r"scale=-1: expected a number in \(0, 1e\+09\]"),
    ({"potential": "plan"}, "potential='plan': expected one of distance, plan-step")])
def test_bad_shaping_arguments(kw: dict, message: str) -> None:
    with pytest.raises(ConfigError, match="^KnowledgeShaping: " + message):
        KnowledgeShaping(make("office"), **kw)


def test_from_files_takes_shipped_names() -> None:
    by_name = PDDLInstance.from_files("keys", "keys-2")
    assert by_name.n_states == context("keys").n_states
    assert by_name.dynamics.source.endswith("keys.toml")


def test_a_dead_end_stands_at_the_step_limit() -> None:
    instance = cliff()
    pit = next(s for s in range(instance.n_states) if "(at pit)" in instance.atoms(s))
    assert instance.goal_distance(pit) == -1 and instance.plan_action(pit) == -1
    env = DistanceObservation(KnowledgeShaping(make("cliff"), gamma=0.9, scale=2.0))
    obs, info = env.reset(seed=0)
    assert obs["distance"][0] == 2 and info["potential"] == -4.0
    jump = next(a for a in range(instance.n_actions)
                if instance.action_name(a) == "(jump a pit)")
    obs, _, terminated, truncated, info = env.step(jump)
    limit = int(instance.model.step_limit)
    assert not terminated and not truncated
    assert obs["distance"][0] == -1 and obs["plan_action"] == env.action_space.n
    assert info["plan_action"] == -1 and info["potential"] == -2.0 * limit
    assert info["shaping"] == pytest.approx(0.9 * -2.0 * limit + 4.0)
