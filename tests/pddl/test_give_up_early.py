"""``--explore auto`` gives up an enumeration whose breadth-first levels keep growing
past the table budget (:func:`~gdq_pddl.pddl.reachable.projected_states`) and goes
online, where it used to enumerate until past the budget (manytireworld_test problem0:
12.9 million states and over 3 minutes before going online); ``--explore enumerate``
never gives up early. It gives up only on a level that grew as the levels before it
projected (:func:`~gdq_pddl.pddl.reachable.backed_by`): a teleport that fills the space
at level 2, and bursts followed by plateaus, are enumerated (issue 40 item 5)."""

import json
from math import comb

import numpy as np
import pytest

from gdq_pddl.cli import main
from gdq_pddl.errors import TooManyStates
from gdq_pddl.pddl import reachable
from gdq_pddl.pddl.reachable import (
    GROWTH_LEVELS,
    PROJECTION_SLACK,
    backed_by,
    projected_levels,
    projected_states,
    reachable_graph,
)
from gdq_pddl.planning.base import PlanningProblem

# n bits written one at a time, each 0 or 1: level k holds 2**k states, until level n
BITS = """(define (domain bits) (:requirements :strips :probabilistic-effects)
  (:predicates (turn ?i) (next ?i ?j) (one ?i) (zero ?i))
  (:action write-zero :parameters (?i ?j) :precondition (and (turn ?i) (next ?i ?j))
    :effect (probabilistic 0.9 (and (zero ?i) (turn ?j) (not (turn ?i)))))
  (:action write-one :parameters (?i ?j) :precondition (and (turn ?i) (next ?i ?j))
    :effect (probabilistic 0.9 (and (one ?i) (turn ?j) (not (turn ?i))))))
"""


def bits(n: int) -> str:
    names = [f"b{i}" for i in range(n + 1)]
    links = " ".join(f"(next {a} {b})" for a, b in zip(names, names[1:], strict=False))
    return (f"(define (problem bits-{n}) (:domain bits) (:objects {' '.join(names)})\n"
            f"  (:init (turn b0) {links}) (:goal (and (turn b{n}) (one b0))))")


def test_no_projection_before_three_levels_or_after_an_empty_one():
    assert projected_states([1]) == projected_states([1, 5]) == 0
    assert projected_states([1, 5, 0]) == 0


def test_steady_growth_is_projected_geometrically():
    levels = [1, 3, 9, 27]
    assert projected_states(levels) == sum(levels) + sum(27 * 3**j
                                                         for j in range(1, GROWTH_LEVELS + 1))


@pytest.mark.parametrize("n", range(6, 34))
def test_independent_switches_are_never_projected_past_their_states(n):
    # level k of n switches holds comb(n, k) states: growth slows at every level
    levels = [comb(n, k) for k in range(n + 1)]
    worst = max(projected_states(levels[:k]) for k in range(3, n + 2))
    assert 2**n <= worst <= 1.02 * 2**n


def test_growth_that_keeps_on_is_given_up_early(monkeypatch):
    task = PlanningProblem.from_texts(BITS, bits(14)).learner_task
    monkeypatch.setattr(reachable, "TABLE_BUDGET", 3000 * reachable.state_bytes(2))
    with pytest.raises(TooManyStates) as full:
        reachable_graph(task, source="bits.pddl")
    # the figures agree: 4,095 states projected past the cap of 3,000, their tables 4,095
    # x 320 bytes past the budget of 3,000 x 320
    with pytest.raises(TooManyStates, match=r"bits.pddl: likely more than 3,000 reachable "
                       r"states, the budget's cap \(given up early after breadth-first level "
                       r"8, 511 states found, up to 2 applicable ground actions a state\); "
                       r"states of breadth-first levels 3 to 8: 8, 16, 32, 64, 128, 256; "
                       r"level 8 grew as projected \(256 states against 256 projected from "
                       r"the levels before it\), and 3 more levels growing as these did would "
                       r"make 4,095 states, whose tables would need about 1.31 MB \(160 bytes "
                       r".*past the budget of 960 kB: .*TABLE_BUDGET = 960,000 .*--explore "
                       r"enumerate") as early:
        reachable_graph(task, source="bits.pddl", give_up_early=True)
    assert "more than 3,000 reachable states (4,095 found so far" in str(full.value)
    assert "likely" not in str(full.value) and "likely" in str(early.value)


