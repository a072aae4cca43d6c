"""The office as a Gymnasium env: API conformance, rewards, episode ends, rendering."""

from __future__ import annotations

from pathlib import Path

import gymnasium
import numpy as np
import pytest
from gymnasium.spaces import Discrete
from gymnasium.utils.env_checker import check_env

import gdq_pddl  # noqa: F401  (registers the env)
from gdq_pddl.envs import register_envs
from gdq_pddl.envs.office import OfficeEnv
from gdq_pddl.envs.variants import deterministic_world, with_door
from gdq_pddl.errors import PlanningError, WorldError

ENV_ID = "gdq_pddl/Office-v0"

TINY = """
[world]
name = "tiny"
step_limit = 5
r_max = 10.0
positions = ["a", "b", "c", "d"]
adjacency = [["a", "b"], ["b", "c"], ["c", "d"]]

[doors.door]
sides = ["b", "c"]
success = 0.5
stuck = 0.25

[areas]
1 = ["a", "b"]
2 = ["c", "d"]

[tasks.T]
start = "a"
goal = "d"
"""


@pytest.fixture(scope="module")
def tiny_file(tmp_path_factory: pytest.TempPathFactory) -> Path:
    path = tmp_path_factory.mktemp("worlds") / "tiny.toml"
    path.write_text(TINY, encoding="utf-8")
    return path


def act(env: gymnasium.Env, verb: str, position: str) -> tuple:
    return env.step(env.unwrapped.spaces.action(verb, position))


def test_check_env() -> None:
    check_env(gymnasium.make(ENV_ID).unwrapped, skip_render_check=False)


def test_spaces_and_default_task() -> None:
    env = gymnasium.make(ENV_ID)
    assert env.observation_space == Discrete(31)
    assert env.action_space == Discrete(95)
    assert env.unwrapped.task.name == "C"
    assert env.spec is not None and env.spec.max_episode_steps == 20  # the env's own limit


def test_make_by_task_start_goal_and_file(tiny_file: Path) -> None:
    by_task = gymnasium.make(ENV_ID, task="D").unwrapped
    assert (by_task.task.start, by_task.task.goal) == ("p0", "p18")
    adhoc = gymnasium.make(ENV_ID, start="p0", goal="p17").unwrapped
    assert (adhoc.task.start, adhoc.task.goal) == ("p0", "p17")
    landmarks = gymnasium.make(ENV_ID, start="P1", goal="P4").unwrapped
    assert (landmarks.task.start, landmarks.task.goal) == ("p14", "p18")
    tiny = gymnasium.make(ENV_ID, world=str(tiny_file))
    assert tiny.observation_space == Discrete(6)  # a, b x2, c x2, d
    assert tiny.action_space == Discrete(20)
    assert tiny.unwrapped.task.name == "T"  # no task C in this world: its first task
    obs, info = tiny.reset(seed=0)
    assert info["position"] == "a" and obs == 0
    assert gymnasium.make(ENV_ID, world=tiny_file, task="T").unwrapped.world.name == "tiny"
    assert gymnasium.make(ENV_ID, world="office").unwrapped.world.name == "office"


def test_register_twice_is_harmless() -> None:
    register_envs()
    register_envs()
    assert ENV_ID in gymnasium.registry


def test_bad_arguments_are_world_errors() -> None:
    with pytest.raises(WorldError, match="same position"):
        OfficeEnv(start="p3", goal="p3")
    with pytest.raises(WorldError, match="same position"):
        OfficeEnv(start="P2", goal="p0")  # a landmark for the same place
    with pytest.raises(WorldError, match="unknown task"):
        OfficeEnv(task="Z")
    with pytest.raises(WorldError, match="unknown position"):
        OfficeEnv(start="p0", goal="p99")
    with pytest.raises(WorldError, match="not both"):
        OfficeEnv(task="C", start="p0", goal="p17")
    with pytest.raises(PlanningError, match="no shipped world of that name"):
        OfficeEnv(world="no_such_building")  # names resolve as the CLI's do (resources)


def run(env: gymnasium.Env, seed: int, n: int) -> list:
    rng = np.random.default_rng(seed)
    out = []
    obs, info = env.reset(seed=seed)
    for _ in range(n):
        obs, reward, terminated, truncated, info = env.step(int(rng.integers(95)))
        out.append((obs, reward, terminated, truncated, info["full_state"]))
        if terminated or truncated:
            obs, info = env.reset()
    return out


