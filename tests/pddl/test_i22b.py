"""Progress on slow work (issue 22 item 4): grounding and the true model's outcome rows
count their steps on :func:`~gdq_pddl.limits.slow_progress` bars."""

import numpy as np
import pytest
from tqdm import tqdm

from gdq_pddl.pddl import outcomes
from gdq_pddl.pddl.outcomes import reality_outcomes
from gdq_pddl.pddl.reachable import reachable_graph
from gdq_pddl.planning.base import PlanningProblem

SWITCHES = """(define (domain switches) (:requirements :typing :probabilistic-effects)
  (:types switch) (:predicates (on ?s - switch))
  (:action flip :parameters (?s - switch) :precondition (not (on ?s))
    :effect (probabilistic 0.9 (on ?s))))
"""

STRIPS = SWITCHES.replace("(probabilistic 0.9 (on ?s))", "(on ?s)").replace(
    ":probabilistic-effects", ":negative-preconditions")
WHEN = SWITCHES.replace("(probabilistic 0.9 (on ?s))", "(when (not (on ?s)) (on ?s))")


def switches(n: int) -> str:
    names = " ".join(f"s{i}" for i in range(n))
    goal = " ".join(f"(on s{i})" for i in range(n))
    return f"(define (problem sw) (:domain switches) (:objects {names} - switch) (:init) " \
        f"(:goal (and {goal})))"


def counted(bars: list[tqdm], desc: str) -> list[int]:
    return [bar.n for bar in bars if bar.desc.startswith(desc)]


@pytest.mark.parametrize("domain, steps", [(STRIPS, [7, 7]), (SWITCHES, [7, 7]),
                                           (WHEN, [7, 7])], ids=["strips", "ppddl", "when"])
def test_grounding_counts_every_ground_action(bars, domain, steps):
    # bindings, then ground actions: one grounder for every domain
    problem = PlanningProblem.from_texts(domain, switches(7), "d.pddl", "p.pddl")
    assert len(problem.learner_task.ops) == 7
    assert counted(bars, "grounding") == steps


def test_true_model_rows_count_their_chunks(bars, monkeypatch):
    task = PlanningProblem.from_texts(SWITCHES, switches(6), "d.pddl", "p.pddl").learner_task
    graph = reachable_graph(task)
    whole = reality_outcomes(graph)  # one chunk
    assert len(whole[0]) == 2 * 6 * 2**5  # each off switch of each state: flipped or not
    n_live = int((~graph.is_goal).sum())
    monkeypatch.setattr(outcomes, "OUTCOME_CHUNK", 10 * graph.offered.shape[1])
    bars.clear()
    pair, prob, fields = reality_outcomes(graph)  # 10 states a chunk
    [model] = [bar for bar in bars if bar.desc.startswith("true model")]
    assert model.n == model.total == -(-n_live // 10) > 1
    for a, b in zip([pair, prob, *fields], [whole[0], whole[1], *whole[2]], strict=True):
        assert a.dtype == b.dtype and np.array_equal(a, b)  # the chunks' rows are the whole's


def test_a_refusal_midway_clears_its_bar_before_the_message(bars):
    """Each slow step's bar is a ``with`` block: an error inside it closes the bar first
    (a closed tqdm bar is disabled), so the message is not printed over a bar."""
    from gdq_pddl.errors import PlanningError

    task = PlanningProblem.from_texts(SWITCHES, switches(6), "d.pddl", "p.pddl").learner_task
    with pytest.raises(PlanningError, match="more than 5 reachable states"):
        reachable_graph(task, max_states=5)
    [enumerating] = [bar for bar in bars if bar.desc.startswith("reachable states")]
    assert enumerating.disable  # closed
