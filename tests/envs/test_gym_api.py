"""The Gymnasium API as other libraries use it, on both env ids: ``action_masks()`` as
sb3-contrib's MaskablePPO calls it (wrapped and vectorised; no torch needed),
``reset(options=...)``, ``spec.max_episode_steps`` and the render modes."""

from __future__ import annotations

from pathlib import Path

import gymnasium
import numpy as np
import pytest
from gymnasium.vector import SyncVectorEnv
from gymnasium.wrappers import RecordEpisodeStatistics, TimeLimit

import gdq_pddl  # noqa: F401  (registers the envs)
from gdq_pddl.envs import ENV_IDS, OFFICE_ID, PDDL_ID
from gdq_pddl.errors import ConfigError

KWARGS = {OFFICE_ID: {"task": "C"}, PDDL_ID: {"domain": "keys", "problem": "keys-2"}}
WORLD = """
[world]
name = "line"
step_limit = 7
positions = ["a", "b", "c"]
adjacency = [["a", "b"], ["b", "c"]]

[areas]
1 = ["a", "b", "c"]

[tasks.T]
start = "a"
goal = "c"
"""


def make(env_id: str, **kwargs) -> gymnasium.Env:
    return gymnasium.make(env_id, **KWARGS[env_id], **kwargs)


def check_mask(mask, info_mask: np.ndarray) -> None:
    assert isinstance(mask, np.ndarray) and mask.dtype == np.bool_
    np.testing.assert_array_equal(mask, info_mask.astype(bool))
    assert mask.any()


@pytest.mark.parametrize("env_id", sorted(ENV_IDS))
def test_action_masks_is_the_current_mask_through_wrappers(env_id):
    env = RecordEpisodeStatistics(make(env_id))
    masks = env.get_wrapper_attr("action_masks")
    rng = np.random.default_rng(0)
    _, info = env.reset(seed=0)
    check_mask(masks(), info["action_mask"])
    for _ in range(30):
        _, _, terminated, truncated, info = env.step(env.action_space.sample(
            mask=info["action_mask"]) if rng.random() < 0.8 else env.action_space.sample())
        check_mask(masks(), info["action_mask"])
        if terminated or truncated:
            _, info = env.reset()
    unwrapped = env.unwrapped
    np.testing.assert_array_equal(masks(), unwrapped.mask_table[unwrapped._observe()])


@pytest.mark.parametrize("env_id", sorted(ENV_IDS))
def test_action_masks_vectorised(env_id):
    envs = SyncVectorEnv([lambda: make(env_id)] * 2)
    _, infos = envs.reset(seed=[0, 1])
    for _ in range(25):  # past an episode's end: the autoreset step answers the reset state
        for k, mask in enumerate(envs.call("action_masks")):
            check_mask(mask, infos["action_mask"][k])
        actions = [envs.single_action_space.sample(mask=m) for m in infos["action_mask"]]
        *_, infos = envs.step(np.array(actions))
    envs.close()


def test_office_reset_takes_start_and_goal_for_one_episode():
    env = make(OFFICE_ID)
    spaces = env.unwrapped.spaces
    obs, info = env.reset(seed=0, options={"start": "p3"})
    assert (obs, info["position"]) == (spaces.state("p3"), "p3")
    assert env.unwrapped.task.goal == "p17"
    obs, info = env.reset(options={"start": "p18", "goal": "p13"})
    assert info["position"] == "p18"
    *_, terminated, _, info = env.step(spaces.action("approach", "p13"))
    assert terminated and info["cause"] == "goal"
    obs, info = env.reset()  # no options: the env's own task again
    assert info["position"] == "p0" and env.unwrapped.task.name == "C"


def test_pddl_reset_takes_a_start_state_as_its_facts():
    env = make(PDDL_ID, render_mode="ansi")
    _, info = env.reset(seed=0)
    obs, *_ = env.step(int(np.flatnonzero(info["action_mask"])[0]))
    facts = env.render().split(": ", 1)[1]
    assert obs != 0
    assert env.reset(options={"start": facts})[0] == obs
    assert env.reset()[0] == 0
    atoms = sorted(env.unwrapped.atoms(obs))
    assert env.reset(options={"start": [a.upper() for a in atoms]})[0] == obs


@pytest.mark.parametrize("env_id,options,message", [
    (OFFICE_ID, {"start": "p99"}, "unknown position 'p99'"),
    (OFFICE_ID, {"start": "p17"}, "same position"),
    (OFFICE_ID, {"begin": "p3"}, "unknown key 'begin'"),
    (PDDL_ID, {"start": "(at c11) (at nowhere)"}, r"\(at nowhere\) is no fluent fact"),
    (PDDL_ID, {"start": "(at c12)"}, "exactly these fluent facts"),
    (PDDL_ID, {"goal": "(at c35)"}, "a PDDL env's goal is its problem's"),
    (PDDL_ID, {"seed": 3}, "unknown key 'seed'"),
])
def test_reset_options_refused_clearly(env_id, options, message):
    env = make(env_id)
    with pytest.raises(ConfigError, match=message) as caught:
        env.reset(options=options)
    assert isinstance(caught.value, ValueError)