def test_same_seed_same_trajectory() -> None:
    a = run(gymnasium.make(ENV_ID, task="C"), 7, 300)
    b = run(gymnasium.make(ENV_ID, task="C"), 7, 300)
    c = run(gymnasium.make(ENV_ID, task="C"), 8, 300)
    assert a == b
    assert a != c


def test_step_limit_truncates_with_minus_r_max() -> None:
    env = gymnasium.make(ENV_ID, task="C")
    env.reset(seed=0)
    rewards = []
    for t in range(20):
        obs, reward, terminated, truncated, info = act(env, "stay", "p0")
        rewards.append(reward)
        assert not terminated
        assert truncated == (t == 19)
        assert info["step"] == t + 1
    assert rewards == [-1.0] * 19 + [-20.0]
    assert info["cause"] == "timeout"
    with pytest.raises(gymnasium.error.ResetNeeded):
        act(env, "stay", "p0")


def test_goal_gives_plus_r_max(office) -> None:
    env = gymnasium.make(ENV_ID, world=deterministic_world(office), start="p16", goal="p18")
    env.reset(seed=0)
    obs, reward, terminated, truncated, info = act(env, "goto", "p18")
    assert (reward, terminated, truncated) == (20.0, True, False)
    assert info["cause"] == "goal" and info["position"] == "p18" and info["area"] == 7


def test_shortest_plan_in_the_deterministic_office(office) -> None:
    env = gymnasium.make(ENV_ID, world=deterministic_world(office), task="C")
    env.reset(seed=3)
    plan = [("approach", "p2"), ("opendoor", "p2"), ("gothrough", "p4"), ("goto", "p8"),
            ("goto", "p5"), ("approach", "p6"), ("opendoor", "p6"), ("gothrough", "p7"),
            ("goto", "p17")]
    total = 0.0
    for verb, p in plan:
        obs, reward, terminated, truncated, info = act(env, verb, p)
        total += reward
    assert terminated and info["cause"] == "goal"
    assert total == 20.0 - (len(plan) - 1)


def test_stuck_gives_minus_r_max(office) -> None:
    world = with_door(office, "d0", success=0.0, stuck=1.0)
    env = gymnasium.make(ENV_ID, world=world, start="p1", goal="p17")
    env.reset(seed=0)
    obs, reward, terminated, truncated, info = act(env, "opendoor", "p1")
    assert (reward, terminated, truncated) == (-20.0, True, False)
    assert info["cause"] == "stuck" and info["position"] == "p1"


def test_inapplicable_action_costs_a_step_and_changes_nothing() -> None:
    env = gymnasium.make(ENV_ID, task="C")
    obs0, info0 = env.reset(seed=0)
    obs, reward, terminated, truncated, info = act(env, "gothrough", "p3")  # not at a door
    assert (obs, reward, terminated, truncated) == (obs0, -1.0, False, False)
    assert info["full_state"] == info0["full_state"]


def test_info_fields() -> None:
    env = gymnasium.make(ENV_ID, task="A")
    obs, info = env.reset(seed=1)
    mask = info.pop("action_mask")  # tests/envs/test_gym_conventions.py checks its values
    assert mask.dtype == np.int8 and mask.shape == (95,)
    plan = info.pop("plan_action")  # tests/envs/test_wrappers_knowledge.py checks its values
    assert mask[plan] == 1
    assert info == {"position": "p14", "area": 4, "cause": "", "full_state":
                    env.unwrapped.instance.start_state, "step": 0}
    obs, reward, terminated, truncated, info = act(env, "approach", "p15")
    assert set(info) == {"action_mask", "plan_action", "position", "area", "cause",
                         "full_state", "step"}
    assert info["step"] == 1 and info["cause"] == ""
    assert info["position"] in ("p15", "p11", "p14")
    assert env.unwrapped.model.obs_of[info["full_state"]] == obs


def test_doors_closed_at_reset(office) -> None:
    env = gymnasium.make(ENV_ID, world=deterministic_world(office), start="p2", goal="p17")
    env.reset(seed=0)
    act(env, "opendoor", "p2")
    _, info = env.reset()
    position, opened = env.unwrapped.decode(info["full_state"])
    assert (position, opened) == ("p2", frozenset())


def test_exposed_model() -> None:
    env = gymnasium.make(ENV_ID, task="C").unwrapped
    assert env.world.step_limit == env.model.step_limit == 20
    assert env.spaces.n_states == 31


def test_ansi_render(office) -> None:
    env = gymnasium.make(ENV_ID, world=deterministic_world(office), task="C",
                         render_mode="ansi")
    env.reset(seed=0)
    text = env.render()
    assert "@p0" in text and "*p17" in text and "d1 p2|p4 closed" in text
    act(env, "approach", "p2")
    act(env, "opendoor", "p2")
    text = env.render()
    assert "@p2[d1 open]" in text and "d1 p2|p4 open" in text


