"""Gymnasium's conventions on both registered envs: ``info["action_mask"]`` (as Taxi's),
``gdq_pddl/PDDL-v0`` with files or shipped names, and the env checker."""

from __future__ import annotations

import gymnasium
import numpy as np
import pytest
from gymnasium.utils.env_checker import check_env
from hypothesis import given, settings
from hypothesis import strategies as st

import gdq_pddl  # noqa: F401  (registers the envs)
from gdq_pddl.envs import ENV_IDS, OFFICE_ID, PDDL_ID
from gdq_pddl.envs.office import CompactEnv, OfficeEnv
from gdq_pddl.envs.pddl_env import PDDLEnv, shipped_names
from gdq_pddl.envs.step import pair_of
from gdq_pddl.errors import PlanningError
from gdq_pddl.learners import office_task_context
from tests.helpers import REPO_ROOT as ROOT

KEYS_FILES = {"domain": ROOT / "domains" / "keys.pddl",
              "problem": ROOT / "problems" / "keys-2.pddl",
              "dynamics": ROOT / "gdq_pddl" / "data" / "dynamics" / "keys.toml"}


def make(env_id: str):
    kwargs = {"domain": "keys", "problem": "keys-2"} if env_id == PDDL_ID else {"task": "C"}
    return gymnasium.make(env_id, **kwargs)


def does_something(model, fs: int, a: int) -> bool:
    """Whether the true model gives (full state, action) an outcome that moves or sticks."""
    k = pair_of(model, fs, a)
    if k is None:  # not offered there: its preconditions fail
        return False
    lo, hi = model.ptr[k], model.ptr[k + 1]
    return bool(np.any((model.next[lo:hi] != fs) | model.stuck[lo:hi]))


@pytest.mark.parametrize("env_id", sorted(ENV_IDS))
def test_check_env_passes(env_id):
    check_env(make(env_id).unwrapped, skip_render_check=False)


@pytest.mark.parametrize("env_id", sorted(ENV_IDS))
def test_action_mask_in_reset_and_step_infos(env_id):
    env = make(env_id)
    obs, info = env.reset(seed=0)
    n = env.action_space.n
    for _ in range(5):
        mask = info["action_mask"]
        assert mask.dtype == np.int8 and mask.shape == (n,) and set(np.unique(mask)) <= {0, 1}
        np.testing.assert_array_equal(mask, env.unwrapped.mask_table[obs])
        assert mask.any()
        a = env.action_space.sample(mask=mask)  # Gymnasium takes it as Discrete's mask
        obs, _, terminated, truncated, info = env.step(a)
        if terminated or truncated:
            break


def test_office_mask_is_the_knowledge_through_o():
    env = OfficeEnv(task="C")
    spaces = env.spaces
    _, info = env.reset(seed=0)
    names = {spaces.action_name(a) for a in np.flatnonzero(info["action_mask"])}
    assert names == {"approach p1", "approach p2"}
    masks = env.mask_table
    closed, opened = spaces.state("p1", False), spaces.state("p1", True)
    assert masks[closed, spaces.action("opendoor", "p1")] == 1
    assert masks[closed, spaces.action("gothrough", "p3")] == 0
    assert masks[opened, spaces.action("opendoor", "p1")] == 0
    assert masks[opened, spaces.action("gothrough", "p3")] == 1
    stay = [spaces.action("stay", p) for p in env.world.positions]
    assert not masks[:, stay].any()  # the knowledge has no stay


def test_office_mask_agrees_with_the_true_model_everywhere():
    """Where knowledge and reality agree (the shipped office), 1 exactly where the action
    moves the robot, opens a door or can leave it stuck, in every full state."""
    env = OfficeEnv(task="C")
    model = env.model
    for fs in range(len(model.obs_of)):
        row = env.mask_table[model.obs_of[fs]]
        for a in range(model.n_actions):
            assert bool(row[a]) == does_something(model, fs, a), (env.decode(fs), a)


