"""``--explore auto`` gives up an enumeration whose breadth-first levels keep growing
past the table budget (:func:`~gdq_pddl.pddl.reachable.projected_states`) and goes
online, where it used to enumerate until past the budget (manytireworld_test problem0:
12.9 million states and over 3 minutes before going online); ``--explore enumerate``
never gives up early."""

from math import comb

import pytest

from gdq_pddl.cli import main
from gdq_pddl.errors import TooManyStates
from gdq_pddl.pddl import reachable
from gdq_pddl.pddl.reachable import GROWTH_LEVELS, projected_states, reachable_graph
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
    with pytest.raises(TooManyStates, match=r"bits.pddl: likely more than 3,000 reachable "
                       r"states \(511 found so far.*levels 3 to 8: 8, 16, 32, 64, 128, 256, "
                       r"3 more levels growing as these did would make 4,095 "
                       r"\(given up early") as early:
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
    assert main([*common, "--explore", "enumerate", "--out", str(tmp_path / "all")]) == 0
    err = capsys.readouterr().err
    assert "likely" not in err and "explored online" not in err