def test_rgb_render() -> None:
    env = gymnasium.make(ENV_ID, task="B", render_mode="rgb_array")
    env.reset(seed=0)
    first = env.render()
    assert first.ndim == 3 and first.shape[2] == 3 and first.dtype == np.uint8
    assert first.shape[0] > 100 and first.shape[1] > 100
    act(env, "goto", "p11")
    second = env.render()
    assert second.shape == first.shape
    assert not np.array_equal(first, second)  # the robot moved (or at least the step did)


def test_render_without_mode_returns_none() -> None:
    env = OfficeEnv()
    env.reset(seed=0)
    with pytest.warns(UserWarning):
        assert env.render() is None


def test_greedy_target_reads_a_q_table_on_the_map(office) -> None:
    from gdq_pddl.envs.render import greedy_target
    from gdq_pddl.spaces import LearnerSpaces

    spaces = LearnerSpaces(office)
    masks = OfficeEnv(task="C").mask_table
    q = np.zeros((spaces.n_states, spaces.n_actions))
    assert greedy_target(spaces, q, "p0") is None  # every action ties
    q[spaces.state("p0"), spaces.action("approach", "p2")] = 1.0
    assert greedy_target(spaces, q, "p0", masks) == "p2"
    # opening the door leads on through it: the open state's greedy action
    q[spaces.state("p2"), spaces.action("opendoor", "p2")] = 1.0
    assert greedy_target(spaces, q, "p2") is None  # nothing preferred behind the door
    q[spaces.state("p2", True), spaces.action("gothrough", "p4")] = 1.0
    assert greedy_target(spaces, q, "p2", masks) == "p4"
    # arrived through a door (the closed state has no preference): the open state's
    q[spaces.state("p4", True), spaces.action("goto", "p8")] = 1.0
    assert greedy_target(spaces, q, "p4", masks) == "p8"
    # a greedy action that does nothing there: stay, or one the masks rule out
    q[spaces.state("p8"), spaces.action("stay", "p8")] = 1.0
    assert greedy_target(spaces, q, "p8") == ""
    q[spaces.state("p8"), spaces.action("goto", "p17")] = 2.0  # not a neighbour of p8
    assert greedy_target(spaces, q, "p8") == "p17"
    assert greedy_target(spaces, q, "p8", masks) == ""


def test_draw_q_draws_one_arrow_per_greedy_move(office) -> None:
    from matplotlib.figure import Figure

    from gdq_pddl.envs.render import MapPainter
    from gdq_pddl.learners import office_task_context

    painter = MapPainter(office)
    context = office_task_context(office, "C")
    q = np.zeros((context.n_states, context.n_actions))
    first_plan = context.plans.plans_from(context.s0)[0]  # p0 -> p1 -> p3 ...: Q = 1 on it
    for s, a in first_plan:
        q[s, a] = 1.0
    ax = Figure().add_subplot()
    mapping = painter.draw_q(ax, q, masks=OfficeEnv(task="C").mask_table)
    arrows = [c for c in ax.get_children() if type(c).__name__ == "Annotation"]
    # p0 -> p1, through d0 to p3, p3 -> p5, p5 -> p6, through d3 to p7, p7 -> p17
    assert len(arrows) == 6
    assert mapping.norm.vmin == 0.0 and mapping.norm.vmax == 1.0


def test_the_env_names_what_it_says_of_its_instance_and_forwards_nothing_else():
    """An env used to forward any unknown attribute to its instance (34 members): now its
    named properties read the instance, and anything else is ``env.unwrapped.instance``'s."""
    from gdq_pddl.envs.pddl_env import PDDLEnv

    office = OfficeEnv(task="C")
    inst = office.instance
    assert office.world is inst.world and office.task.name == "C"
    assert office.mask_table is inst.mask_table and office.spaces is inst.spaces
    assert office.action_name(0) == inst.action_name(0)
    assert office.decode(inst.start_state) == inst.decode(inst.start_state)
    keys = PDDLEnv("keys", "keys-1")
    assert keys.atoms(0) == keys.instance.atoms(0) and keys.atom_names == keys.instance.atom_names
    for name in ("prior", "goal_pos", "start_state", "plan_table", "r_max", "graph"):
        assert hasattr(keys.instance, name) and not hasattr(keys, name), name
    with pytest.raises(AttributeError):
        keys.world  # noqa: B018  (a PDDL problem has no office world)
