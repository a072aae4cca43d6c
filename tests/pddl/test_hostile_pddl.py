"""Hostile PDDL (issue 19): characters no name may have, nesting past any real domain,
declarations given twice or in a cycle, misspelled sections and requirements, and a
byte-order mark. Each is refused with one line naming the file and the line (a
:class:`~gdq_pddl.errors.PDDLError`), or read correctly; never dropped in silence."""

from __future__ import annotations

import pytest

from gdq_pddl.cli import main
from gdq_pddl.errors import PDDLError
from gdq_pddl.pddl import ground, parse_domain, parse_problem, read_domain, read_problem
from gdq_pddl.pddl.ppddl import ground_ppddl
from gdq_pddl.pddl.sexpr import MAX_DEPTH

# A lamp that a flaky switch turns on (0.8) or breaks (0.2); a spare switch always works.
LAMP_DOMAIN = """(define (domain lamp)
  (:requirements :strips :typing :probabilistic-effects)
  (:types lamp switch)
  (:predicates (on ?l - lamp) (wired ?s - switch ?l - lamp) (broken ?s - switch))
  (:action flip
    :parameters (?s - switch ?l - lamp)
    :precondition (and (wired ?s ?l) (not (broken ?s)))
    :effect (probabilistic 0.8 (on ?l) 0.2 (broken ?s)))
  (:action press
    :parameters (?s - switch ?l - lamp)
    :precondition (wired ?s ?l)
    :effect (on ?l)))
"""
LAMP_PROBLEM = """(define (problem lamp-1) (:domain lamp)
  (:objects l1 - lamp s1 s2 - switch)
  (:init (wired s1 l1))
  (:goal (on l1)))
"""


def edit(text: str, old: str, new: str) -> str:
    assert old in text, old
    return text.replace(old, new, 1)


def refused_at(fn, source: str, line: int, *words: str) -> str:
    """Run ``fn``; it must raise one-line PDDLError ``source:line: ...`` with ``words``."""
    with pytest.raises(PDDLError) as err:
        fn()
    text = str(err.value)
    assert text.startswith(f"{source}:{line}: "), text
    assert "\n" not in text, text
    for word in words:
        assert word in text, f"{word!r} not in {text!r}"
    return text


def domain_refused(text: str, line: int, *words: str) -> str:
    return refused_at(lambda: parse_domain(text, "d.pddl"), "d.pddl", line, *words)


def problem_refused(text: str, line: int, *words: str, domain: str = LAMP_DOMAIN) -> str:
    parsed = parse_domain(domain, "d.pddl")
    return refused_at(lambda: parse_problem(text, parsed, "p.pddl"), "p.pddl", line, *words)


def test_the_lamp_reads_and_grounds():
    domain = parse_domain(LAMP_DOMAIN)
    learner, _ = ground_ppddl(domain, parse_problem(LAMP_PROBLEM, domain))
    assert sorted(op.name for op in learner.ops) == ["(flip s1 l1)", "(press s1 l1)"]
    flip = next(op for op in learner.ops if op.name == "(flip s1 l1)")
    assert [o.probability for o in flip.outcomes] == [0.8, 0.2]


# --- characters --------------------------------------------------------------------------

@pytest.mark.parametrize(("old", "new", "line", "char"), [
    ("(:action press", "(:action pr#ess", 9, "'#'"),  # the case: no longer dropped
    ("(:action flip", "(:action flip#1", 5, "'#'"),
    ("(on ?l - lamp)", "(on# ?l - lamp)", 4, "'#'"),
    ("(:types lamp switch)", "(:types lamp switch é)", 3, "'é'"),
    ("(:types lamp switch)", "(:types lamp swi,tch)", 3, "','"),
    ("(wired ?s ?l) (not", "(wired ?s ?l) (no\"t", 7, "'\"'"),
    ("(on ?l)))", "(on ?l=))))", 12, "'='"),
    ("(:action press", "(:action pre?ss", 9, "'?'"),
])
def test_a_character_no_name_may_have_is_refused_where_it_stands(old, new, line, char):
    text = domain_refused(edit(LAMP_DOMAIN, old, new), line, char, "cannot be part of a name")
    if char == "'#'":
        assert "a comment starts with ';'" in text


def test_a_hash_in_an_object_name_is_refused_in_the_problem():
    problem_refused(edit(LAMP_PROBLEM, "s1 s2", "s1 s#2"), 2, "'#'")