def test_every_plan_action_is_unmasked():
    env = OfficeEnv(task="C")
    table = office_task_context(env.world, "C").darling_plans
    for s in range(table.n_states):
        for plan in table.plans_from(s):
            for state, action in plan:
                assert env.mask_table[state, action] == 1


def test_pddl_mask_is_the_applicable_ground_actions():
    env = PDDLEnv(**KEYS_FILES)
    inst = env.instance
    graph, model = inst.graph, inst.model
    assert graph.is_goal.any()
    for s in range(graph.n_states):
        applicable = [op.applicable(graph.states[s]) for op in graph.task.ops]
        np.testing.assert_array_equal(env.mask_table[s], np.array(applicable, np.int8))
        if not graph.is_goal[s]:  # goal states end the episode: the model never steps them
            for a in range(model.n_actions):
                assert bool(applicable[a]) == does_something(model, s, a)


@settings(max_examples=25, deadline=None)
@given(seed=st.integers(0, 2**31 - 1), env_id=st.sampled_from(sorted(ENV_IDS)))
def test_a_masked_action_never_changes_anything(seed, env_id):
    """Property: in a random episode, an action the mask rules out leaves the full state
    as it was and never sticks."""
    env = make(env_id)
    rng = np.random.default_rng(seed)
    _, info = env.reset(seed=seed)
    done = False
    while not done:
        a = int(rng.integers(env.action_space.n))
        before, masked = info["full_state"], info["action_mask"][a] == 0
        _, _, terminated, truncated, info = env.step(a)
        done = terminated or truncated
        if masked:
            assert info["full_state"] == before and info["cause"] != "stuck"


def test_compact_env_has_the_office_mask():
    office, compact = OfficeEnv(task="C"), CompactEnv(task="C")
    np.testing.assert_array_equal(compact.mask_table, office.mask_table)
    _, info = compact.reset(seed=0)
    start = compact.spaces.state("p0")
    np.testing.assert_array_equal(info["action_mask"], office.mask_table[start])


def test_masks_are_read_only_and_infos_are_fresh():
    env = make(OFFICE_ID)
    _, info = env.reset(seed=0)
    with pytest.raises(ValueError):
        env.unwrapped.mask_table[0, 0] = 1
    info["action_mask"][:] = 0  # the user's copy: the env's table is untouched
    assert env.unwrapped.mask_table[0].any()


def test_pddl_env_by_shipped_names_equals_by_files():
    by_name = gymnasium.make(PDDL_ID, domain="keys", problem="keys-2").unwrapped
    by_file = gymnasium.make(PDDL_ID, **{k: str(v) for k, v in KEYS_FILES.items()}).unwrapped
    assert by_name.observation_space == by_file.observation_space
    assert [by_name.action_name(a) for a in range(by_name.action_space.n)] == \
        [by_file.action_name(a) for a in range(by_file.action_space.n)]
    for name in ("ptr", "prob", "next", "stuck", "cost_a"):
        np.testing.assert_array_equal(getattr(by_name.model, name), getattr(by_file.model, name))
    office = gymnasium.make(PDDL_ID, domain="office", problem="task-c").unwrapped
    assert office.observation_space.n == 828  # the office's full states (docs/domains.md)


def test_shipped_names_are_listed():
    assert {"keys", "delivery", "office"} <= set(shipped_names("domain"))
    assert {"keys-1", "keys-2", "task-c"} <= set(shipped_names("problem"))


@pytest.mark.parametrize("kwargs,message", [
    ({"domain": "nosuch", "problem": "keys-2"}, "no shipped domain of that name"),
    ({"domain": "keys", "problem": "nosuch"}, "no shipped problem of that name"),
    ({"domain": "keys"}, "needs domain= and problem="),
    ({"domain": str(KEYS_FILES["domain"]), "problem": "keys-2"}, "give its dynamics file"),
])
def test_pddl_env_argument_errors(kwargs, message):
    with pytest.raises(PlanningError, match=message):
        gymnasium.make(PDDL_ID, **kwargs)
