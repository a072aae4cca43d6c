"""The PDDL reader, the grounder and the generated office problems."""

from __future__ import annotations

import os
import sys

import pytest

from gdq_pddl.errors import PDDLError
from gdq_pddl.pddl import ground, parse_domain, parse_problem
from gdq_pddl.resources import domain_text, problem_text
from gdq_pddl.world import load_world
from gdq_pddl.world_types import office_problem
from tests.helpers import BACKGROUND

TINY_DOMAIN = """(define (domain tiny)
  (:requirements :strips :typing)
  (:types room)
  (:predicates (at ?r - room) (link ?a ?b - room))
  (:action move :parameters (?a ?b - room)
    :precondition (and (at ?a) (link ?a ?b))
    :effect (and (at ?b) (not (at ?a)))))
"""

TINY_PROBLEM = """(define (problem t) (:domain tiny)
  (:objects r1 r2 r3 - room)
  (:init (at r1) (link r1 r2) (link r2 r3))
  (:goal (at r3)))
"""


def test_tiny_domain_grounds_to_its_static_links():
    task = ground(parse_domain(TINY_DOMAIN), parse_problem(TINY_PROBLEM, parse_domain(TINY_DOMAIN)))
    assert sorted(op.name for op in task.ops) == ["(move r1 r2)", "(move r2 r3)"]
    assert task.atoms(task.init) == {"(at r1)"}
    assert task.goal_possible


@pytest.mark.parametrize(("text", "line", "expected"), [
    (TINY_DOMAIN[:TINY_DOMAIN.index(":effect")], 5, "never closed"),
    (TINY_DOMAIN.replace("(link ?a ?b))\n", "(link ?a ?b)\n"), 6, "never closed"),
    (TINY_DOMAIN.replace("(link ?a ?b))", "(lnk ?a ?b))"), 6, "unknown predicate 'lnk'"),
    (TINY_DOMAIN.replace("(at ?b)", "(at ?c)"), 7, "unknown variable '?c'"),
    (TINY_DOMAIN.replace(":typing", ":typing :fluentz"), 2, "requirement :fluentz"),
    (TINY_DOMAIN.replace("(at ?b)", "(at ?a ?b)"), 7, "takes 1 argument(s), got 2"),
    (TINY_DOMAIN.replace("- room)", "- rom)", 1), 4, "unknown type 'rom'"),
    (TINY_DOMAIN + ")", 8, "unexpected ')'"),
])
def test_domain_errors_name_file_line_and_expectation(text, line, expected):
    with pytest.raises(PDDLError) as err:
        parse_domain(text, "my.pddl")
    assert err.value.source == "my.pddl"
    assert err.value.line == line
    assert expected in str(err.value)
    assert str(err.value).startswith(f"my.pddl:{line}: ")


@pytest.mark.parametrize(("text", "expected"), [
    (TINY_PROBLEM.replace("(:domain tiny)", "(:domain other)"), "for domain 'other'"),
    (TINY_PROBLEM.replace("(link r2 r3)", "(link r2 r9)"), "unknown object 'r9'"),
    (TINY_PROBLEM.replace("(at r3)", "(near r3)"), "unknown predicate 'near'"),
    (TINY_PROBLEM.replace("r1 r2 r3 - room", "r1 r2 r3 - hall"), "unknown type 'hall'"),
])
def test_problem_that_does_not_match_the_domain(text, expected):
    with pytest.raises(PDDLError, match=expected):
        parse_problem(text, parse_domain(TINY_DOMAIN), "p.pddl")


def test_office_state_space_has_897_reachable_states():
    world = load_world()
    domain = parse_domain(domain_text())
    task = ground(domain, parse_problem(office_problem(world, world.task("C")), domain))
    seen, frontier = {task.init}, [task.init]
    while frontier:
        for _, t in task.successors(frontier.pop()):
            if t not in seen:
                seen.add(t)
                frontier.append(t)
    assert len(seen) == 897


@pytest.mark.parametrize("name", ["A", "B", "C", "D", "E", "X"])
def test_shipped_problems_match_the_world_file(name):
    """Knowledge agrees with reality: problems/ is `gdq-pddl problem --all` output."""
    world = load_world()
    assert problem_text(name) == office_problem(world, world.task(name)), (
        f"problems/task-{name.lower()}.pddl drifted from the world file: regenerate it with "
        "`gdq-pddl problem --all --out problems`")


def test_knowledge_and_reality_agree_on_every_move():
    """Each ground PDDL action is possible in the simulator, and vice versa."""
    from gdq_pddl.abstraction import OfficeAbstraction
    from gdq_pddl.envs.model import compile_model, full_state

    world = load_world()
    domain = parse_domain(domain_text())
    task = ground(domain, parse_problem(office_problem(world, world.task("C")), domain))
    model = compile_model(world)
    abstraction = OfficeAbstraction(world)
    for state in range(1 << len(world.doors)):
        for p in world.positions:
            open_doors = frozenset(d.name for i, d in enumerate(world.doors) if state >> i & 1)
            atoms = {f"(at {p})"} | {f"({'open' if d.name in open_doors else 'closed'} "
                                     f"{d.name})" for d in world.doors}
            planned = {abstraction.learner_action(op.name): abstraction.learner_state(
                task.atoms(t)) for op, t in task.successors(task.mask(atoms))}
            fs = full_state(world, p, open_doors)
            for a in range(model.n_actions):
                i = fs * model.n_actions + a
                lo, hi = model.ptr[i], model.ptr[i + 1]
                likeliest = model.next[lo + int(model.prob[lo:hi].argmax())]
                moved = hi - lo > 1 or likeliest != fs
                assert moved == (a in planned), (p, open_doors, abstraction.spaces.action_name(a))
                if a in planned:
                    assert model.obs_of[likeliest] == planned[a]


HASH_SEED_SCRIPT = """
import numpy as np
from gdq_pddl.pddl import ground, parse_domain, parse_problem
from gdq_pddl.resources import data_file
from gdq_pddl.envs.pddl_env import PDDLEnv
from gdq_pddl.learners import make_learner, run_episodes
from gdq_pddl.learners.context import pddl_task_context
d = data_file("domains", "keys.pddl").read_text()
p = data_file("problems", "keys-1.pddl").read_text()
domain = parse_domain(d)
print([op.name for op in ground(domain, parse_problem(p, domain)).ops])
env = PDDLEnv(str(data_file("domains", "keys.pddl")), str(data_file("problems", "keys-1.pddl")),
              str(data_file("dynamics", "keys.toml")))
env.reset(seed=0)
learner = make_learner("gdq", pddl_task_context(env.instance), variant="code")
print(run_episodes(learner, env, 30, np.random.default_rng(0)).returns.tolist())
"""


def start_hash_seeds(item=None) -> list:
    """The script under three hash seeds, queued when collection ends to run beside the
    other tests (``tests.helpers.Background``)."""
    return [BACKGROUND.run(f"pddl hash seed {seed}", [sys.executable, "-c", HASH_SEED_SCRIPT],
                           env=dict(os.environ, PYTHONHASHSEED=seed), timeout=300)
            for seed in ("1", "2", "3")]


@pytest.mark.background.with_args(start_hash_seeds)
def test_grounding_and_a_pddl_run_do_not_depend_on_the_hash_seed():
    """Ground action order (a PDDL env's action indices) must be the same in every process."""
    outs = [future.result() for future in start_hash_seeds()]
    for out in outs:
        assert out.returncode == 0, out.stderr[-2000:]
    assert outs[0].stdout == outs[1].stdout == outs[2].stdout
