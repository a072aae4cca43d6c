"""The IPPC PPDDL language at the PDDL layer (issue 22, item 1): a domain and its problems
in one file, requirements that declare and never decide, every construct outside the
language listed at once. Construct by construct: test_ippc_constructs.py."""

from __future__ import annotations

import pytest

from gdq_pddl.cli import main
from gdq_pddl.errors import PDDLError
from gdq_pddl.pddl import ground, parse_domain, parse_problem, read_domain, read_problem
from gdq_pddl.pddl.ppddl import ground_ppddl

# Two rooms and a door; opening is a coin flip. The domain and two problems in one file,
# as the IPPC-2008 distribution writes them.
ONE_FILE = """; a door between two rooms
(define (domain door)
  (:requirements :typing :probabilistic-effects)
  (:types room)
  (:predicates (in ?r - room) (open) (link ?a ?b - room))
  (:action push
    :parameters ()
    :precondition (not (open))
    :effect (probabilistic 1/2 (open)))
  (:action go
    :parameters (?a ?b - room)
    :precondition (and (in ?a) (link ?a ?b) (open))
    :effect (and (in ?b) (not (in ?a)))))

(define (problem door-1) (:domain door)
  (:objects hall kitchen - room)
  (:init (in hall) (link hall kitchen))
  (:goal (in kitchen)))

(define (problem door-2) (:domain door)
  (:objects hall kitchen - room)
  (:init (in kitchen) (link kitchen hall))
  (:goal (in hall)))
"""


def only(text: str, drop: str) -> str:
    """``ONE_FILE`` without the problem named ``drop``."""
    start = text.index(f"(define (problem {drop})")
    end = text.find("(define", start + 1)
    return text[:start] + (text[end:] if end >= 0 else "")


def test_a_domain_and_its_problems_in_one_file_are_read_by_name():
    domain = parse_domain(ONE_FILE, "door.pddl")
    assert domain.name == "door" and [a.name for a in domain.actions] == ["push", "go"]
    one = parse_problem(ONE_FILE, domain, "door.pddl", name="door-1")
    two = parse_problem(ONE_FILE, domain, "door.pddl", name="DOOR-2")  # names: any case
    assert [str(a) for a in sorted(one.init, key=str)] == ["(in hall)", "(link hall kitchen)"]
    assert [str(lit.atom) for lit in two.goal] == ["(in hall)"]


def test_several_problems_and_no_name_is_refused_listing_them():
    domain = parse_domain(ONE_FILE)
    with pytest.raises(PDDLError, match=r"^door.pddl:20: this file has 2 problems "
                                        r"\(door-1, door-2\): pick one by name "
                                        r"\(door.pddl:door-1\)$"):
        parse_problem(ONE_FILE, domain, "door.pddl")
    with pytest.raises(PDDLError, match=r"no problem named 'door-3' in this file \(it has "
                                        r"door-1, door-2\)"):
        parse_problem(ONE_FILE, domain, "door.pddl", name="door-3")


def test_a_file_of_only_problems_is_no_domain():
    domain = parse_domain(ONE_FILE)
    problems = ONE_FILE[ONE_FILE.index("(define (problem door-1)"):]
    with pytest.raises(PDDLError, match="^p.pddl: expected a .define .domain NAME"):
        parse_domain(problems, "p.pddl")
    with pytest.raises(PDDLError, match="^d.pddl: expected a .define .problem NAME.*only "
                                        "domains"):
        parse_problem(ONE_FILE[:ONE_FILE.index("(define (problem")], domain, "d.pddl")


def test_one_file_given_as_both_domain_and_problem_runs(capsys, tmp_path):
    """The command line reads the same file as the domain and as the problem."""
    path = tmp_path / "door.pddl"
    path.write_text(only(ONE_FILE, "door-2"), encoding="utf-8")
    domain = read_domain(path)
    learner, _ = ground_ppddl(domain, read_problem(path, domain))
    # push (open: 1/2) then go: the ground actions, hand-derived
    assert [op.name for op in learner.ops] == ["(push)", "(go hall kitchen)"]
    code = main(["run", "--domain", str(path), "--problem", str(path), "--episodes", "3",
                 "--runs", "1", "--method", "Q-learning", "--jobs", "1", "--no-report",
                 "--out", str(tmp_path / "out")])
    out = capsys.readouterr()
    assert code == 0, out.out + out.err
    assert (tmp_path / "out" / "episodes.csv").exists()


def test_a_type_glued_to_its_dash_is_read_as_lexers_read_it():
    """``(?loc -zone)``, as a published IPPC domain writes it: '-zone' is '- zone'."""
    domain = parse_domain(ONE_FILE.replace("(?a ?b - room)", "(?a ?b -room)"))
    assert domain.actions[1].parameters == (("?a", "room"), ("?b", "room"))


# --- requirements declare, never decide -------------------------------------------------

def test_an_undeclared_requirement_does_not_block_its_construct():
    """A negative precondition without :negative-preconditions is read, in a STRIPS
    domain as in a PPDDL one; before, only a PPDDL domain got this leniency."""
    text = """(define (domain d) (:requirements :strips)
      (:predicates (a) (b))
      (:action go :parameters () :precondition (not (b)) :effect (b)))"""
    domain = parse_domain(text)
    task = ground(domain, parse_problem("(define (problem p) (:domain d) (:init (a)) "
                                        "(:goal (b)))", domain))
    assert [op.name for op in task.ops] == ["(go)"]
    assert task.ops[0].neg == 1 << task.fact_index["(b)"]


def test_a_declared_requirement_never_blocks_a_file():
    """IPPC files declare :adl, :conditional-effects, :fluents... whatever they use."""
    reqs = ":adl :conditional-effects :fluents :rewards :mdp :equality :universal-preconditions"
    domain = parse_domain(ONE_FILE.replace(":typing :probabilistic-effects", f":typing {reqs}"))
    assert ":conditional-effects" in domain.requirements


# --- every construct outside the language, at once -----------------------------------------

def test_every_construct_outside_the_language_is_listed():
    text = ONE_FILE.replace(":effect (probabilistic 1/2 (open))",
                            ":effect (oneof (open) (and))") \
        .replace("(:types room)", "(:types room)\n  (:derived (open) (open))") \
        .replace(":effect (and (in ?b) (not (in ?a)))", ":effect (and (in ?b) (assign "
                 "(fuel) 1)\n (oneof (in ?a) (in ?b)))")
    with pytest.raises(PDDLError) as err:
        parse_domain(text, "door.pddl")
    message = str(err.value)
    assert message.startswith("door.pddl:5: not supported"), message
    for listed in ("(:derived ...) at line 5", "(oneof ...) (FOND: give probabilities with "
                   "(probabilistic ...)) at lines 10, 15", "(assign ...) (numeric fluents) at "
                   "line 14"):
        assert listed in message, message
    assert "\n" not in message