@pytest.mark.parametrize("env_id", sorted(ENV_IDS))
def test_spec_states_the_envs_own_step_limit(env_id):
    env = make(env_id)
    limit = env.unwrapped.model.step_limit
    assert env.spec.max_episode_steps == limit
    assert not any(isinstance(w, TimeLimit) for w in _chain(env))  # one truncation only
    _, info = env.reset(seed=0)
    idle = int(np.flatnonzero(info["action_mask"] == 0)[-1])  # does nothing, never ends
    for t in range(1, limit + 1):
        *_, terminated, truncated, info = env.step(idle)
        assert not terminated and truncated == (t == limit)


def test_spec_follows_a_world_file(tmp_path: Path):
    path = tmp_path / "line.toml"
    path.write_text(WORLD, encoding="utf-8")
    env = gymnasium.make(OFFICE_ID, world=str(path))
    assert env.spec.max_episode_steps == 7
    assert gymnasium.make(env.spec).spec.max_episode_steps == 7  # remade from its spec


def _chain(env: gymnasium.Env):
    while isinstance(env, gymnasium.Wrapper):
        yield env
        env = env.env


def test_pddl_ansi_lists_the_true_facts():
    env = make(PDDL_ID, render_mode="ansi")
    obs, info = env.reset(seed=0)
    for _ in range(3):
        text = env.render()
        assert text.startswith(f"step {info['step']}")
        assert set(text.split(": ", 1)[1].replace(") (", ")|(").split("|")) == \
            set(env.unwrapped.atoms(obs))
        obs, *_, info = env.step(int(np.flatnonzero(info["action_mask"])[-1]))


def test_pddl_rgb_array_draws_the_facts_at_one_size():
    """What sb3's ``make_vec_env`` asks for by default, and a video needs: one shape."""
    env = make(PDDL_ID, render_mode="rgb_array")
    _, info = env.reset(seed=0)
    first = env.render()
    env.step(int(np.flatnonzero(info["action_mask"])[0]))
    second = env.render()
    assert first.shape == second.shape == (480, 640, 3) and first.dtype == np.uint8
    assert first.min() < 128 and not np.array_equal(first, second)


@pytest.mark.parametrize("start,message", [
    (3, r"start 3 is of type int; expected a string of fluent facts"),
    (b"(at c11)", r"is of type bytes"),
    ([3], r"3 \(of type int\) is not a fact"),
    (["(at c11) (open c11)"], r"'\(at c11\) \(open c11\)' is not one fact"),
    ({"(at c11)": 1}, r"is of type dict"),
    ("at c11", r"text outside \( \) at character 1: 'at'"),
    ("(at c11) (open c11", r"unbalanced parentheses: a '\(' never closed"),
    ("(at c11)) (open c11", r"unbalanced parentheses: a '\)' without its '\(' at character 9"),
    ("(at (c11))", r"nested parentheses at character 5"),
])
def test_a_start_that_is_not_facts_is_refused(start, message):
    """Issue 38: an int was a TypeError, bytes and lists of non-strings became facts such
    as ``(116)``, and text outside ``( )`` was dropped."""
    with pytest.raises(ConfigError, match=message):
        make(PDDL_ID).reset(options={"start": start})


@pytest.mark.parametrize("extra", [" (", ")", " x", " (open c11"])
def test_a_start_with_more_than_its_facts_is_not_read_as_them(extra):
    """Unbalanced parentheses or words around a right start were dropped, so that the text
    was silently read as that start."""
    env = make(PDDL_ID, render_mode="ansi")
    env.reset(seed=0)
    facts = env.render().split(": ", 1)[1]  # the start, as render() lists it
    assert env.reset(options={"start": facts})[0] == 0
    with pytest.raises(ConfigError, match="unbalanced parentheses|text outside"):
        env.reset(options={"start": facts + extra})


@pytest.mark.parametrize("options", [3, ["start"], "start"])
def test_reset_options_that_are_not_a_dict_are_refused(options):
    with pytest.raises(ConfigError, match="reset options: expected a dict"):
        make(PDDL_ID).reset(options=options)


@pytest.mark.parametrize("env_id,kwargs,name", [
    (PDDL_ID, {"domain": 123, "problem": "keys-2"}, "domain=123"),
    (PDDL_ID, {"domain": "keys", "problem": ["keys-2"]}, r"problem=\['keys-2'\]"),
    (PDDL_ID, {"domain": "keys", "problem": "keys-2", "dynamics": 1.5}, "dynamics=1.5"),
    (PDDL_ID, {"domain": b"keys", "problem": "keys-2"}, "domain=b'keys'"),
    (OFFICE_ID, {"world": 3}, "world=3"),
])
def test_make_names_a_parameter_of_the_wrong_type(env_id, kwargs, name):
    with pytest.raises(ConfigError, match=f"^{name}: expected the name of a shipped .* or a "
                       r"file's path \(a str or an os.PathLike\).*, got "):
        gymnasium.make(env_id, **kwargs)
