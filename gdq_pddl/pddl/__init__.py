"""PDDL: reading domains and problems, grounding them, writing office problems."""

from gdq_pddl.pddl.grounding import GroundOp, GroundOutcome, GroundTask, ground
from gdq_pddl.pddl.model import Action, Atom, Domain, Literal, Problem
from gdq_pddl.pddl.parser import parse_domain, read_domain
from gdq_pddl.pddl.problem_reader import parse_problem, read_problem

__all__ = ["Action", "Atom", "Domain", "GroundOp", "GroundOutcome", "GroundTask", "Literal",
           "Problem", "ground", "parse_domain", "parse_problem", "read_domain", "read_problem"]