@pytest.mark.parametrize(("old", "new", "line", "what"), [
    ("(:action press", "(:action 2press", 9, "an action name"),
    ("(:types lamp switch)", "(:types lamp _switch)", 3, "a name"),
    ("(domain lamp)", "(domain 1/2)", 1, "a domain name"),
    ("(on ?l - lamp)", "(?on ?l - lamp)", 4, "a predicate name"),
    (":parameters (?s - switch ?l - lamp)\n    :precondition (and",
     ":parameters (?s - switch ?-l - lamp)\n    :precondition (and", 6, "a variable"),
])
def test_a_symbol_that_is_not_a_name_is_refused_where_a_name_is_expected(old, new, line,
                                                                          what):
    domain_refused(edit(LAMP_DOMAIN, old, new), line, f"expected {what}")


def test_a_problem_name_may_start_with_a_digit_as_a_world_name_may():
    domain = parse_domain(LAMP_DOMAIN)
    assert parse_problem(edit(LAMP_PROBLEM, "lamp-1", "3rooms-c"), domain).name == "3rooms-c"
    problem_refused(edit(LAMP_PROBLEM, "lamp-1", "../x"), 1, "a problem name",
                    "letter or digit")


def test_a_comment_may_follow_a_name_without_a_space():
    text = edit(LAMP_DOMAIN, "(:types lamp switch)", "(:types lamp switch;the kinds\n)")
    assert parse_domain(text).types == {"object": None, "lamp": "object", "switch": "object"}


# --- nesting -----------------------------------------------------------------------------

def nested(depth: int, inner: str) -> str:
    return "(and " * depth + inner + ")" * depth


@pytest.mark.parametrize("where", ["precondition", "effect", "goal", "not"])
def test_nesting_past_the_limit_is_refused_not_a_recursion_error(where):
    deep = 10_000
    if where == "goal":
        problem_refused(edit(LAMP_PROBLEM, "(:goal (on l1))", f"(:goal {nested(deep, '(on l1)')})"),
                        4, f"nested more than {MAX_DEPTH} levels")
        return
    if where == "precondition":
        text = edit(LAMP_DOMAIN, ":precondition (wired ?s ?l)",
                    f":precondition {nested(deep, '(wired ?s ?l)')}")
    elif where == "effect":
        text = edit(LAMP_DOMAIN, ":effect (on ?l)))", f":effect {nested(deep, '(on ?l)')}))")
        domain_refused(text, 12, f"nested more than {MAX_DEPTH} levels")
        return
    else:
        text = edit(LAMP_DOMAIN, ":precondition (wired ?s ?l)",
                    ":precondition " + "(not " * deep + "(wired ?s ?l)" + ")" * deep)
    domain_refused(text, 11, f"nested more than {MAX_DEPTH} levels")


def test_nesting_up_to_the_limit_parses_and_grounds():
    """Every level the reader accepts, the later stages walk without running out of
    stack: the deepest precondition, effect and goal the limit allows."""
    room = MAX_DEPTH - 6  # define, action, :precondition's form and the atom itself
    domain_text = edit(edit(LAMP_DOMAIN, ":precondition (wired ?s ?l)",
                            f":precondition {nested(room, '(wired ?s ?l)')}"),
                       ":effect (on ?l)))", f":effect {nested(room, '(on ?l)')}))")
    problem_text = edit(LAMP_PROBLEM, "(:goal (on l1))", f"(:goal {nested(room, '(on l1)')})")
    domain = parse_domain(domain_text)
    learner, _ = ground_ppddl(domain, parse_problem(problem_text, domain))
    assert sorted(op.name for op in learner.ops) == ["(flip s1 l1)", "(press s1 l1)"]
    assert learner.atoms(learner.goal_pos) == {"(on l1)"}


# --- declarations --------------------------------------------------------------------------

