"""The command line takes the shipped names the envs take (one resolver,
:func:`gdq_pddl.resources.resolve`), and ``gdq-pddl list`` shows them."""

from __future__ import annotations

import json
from pathlib import Path

import pytest

from gdq_pddl.errors import PlanningError
from gdq_pddl.resources import resolve, resolve_pddl, shipped_names
from tests.helpers import REPO_ROOT, cli


def test_names_resolve_to_the_shipped_files():
    assert resolve("domain", "keys").read_text() == (REPO_ROOT / "domains/keys.pddl").read_text()
    assert resolve("world", "office_robot").name == "office_robot.toml"
    assert resolve("dynamics", "office").name == "office.toml"  # a world is dynamics too
    assert resolve("problem", "sub/keys-2") == Path("sub/keys-2")  # a folder: a path
    domain, problem, dynamics = resolve_pddl("keys", "keys-2", None)
    assert (domain.name, problem.name, dynamics.name) == ("keys.pddl", "keys-2.pddl",
                                                          "keys.toml")


def test_an_existing_file_wins_over_a_shipped_name(tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)
    Path("keys").write_text("(define (domain mine))")
    assert resolve("domain", "keys") == Path("keys")
    assert resolve_pddl("keys", "keys-2", None)[2] is None  # a file gets no shipped dynamics


def test_an_unknown_name_lists_the_shipped_ones():
    with pytest.raises(PlanningError, match=r"problem 'keys-9': no such file, and no shipped "
                       r"problem of that name \(shipped: .*delivery-1, .*keys-2"):
        resolve("problem", "keys-9")


@pytest.mark.parametrize("argv,message", [
    (["plan", "--domain", "nosuch", "--problem", "keys-2"],
     "shipped: courier, cracking-blocks, delivery, keys"),
    (["run", "--problem", "nosuch"], "no shipped problem of that name"),
    (["run", "--task", "C", "--world", "nosuch"], "shipped: office, office_robot"),
    (["run", "--domain", "keys", "--problem", "keys-2", "--dynamics", "nosuch"],
     "no shipped dynamics"),
])
def test_cli_refuses_unknown_names_listing_the_shipped_ones(capsys, argv, message):
    code, out = cli(capsys, *argv)
    assert code == 2 and message in out and "Traceback" not in out


def test_plan_takes_shipped_names_and_the_domain_a_problem_names(capsys):
    by_files = cli(capsys, "plan", "--domain", REPO_ROOT / "domains/keys.pddl", "--problem",
                   REPO_ROOT / "problems/keys-2.pddl", "--json")
    assert cli(capsys, "plan", "--domain", "keys", "--problem", "keys-2", "--json") == by_files
    assert cli(capsys, "plan", "--problem", "keys-2", "--json") == by_files
    assert cli(capsys, "plan", "--world", "office_robot", "--task", "X")[0] == 0


def test_list_shows_every_shipped_name(capsys):
    code, out = cli(capsys, "list", "--json")
    shown = json.loads(out)
    assert code == 0
    assert shown["domains"] == shipped_names("domain")
    assert shown["problems"]["keys-ppddl-2"] == "keys-ppddl"
    assert shown["problems"]["task-c"] == "office"
    assert shown["dynamics"] == shipped_names("dynamics")
    assert shown["worlds"]["office"] == ["A", "B", "C", "D", "E", "X"]
    assert shown["planners"]["graph"] == "usable"
    code, text = cli(capsys, "list")
    assert code == 0 and "keys-ppddl-2" in text and "office_robot" in text
