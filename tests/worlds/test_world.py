"""The world loader: a valid file loads; every error names the file and the key."""

from __future__ import annotations

from pathlib import Path

import pytest

from gdq_pddl.errors import WorldError
from gdq_pddl.world import load_world, parse_world

TINY = """
[world]
name = "tiny"
step_limit = 6
positions = ["a", "b", "c", "d"]
adjacency = [["a", "b"], ["b", "c"], ["c", "d"]]

[doors.door]
sides = ["b", "c"]
success = 0.5
stuck = 0.25

[areas]
1 = ["a", "b"]
2 = ["c", "d"]

[landmarks]
HOME = "a"

[tasks.T]
start = "HOME"
goal = "d"
"""


def broken(old: str, new: str) -> str:
    assert old in TINY, old
    return TINY.replace(old, new)


def test_tiny_world_loads() -> None:
    w = parse_world(TINY, source="tiny.toml")
    assert w.positions == ("a", "b", "c", "d")
    assert w.step_limit == 6
    assert [d.name for d in w.doors] == ["door"]
    assert w.door_at["b"].stuck == 0.25
    assert w.walk_neighbours["b"] == ("a",)  # the door's own edge is not walkable
    assert w.tasks["T"].start == "a" and w.tasks["T"].goal == "d"
    assert w.area_of == {"a": 1, "b": 1, "c": 2, "d": 2}


def test_builtin_office() -> None:
    w = load_world(None)
    assert len(w.positions) == 19 and len(w.doors) == 6
    assert (w.step_limit, w.r_max) == (20, 20.0)
    assert {t: (w.tasks[t].start, w.tasks[t].goal) for t in "ABCD"} == {
        "A": ("p14", "p17"), "B": ("p14", "p18"), "C": ("p0", "p17"), "D": ("p0", "p18")}


CASES = [
    pytest.param(broken('["c", "d"]]', '["c", "zz"]]'), "world.adjacency[2]", "zz",
                 id="unknown-position"),
    pytest.param(broken('sides = ["b", "c"]', 'sides = ["b"]'), "doors.door.sides",
                 "exactly two", id="door-one-side"),
    pytest.param(broken('sides = ["b", "c"]', 'sides = ["b", "c", "d"]'), "doors.door.sides",
                 "exactly two", id="door-three-sides"),
    pytest.param(broken("success = 0.5", "success = 1.5"), "doors.door.success",
                 "[0, 1]", id="probability-above-1"),
    pytest.param(broken("stuck = 0.25", "stuck = -0.1"), "doors.door.stuck",
                 "[0, 1]", id="probability-below-0"),
    pytest.param(broken("stuck = 0.25", "stuck = 0.75"), "doors.door",
                 "success + stuck", id="success-plus-stuck"),
    pytest.param(broken('2 = ["c", "d"]', '2 = ["c", "nowhere"]'), "areas.2", "nowhere",
                 id="area-unknown-position"),
    pytest.param(broken('goal = "d"', 'goal = "p99"'), "tasks.T.goal", "p99",
                 id="task-unknown-position"),
    pytest.param(broken('start = "HOME"', 'start = "HOMEX"'), "tasks.T.start", "HOMEX",
                 id="task-unknown-landmark"),
]


@pytest.mark.parametrize(("text", "key", "detail"), CASES)
def test_errors_name_source_and_key(text: str, key: str, detail: str) -> None:
    with pytest.raises(WorldError) as err:
        parse_world(text, source="bad-world.toml")
    message = str(err.value)
    assert err.value.source == "bad-world.toml"
    assert err.value.key == key
    assert message.startswith(f"bad-world.toml: {key}: ")
    assert detail in message


@pytest.mark.parametrize(("text", "key", "detail"), CASES[:3])
def test_load_world_names_the_path(tmp_path: Path, text: str, key: str, detail: str) -> None:
    path = tmp_path / "building.toml"
    path.write_text(text, encoding="utf-8")
    with pytest.raises(WorldError, match=key.replace("[", r"\[").replace("]", r"\]")) as err:
        load_world(path)
    assert err.value.source == str(path)
    assert str(path) in str(err.value)


def test_bad_toml_names_the_file(tmp_path: Path) -> None:
    path = tmp_path / "garbled.toml"
    path.write_text(TINY + "\nthis is = = not toml\n", encoding="utf-8")
    with pytest.raises(WorldError, match="not valid TOML") as err:
        load_world(path)
    assert str(path) in str(err.value)
    assert "line" in str(err.value)  # tomllib says where


def test_missing_file_is_a_world_error(tmp_path: Path) -> None:
    with pytest.raises(WorldError, match="cannot read"):
        load_world(tmp_path / "absent.toml")


def test_load_world_from_file(tmp_path: Path) -> None:
    path = tmp_path / "tiny.toml"
    path.write_text(TINY, encoding="utf-8")
    w = load_world(path)
    assert w.source == str(path) and w.name == "tiny"