@pytest.mark.parametrize(("old", "new", "line", "words"), [
    ("(:types lamp switch)", "(:types lamp - switch switch - lamp)", 3,
     ("cycle", "lamp - switch - lamp")),
    ("(:types lamp switch)", "(:types lamp - lamp switch)", 3, ("cycle", "lamp - lamp")),
    ("(:types lamp switch)", "(:types lamp switch\n lamp)", 4,
     ("type lamp is declared twice", "first at line 3")),
    ("(:types lamp switch)", "(:types lamp switch object - lamp)", 3, ("root type",)),
    (":parameters (?s - switch ?l - lamp)\n    :precondition (and",
     ":parameters (?s - switch ?s - lamp)\n    :precondition (and", 6,
     ("action flip: parameter ?s is declared twice",)),
    ("(wired ?s - switch ?l - lamp)", "(wired ?s - switch ?s - lamp)", 4,
     ("predicate wired: parameter ?s is declared twice",)),
    ("(broken ?s - switch))", "(broken ?s - switch)\n  (on ?x - switch))", 5,
     ("predicate on is declared twice", "first at line 4")),
    ("(broken ?s - switch))", "(broken ?s - switch) (and ?x))", 4, ("cannot be named and",)),
    ("(:action press", "(:action flip", 9, ("action flip is declared twice",
                                            "first at line 5")),
    ("(:action press", "(:actionpress", 9, ("unknown section :actionpress", ":action")),
    ("(:action press", "(:action0 press", 9, ("unknown section :action0",)),
    ("(:types lamp switch)", "(:types lamp switch)\n  (:constants c1 c2 c1 - lamp)", 4,
     ("constant c1 is declared twice",)),
    ("(:requirements :strips", "(:requirements :stirps", 2, ("unknown requirement :stirps",)),
    ("    :effect (on ?l)))", "    :effect (on ?l)\n    :effect (on ?l)))", 13,
     ("action press: :effect is given twice", "first at line 12")),
    ("(:types lamp switch)", "(:types lamp switch)\n  (:types bulb)", 4,
     ("duplicate section :types", "first at line 3")),
])
def test_declarations_that_cannot_be_meant_are_refused(old, new, line, words):
    domain_refused(edit(LAMP_DOMAIN, old, new), line, *words)


def test_functions_declared_twice_or_with_a_repeated_parameter():
    base = edit(LAMP_DOMAIN, "(:action flip",
                "(:functions (len ?s - switch) (len ?l - lamp))\n  (:action flip")
    domain_refused(base, 5, "function len is declared twice")
    domain_refused(edit(base, "(len ?s - switch) (len ?l - lamp)", "(len ?s ?s - switch)"), 5,
                   "function len: parameter ?s is declared twice")


@pytest.mark.parametrize(("old", "new", "line", "words"), [
    ("s1 s2 - switch", "s1 s2\n s1 - switch", 3, ("object s1 is declared twice",
                                                   "first at line 2")),
    ("(:domain lamp)", "(:domain lamp) (:requirements :typo)", 1, ("unknown requirement :typo",)),
    ("(:goal (on l1))", "(:goals (on l1))", 4, ("unknown section :goals", ":goal")),
    ("(:goal (on l1))", "(:goal (on l1)) (:action flip)", 4, ("unknown section :action",)),
    ("(:init (wired s1 l1))", "(:init (wired s1 l1))\n  (:init (on l1))", 4,
     ("duplicate section :init", "first at line 3")),
])
def test_problem_declarations_that_cannot_be_meant_are_refused(old, new, line, words):
    problem_refused(edit(LAMP_PROBLEM, old, new), line, *words)


def test_an_object_that_repeats_a_constant_is_refused():
    domain = edit(LAMP_DOMAIN, "(:types lamp switch)",
                  "(:types lamp switch)\n  (:constants s1 - switch)")
    problem_refused(LAMP_PROBLEM, 2, "object s1 is declared twice", "as a constant",
                    domain=domain)


# --- byte-order mark ---------------------------------------------------------------------

def test_a_byte_order_mark_is_accepted(tmp_path):
    d, p = tmp_path / "lamp.pddl", tmp_path / "lamp-1.pddl"
    d.write_text(LAMP_DOMAIN, encoding="utf-8-sig")
    p.write_text(LAMP_PROBLEM, encoding="utf-8-sig")
    assert d.read_bytes().startswith(b"\xef\xbb\xbf")
    domain = read_domain(d)
    assert domain.name == "lamp"
    problem = read_problem(p, domain)
    assert problem.name == "lamp-1"
    # a STRIPS domain with a BOM grounds as without one
    tiny = "\ufeff" + "(define (domain t) (:predicates (a) (b)) (:action go :effect (b)))"
    task = ground(parse_domain(tiny), parse_problem("\ufeff(define (problem q) (:domain t) "
                                                    "(:init (a)) (:goal (b)))",
                                                    parse_domain(tiny)))
    assert [op.name for op in task.ops] == ["(go)"]


