"""One pipeline: the office's pieces stand where the layers say, and refuse bad input."""

from __future__ import annotations

import gymnasium as gym
import pytest

import gdq_pddl  # noqa: F401  (registers the envs)
from gdq_pddl.errors import WorldError
from gdq_pddl.learners.context import office_task_context
from gdq_pddl.resources import world_text
from gdq_pddl.world import load_world, parse_world


@pytest.mark.parametrize("task", [3, 2.5, ("C",)])
def test_a_task_that_is_not_a_name_is_a_clear_error(task):
    with pytest.raises(WorldError, match="a task is named by a string"):
        gym.make("gdq_pddl/Office-v0", task=task)
    with pytest.raises(WorldError, match="a task is named by a string"):
        office_task_context(load_world(), task)


def test_a_start_that_is_not_a_name_is_a_clear_error():
    with pytest.raises(WorldError, match="a position is named by a string"):
        gym.make("gdq_pddl/Office-v0", start=0, goal="p17")


@pytest.mark.parametrize("number", ["99999999999999999999", "1000000000", "20"])
def test_an_area_number_past_the_positions_names_its_key(number):
    text = world_text("office").replace('7 = ["p13", "p18"]', f'{number} = ["p13", "p18"]')
    with pytest.raises(WorldError, match=rf"areas\.{number}: area numbers run from 1 to 19"):
        parse_world(text, source="w.toml")
