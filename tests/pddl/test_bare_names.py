"""Names written without parentheses, as published IPPC domains write them: a 0-ary
predicate (``broken`` for ``(broken)``) wherever an atom may stand, and a 0-ary function
term (``reward`` for ``(reward)``, PDDL 2.1's ``<f-head> ::= <function-symbol>``) in a
reward or cost effect, an ``(= ...)`` of ``:init`` and ``:metric``. Each file is read as
its fully parenthesised twin (same lines), and a bare name that is not such a predicate
or function is still refused where it stands."""

from __future__ import annotations

import warnings

import pytest

from gdq_pddl import cli
from gdq_pddl.errors import PDDLError
from gdq_pddl.pddl import parse_domain, parse_problem
from gdq_pddl.pddl.ppddl import ground_ppddl

# A lamp that may break when switched; a broken lamp can be fixed. Bare 0-ary atoms in a
# precondition, a (not ...), a when condition and effect, a probabilistic effect, :init
# and the goal; bare (reward) in the costs and the metric.
BARE = """(define (domain lamp)
  (:requirements :probabilistic-effects :conditional-effects :rewards)
  (:predicates (on) (broken) (warned))
  (:action switch
    :precondition (not broken)
    :effect (and (decrease reward 2)
                 (when warned on)
                 (probabilistic 1/4 broken 3/4 (and on (not warned)))))
  (:action fix
    :precondition broken
    :effect (and (not broken) warned (decrease reward 5))))
(define (problem lamp-1) (:domain lamp)
  (:init warned)
  (:goal (and on (not broken)))
  (:goal-reward 10)
  (:metric maximize reward))
"""

PARENTHESISED = """(define (domain lamp)
  (:requirements :probabilistic-effects :conditional-effects :rewards)
  (:predicates (on) (broken) (warned))
  (:action switch
    :precondition (not (broken))
    :effect (and (decrease (reward) 2)
                 (when (warned) (on))
                 (probabilistic 1/4 (broken) 3/4 (and (on) (not (warned))))))
  (:action fix
    :precondition (broken)
    :effect (and (not (broken)) (warned) (decrease (reward) 5))))
(define (problem lamp-1) (:domain lamp)
  (:init (warned))
  (:goal (and (on) (not (broken))))
  (:goal-reward 10)
  (:metric maximize (reward)))
"""


def test_bare_zero_ary_atoms_and_function_terms_read_as_parenthesised():
    bare, full = parse_domain(BARE, "l.pddl"), parse_domain(PARENTHESISED, "l.pddl")
    assert bare == full
    assert [a.cost for a in bare.actions] == [(2.0,), (5.0,)]
    problem = parse_problem(BARE, bare, "l.pddl")
    assert problem == parse_problem(PARENTHESISED, full, "l.pddl")
    assert problem.metric == "maximize (reward)" and problem.goal_reward == 10.0
    assert sorted(map(str, problem.init)) == ["(warned)"]
    # switch from (warned): the when fires in both outcomes (on), and the 3/4 outcome
    # also takes (warned) away; 1/4 breaks the lamp
    learner, _ = ground_ppddl(bare, problem)
    switch = next(op for op in learner.ops if op.name == "(switch)")
    assert sorted(o.probability for o in switch.outcomes) == [0.25, 0.75]


def test_bare_total_cost_in_an_effect_init_and_metric():
    text = """(define (domain d) (:requirements :action-costs)
      (:predicates (done)) (:functions (total-cost) (fuel) - number)
      (:action a :effect (and (done) (increase total-cost fuel))))
    (define (problem p) (:domain d) (:init (= total-cost 0) (= fuel 3)) (:goal done)
      (:metric minimize total-cost))"""
    domain = parse_domain(text)
    assert [str(t) for t in domain.actions[0].cost] == ["(fuel)"]
    problem = parse_problem(text, domain)
    assert problem.metric == "minimize (total-cost)" and problem.values["(fuel)"] == 3.0
    assert [str(lit.atom) for lit in problem.goal] == ["(done)"]


@pytest.mark.parametrize("effect, message", [
    ("(and (on ?r) room)", r"^d.pddl:4: expected an effect, found 'room'"),
    ("(and (on ?r) ready)", r"^d.pddl:4: expected an effect, found 'ready'"),
    ("(decrease score 1)", r"^d.pddl:4: action go: expected \(decrease \(total-cost\) X\) "
                           r"or \(decrease \(reward\) X\)"),
])
def test_a_bare_name_that_is_no_zero_ary_predicate_or_cost_is_refused(effect, message):
    # (on ?r) takes an argument and room is a type: neither may stand bare; 'ready' is
    # not declared at all; 'score' is no cost fluent
    text = f"""(define (domain d) (:types room) (:predicates (on ?r - room))
      (:functions (score) - number)
      (:action go :parameters (?r - room)
        :effect {effect}))"""
    with pytest.raises(PDDLError, match=message):
        parse_domain(text, "d.pddl")


def test_a_last_define_missing_only_its_final_parenthesis_is_read_with_a_warning():
    # as pddlgym's navigation2-10 domains are shipped; anything else left open at the end
    # is still an error (an action cut short, a second form open inside the define)
    cut = PARENTHESISED[:PARENTHESISED.index("(define (problem")].rstrip()[:-1] + "\n"
    with pytest.warns(UserWarning, match=r"^l.pddl:1: this \(define \.\.\.\) is never "
                                         r"closed; read as if the file ended with its '\)'"):
        assert parse_domain(cut, "l.pddl") == parse_domain(PARENTHESISED, "l.pddl")
    inner = cut.replace("(broken) (warned))", "(broken) (warned)")
    with pytest.raises(PDDLError, match=r"^l.pddl:3: expected '\)': this '\(' is never "
                                        "closed"):
        parse_domain(inner, "l.pddl")
    action_cut = cut[:cut.index(":effect (and (not (broken)) (warned)")]
    with pytest.raises(PDDLError, match="never closed"):
        parse_domain(action_cut, "l.pddl")


def test_the_command_line_runs_it_and_shows_the_warning_as_one_line(capsys, tmp_path):
    cut = PARENTHESISED[:PARENTHESISED.index("(define (problem")].rstrip()[:-1] + "\n"
    domain, problem = tmp_path / "lamp.pddl", tmp_path / "lamp-1.pddl"
    domain.write_text(cut, encoding="utf-8")
    problem.write_text(PARENTHESISED[PARENTHESISED.index("(define (problem"):],
                       encoding="utf-8")
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        code = cli.main(["run", "--domain", str(domain), "--problem", str(problem),
                         "--episodes", "2", "--runs", "1", "--method", "Q-learning",
                         "--jobs", "1", "--no-report", "--out", str(tmp_path / "out")])
    out = capsys.readouterr()
    assert code == 0, out.out + out.err
    shown = {cli._format_warning(w.message, w.category, w.filename, w.lineno)
             for w in caught if "never closed" in str(w.message)}
    # one line naming the user's file and line, not the library line that warned
    assert shown == {f"gdq-pddl: warning: {domain}:1: this (define ...) is never closed; "
                     "read as if the file ended with its ')'\n"}
