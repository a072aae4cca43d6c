"""What the PPDDL tests share (``test_ppddl_reader``, ``test_ppddl``,
``test_ppddl_env_cli``): the hike, a PPDDL domain no shipped file knows, and its
problem; the instance built from them; finding its states, actions and outcomes; and
writing them as files."""

from __future__ import annotations

from pathlib import Path

from gdq_pddl.envs.pddl_env import PDDLInstance
from gdq_pddl.envs.step import pair_of

# A domain no shipped file knows: a hiker on two banks of a river. Fording is quick,
# but the current may carry the hiker downstream, or away (a failed trial); the bridge
# is at the far end of the trail.
HIKE_DOMAIN = """; the hike domain
(define (domain hike)
  (:requirements :strips :typing :probabilistic-effects :rewards)
  (:types camp)
  (:predicates (at ?c - camp) (trail ?a ?b - camp) (ford ?a ?b ?down - camp) (stuck))
  (:action walk
    :parameters (?a ?b - camp)
    :precondition (and (at ?a) (trail ?a ?b))
    :effect (and (decrease (reward) 1)
                 (probabilistic 0.9 (and (at ?b) (not (at ?a))))))
  (:action wade
    :parameters (?a ?b ?down - camp)
    :precondition (and (at ?a) (ford ?a ?b ?down))
    :effect (and (decrease (reward) 2)
                 (probabilistic 0.5 (and (at ?b) (not (at ?a)))
                                0.3 (and (at ?down) (not (at ?a)))
                                0.1 (stuck)))))
"""
HIKE_PROBLEM = """(define (problem hike-4) (:domain hike)
  (:objects w1 w2 w3 w4 e1 e2 e3 e4 - camp)
  (:init (at w1)
    (trail w1 w2) (trail w2 w1) (trail w2 w3) (trail w3 w2) (trail w3 w4) (trail w4 w3)
    (trail e1 e2) (trail e2 e1) (trail e2 e3) (trail e3 e2) (trail e3 e4) (trail e4 e3)
    (trail w4 e4) (trail e4 w4)
    (ford w2 e2 e3) (ford w3 e3 e4))
  (:goal (at e1))
  (:goal-reward 30)
  (:metric maximize (reward)))
"""


def hike(determinisation: str = "all-outcomes", overlay: str | None = None) -> PDDLInstance:
    return PDDLInstance.from_texts(HIKE_DOMAIN, HIKE_PROBLEM, overlay,
                                   determinisation=determinisation)


def atoms_of(inst: PDDLInstance, s: int) -> set[str]:
    return set(inst.atoms(s))


def state_with(inst: PDDLInstance, atom: str) -> int:
    return next(s for s in range(inst.n_states) if atom in inst.atoms(s))


def action(inst: PDDLInstance, name: str) -> int:
    return next(a for a in range(inst.n_actions) if inst.action_name(a) == name)


def outcomes(inst: PDDLInstance, s: int, a: int) -> dict[tuple[str, bool], float]:
    """``{(where the hiker is, stuck): probability}`` of action ``a`` in state ``s``."""
    m = inst.model
    i = pair_of(m, s, a)
    if i is None:  # not offered in s: stepping it changes nothing
        return {(next(x for x in inst.atoms(s) if x.startswith("(at")), False): 1.0}
    k = slice(m.ptr[i], m.ptr[i + 1])
    out: dict[tuple[str, bool], float] = {}
    for t, stuck, p in zip(m.next[k], m.stuck[k], m.prob[k], strict=True):
        key = (next(x for x in inst.atoms(int(t)) if x.startswith("(at")), bool(stuck))
        out[key] = out.get(key, 0.0) + float(p)
    return out


def hike_files(tmp_path: Path, domain: str = HIKE_DOMAIN,
               problem: str = HIKE_PROBLEM) -> tuple[Path, Path]:
    files = (tmp_path / "hike.pddl", tmp_path / "hike-4.pddl")
    for path, text in zip(files, (domain, problem), strict=True):
        path.write_text(text, encoding="utf-8")
    return files