def test_a_byte_order_mark_inside_the_text_is_still_refused():
    domain_refused(edit(LAMP_DOMAIN, "(:types lamp switch)", "(:types lamp \ufeffswitch)"), 3,
                   "cannot be part of a name")


# --- the command line ----------------------------------------------------------------------

def test_run_refuses_a_hash_in_an_action_name_with_one_line(capsys, tmp_path):
    d, p = tmp_path / "lamp.pddl", tmp_path / "lamp-1.pddl"
    d.write_text(edit(LAMP_DOMAIN, "(:action press", "(:action pr#ess"), encoding="utf-8")
    p.write_text(LAMP_PROBLEM, encoding="utf-8")
    code = main(["run", "--domain", str(d), "--problem", str(p), "--episodes", "2", "--runs",
                 "1", "--method", "Q-learning", "--jobs", "1", "--out", str(tmp_path / "o")])
    out = capsys.readouterr()
    text = out.out + out.err
    assert code == 2, text
    assert "Traceback" not in text
    assert f"{d}:9: " in text and "'#'" in text


@pytest.mark.parametrize("kind", ["imply", "not", "forall", "or", "when", "forall-effect"])
def test_every_connective_nested_up_to_the_limit_is_normalised_and_grounded(kind):
    """Normalisation and grounding walk conditions and effects recursively: at the deepest
    nesting the reader accepts, each connective still goes through."""
    n = MAX_DEPTH - 8
    pre, eff = "(b)", "(a)"
    if kind == "imply":
        pre = "(imply (a) " * n + "(b)" + ")" * n
    elif kind == "not":
        pre = "(not " * (n - n % 2) + "(b)" + ")" * (n - n % 2)
    elif kind == "forall":
        pre = "(forall (?x - t) " * n + "(b)" + ")" * n
    elif kind == "or":
        pre = "(or (a) " * n + "(b)" + ")" * n
    elif kind == "when":
        eff = "(when (b) " * n + "(a)" + ")" * n
    else:
        eff = "(forall (?x - t) " * n + "(a)" + ")" * n
    domain = parse_domain(f"(define (domain d) (:types t) (:predicates (a) (b)) (:action go "
                          f":parameters () :precondition {pre} :effect {eff}))")
    problem = parse_problem("(define (problem p) (:domain d) (:objects o - t) (:init (b)) "
                            "(:goal (a)))", domain)
    learner, planner = ground_ppddl(domain, problem)
    assert [op.name for op in learner.ops] == ["(go)"]
    assert learner.atoms(learner.ops[0].outcomes[0].apply(learner.init)) == {"(a)"}


EIGHT = " ".join(f"?v{i}" for i in range(8))


@pytest.mark.parametrize(("pre", "eff", "goal"), [
    (f"(forall ({EIGHT} - t) (not (p ?v0)))", "(not (a))", "(not (a))"),
    ("(a)", f"(forall ({EIGHT} - t) (p ?v7))", "(not (a))"),
    ("(a)", "(not (a))", f"(exists ({EIGHT} - t) (p ?v3))"),
])
def test_quantifiers_that_would_expand_past_any_machine_are_refused_up_front(pre, eff, goal):
    """Eight variables over 50 objects are 4e13 atoms: refused at once, naming the action
    (in a precondition, a forall effect) or the goal, not a hang."""
    objects = " ".join(f"o{i}" for i in range(50))
    domain = parse_domain("(define (domain d) (:types t) (:predicates (a) (p ?x - t)) "
                          f"(:action go :parameters () :precondition {pre} :effect {eff}))",
                          "d.pddl")
    problem = f"(define (problem q) (:domain d) (:objects {objects} - t) (:init (a)) " \
              f"(:goal {goal}))"
    if goal != "(not (a))":
        refused_at(lambda: parse_problem(problem, domain, "p.pddl"), "p.pddl", 1,
                   "atoms once its quantifiers are expanded")
        return
    parsed = parse_problem(problem, domain, "p.pddl")
    refused_at(lambda: ground_ppddl(domain, parsed), "d.pddl", 1, "action go",
               "atoms once grounded")