def test_a_budget_that_fits_is_not_given_up_on(monkeypatch):
    # but for growth that stops abruptly at its widest level, past the budget's reach:
    # projected, that is a doomed enumeration (auto goes online; enumerate does not give up)
    task = PlanningProblem.from_texts(BITS, bits(9)).learner_task
    whole = reachable_graph(task).n_states
    assert whole == 2**10 - 1
    monkeypatch.setattr(reachable, "TABLE_BUDGET", 16 * whole * reachable.state_bytes(2))
    assert reachable_graph(task, give_up_early=True).n_states == whole
    monkeypatch.setattr(reachable, "TABLE_BUDGET", 2 * whole * reachable.state_bytes(2))
    with pytest.raises(TooManyStates, match="likely"):
        reachable_graph(task, give_up_early=True)
    assert reachable_graph(task).n_states == whole
    assert reachable_graph(task, max_states=whole, give_up_early=True).n_states == whole


def test_auto_gives_up_early_and_enumerate_does_not(tmp_path, capsys, monkeypatch):
    domain, problem = tmp_path / "bits.pddl", tmp_path / "bits-9.pddl"
    domain.write_text(BITS)
    problem.write_text(bits(9))
    monkeypatch.setattr(reachable, "TABLE_BUDGET", 2 * 1023 * reachable.state_bytes(2))
    common = ["run", "--domain", str(domain), "--problem", str(problem), "--method", "GDQ",
              "--episodes", "3", "--runs", "1", "--jobs", "1", "--no-report"]
    assert main([*common, "--out", str(tmp_path / "auto")]) == 0
    err = capsys.readouterr().err
    assert f"{problem}: likely more than" in err and "explored online" in err
    assert "level 7 grew as projected (128 states against 128 projected" in err
    assert main([*common, "--explore", "enumerate", "--out", str(tmp_path / "all")]) == 0
    err = capsys.readouterr().err
    assert "likely" not in err and "explored online" not in err


# A grid crossed right and up, where a move may kill; a dead walker teleports to any cell
# (IPPC-2008's rectangle tireworld does so): every cell, dead, is known at level 2, and
# the levels after hold the few live cells one move further.
GHOST = """(define (domain ghost-grid)
  (:requirements :typing :negative-preconditions :probabilistic-effects)
  (:types num)
  (:predicates (x ?n - num) (y ?n - num) (next ?a ?b - num) (alive))
  (:action right :parameters (?a ?b ?c - num)
    :precondition (and (alive) (x ?a) (y ?c) (next ?a ?b))
    :effect (probabilistic 0.9 (and (not (x ?a)) (x ?b)) 0.1 (not (alive))))
  (:action up :parameters (?a ?b ?c - num)
    :precondition (and (alive) (x ?c) (y ?a) (next ?a ?b))
    :effect (probabilistic 0.9 (and (not (y ?a)) (y ?b)) 0.1 (not (alive))))
  (:action teleport :parameters (?a ?b ?c ?d - num)
    :precondition (and (not (alive)) (x ?a) (y ?b))
    :effect (and (not (x ?a)) (not (y ?b)) (x ?c) (y ?d))))
"""


def ghost(n: int) -> str:
    names = [f"n{i}" for i in range(n)]
    links = " ".join(f"(next {a} {b})" for a, b in zip(names, names[1:], strict=False))
    return (f"(define (problem ghost-{n}) (:domain ghost-grid) "
            f"(:objects {' '.join(names)} - num)\n  (:init (alive) (x n0) (y n0) {links})\n"
            f"  (:goal (and (alive) (x n{n - 1}) (y n{n - 1}))))")


