"""The frames of an episode (``render_mode="rgb_array"``, what Gymnasium's ``RecordVideo``
saves) show the step, the action just taken and a legend; tested without moviepy, through
``RenderCollection``, which keeps the same frames."""

from __future__ import annotations

import gymnasium
import numpy as np
from gymnasium.wrappers import RenderCollection

import gdq_pddl  # noqa: F401  (registers the env ids)
from gdq_pddl.envs.render import LEGEND, Frame, caption
from gdq_pddl.world import builtin_world


def test_the_caption_names_the_step_and_the_action_taken():
    world = builtin_world("office")
    start = Frame(world, "B", "p0", "p18", frozenset(), 0)
    assert caption(start) == ("task B: robot at p0, goal p18, step 0/20",
                              "start of the episode")
    later = Frame(world, "B", "p11", "p18", frozenset({"d1"}), 3, "stuck", "opendoor p2")
    assert caption(later) == ("task B: robot at p11, goal p18, step 3/20 (stuck)",
                              "action taken: opendoor p2")
    assert {label for *_, label in LEGEND} >= {"robot", "goal", "door open", "door closed"}


def test_frames_differ_by_the_action_taken_alone():
    """Two actions that leave the robot where it was, at the same step: the frames differ,
    in the caption band at the top only."""
    frames = []
    for verb in ("stay", "goto"):
        env = gymnasium.make("gdq_pddl/Office-v0", task="B", render_mode="rgb_array")
        _, info = env.reset(seed=0)
        spaces, start = env.unwrapped.spaces, info["position"]
        env.step(spaces.action(verb, start if verb == "stay" else "p17"))  # neither moves
        assert env.unwrapped.instance.info(env.unwrapped._position())["position"] == start
        frames.append(env.render())
    first, second = frames
    assert first.shape == second.shape
    rows = np.flatnonzero((first != second).any(axis=(1, 2)))
    assert len(rows) and rows.max() < 0.1 * first.shape[0]


def test_render_collection_keeps_one_annotated_frame_per_step():
    env = RenderCollection(gymnasium.make("gdq_pddl/Office-v0", task="B",
                                          render_mode="rgb_array"))
    env.reset(seed=0)
    spaces = env.unwrapped.spaces
    for verb, where in (("goto", "p11"), ("goto", "p14")):
        env.step(spaces.action(verb, where))
    frames = env.render()
    assert len(frames) == 3 and all(f.shape == frames[0].shape for f in frames)
    assert not np.array_equal(frames[1], frames[2])


def test_a_pddl_frame_says_the_action_taken():
    """The same state, reached by two different actions: the frames differ."""
    frames = []
    for k in (0, 1):
        env = gymnasium.make("gdq_pddl/PDDL-v0", domain="keys", problem="keys-1",
                             render_mode="rgb_array")
        _, info = env.reset(seed=0)
        start = env.unwrapped._fs
        frames.append(env.render())
        env.step(int(np.flatnonzero(info["action_mask"] == 0)[k]))  # inapplicable: no change
        assert env.unwrapped._fs == start
        frames.append(env.render())
    assert not np.array_equal(frames[0], frames[1])  # start vs. after an action
    assert np.array_equal(frames[0], frames[2])
    assert not np.array_equal(frames[1], frames[3])  # after one action vs. another


def test_plan_routes_list_where_the_robot_goes_and_are_drawn():
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    from gdq_pddl.envs.render import MapPainter, plan_route
    from gdq_pddl.learners import office_task_context
    from gdq_pddl.spaces import LearnerSpaces

    world = builtin_world("office")
    spaces, context = LearnerSpaces(world), office_task_context(world, "C")
    plan = context.plans.plans_from(context.s0)[0]
    assert [spaces.action_name(a) for _, a in plan][:3] == \
        ["approach p1", "opendoor p1", "gothrough p3"]
    assert plan_route(spaces, plan)[:3] == ["p0", "p1", "p3"]  # opening moves nobody
    assert plan_route(spaces, []) == []
    fig, ax = plt.subplots()
    routes = [plan_route(spaces, p) for p in context.plans.plans_from(context.s0)]
    MapPainter(world).draw_plans(ax, routes, world.task("C"))
    labels = [t.get_text() for t in ax.get_legend().get_texts()]
    assert labels == [f"plan {k + 1}: {' > '.join(r)}" for k, r in enumerate(routes)]
    plt.close(fig)