def bursts(k: int) -> tuple[str, str]:
    """A walk along steps s0 .. s9 where s2 draws one of ``k`` colours and s6 one of ``k``
    shapes: levels 1, 1, 1, k, k, k, k, k^2, k^2, k^2 (bursts, then plateaus)."""
    colours, shapes = [f"c{i}" for i in range(k)], [f"h{i}" for i in range(k)]

    def draw(what: str, names: list[str]) -> str:
        return " ".join(f"{1 / k:g} ({what} {name})" for name in names)
    domain = f"""(define (domain bursts) (:requirements :typing :probabilistic-effects)
  (:types step thing)
  (:constants {' '.join(colours + shapes)} - thing)
  (:predicates (at ?s - step) (next ?s ?t - step) (plain ?s - step) (colour-step ?s - step)
               (shape-step ?s - step) (colour ?c - thing) (shape ?c - thing))
  (:action walk :parameters (?s ?t - step) :precondition (and (at ?s) (next ?s ?t) (plain ?s))
    :effect (and (not (at ?s)) (at ?t)))
  (:action paint :parameters (?s ?t - step)
    :precondition (and (at ?s) (next ?s ?t) (colour-step ?s))
    :effect (and (not (at ?s)) (at ?t) (probabilistic {draw("colour", colours)})))
  (:action carve :parameters (?s ?t - step)
    :precondition (and (at ?s) (next ?s ?t) (shape-step ?s))
    :effect (and (not (at ?s)) (at ?t) (probabilistic {draw("shape", shapes)}))))
"""
    steps = [f"s{i}" for i in range(10)]
    links = " ".join(f"(next {a} {b})" for a, b in zip(steps, steps[1:], strict=False))
    kinds = " ".join("(colour-step s2)" if s == "s2" else "(shape-step s6)" if s == "s6"
                     else f"(plain {s})" for s in steps)
    problem = (f"(define (problem bursts-{k}) (:domain bursts) (:objects {' '.join(steps)} "
               f"- step)\n  (:init (at s0) {links} {kinds}) (:goal (at s9)))")
    return domain, problem


def _sizes(graph) -> list[int]:
    return np.bincount(graph.depth).tolist()


def test_a_teleport_that_fills_the_space_at_level_2_is_not_projected(monkeypatch):
    # level 2 holds every cell (dead): 34 times level 1, which the old projection read as
    # growth to go on, 4 million states from 106; level 3 then holds 4 states
    task = PlanningProblem.from_texts(GHOST, ghost(10)).learner_task
    whole = reachable_graph(task)
    sizes = _sizes(whole)
    assert whole.n_states == 200 and sizes[:4] == [1, 3, 102, 4]
    assert whole.offered.shape[1] == 100  # a dead walker's teleports
    assert projected_states(sizes[:3]) > 4_000_000 and backed_by(sizes[:3]) is None
    monkeypatch.setattr(reachable, "TABLE_BUDGET", 2 * whole.n_states * whole.offered.shape[1]
                        * reachable.PAIR_BYTES)
    assert reachable_graph(task, give_up_early=True).n_states == 200


def test_bursts_then_plateaus_are_enumerated(monkeypatch):
    domain, problem = bursts(10)
    task = PlanningProblem.from_texts(domain, problem).learner_task
    whole = reachable_graph(task)
    sizes = _sizes(whole)
    assert sizes == [1, 1, 1, 10, 10, 10, 10, 100, 100, 100]
    # each burst, and the plateau after it, is no level that grew as projected: only
    # level 2 (the walk) and level 6 (the third level of the first plateau) are
    assert [k - 1 for k in range(3, 11) if backed_by(sizes[:k]) is not None] == [2, 6]
    assert projected_states(sizes[:4]) > 11_000 and projected_states(sizes[:8]) > 100_000
    monkeypatch.setattr(reachable, "TABLE_BUDGET", 2 * whole.n_states * reachable.PAIR_BYTES)
    assert reachable_graph(task, give_up_early=True).n_states == whole.n_states == 343


def test_only_a_level_within_the_slack_of_its_projection_backs_one():
    assert backed_by([1, 5]) is None  # nothing projected it
    assert backed_by([1, 3, 9]) == 9 and backed_by([1, 3, 9 * PROJECTION_SLACK]) == 9
    assert backed_by([1, 3, 9 / PROJECTION_SLACK]) == 9
    assert backed_by([1, 3, 19]) is None and backed_by([1, 3, 4]) is None
    assert projected_levels([1, 3, 9], 2) == [27, 81]
    assert projected_levels([1, 4, 8], 2) == [8, 4]  # growth halved: halves again


def test_a_teleport_grid_runs_enumerated_with_v_star_under_auto(tmp_path, capsys, monkeypatch):
    domain, problem = tmp_path / "ghost.pddl", tmp_path / "ghost-10.pddl"
    domain.write_text(GHOST)
    problem.write_text(ghost(10))
    monkeypatch.setattr(reachable, "TABLE_BUDGET", 2 * 200 * 100 * reachable.PAIR_BYTES)
    out = tmp_path / "auto"
    assert main(["run", "--domain", str(domain), "--problem", str(problem), "--method", "GDQ",
                 "--episodes", "3", "--runs", "1", "--jobs", "1", "--no-report",
                 "--out", str(out)]) == 0
    assert "explored online" not in capsys.readouterr().err
    facts = json.loads((out / "optimal.json").read_text())
    assert next(iter(facts.values()))["states"] == 200
