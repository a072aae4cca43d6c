"""Generated PPDDL problems for the size targets (issue 22 item 4), written to a folder.

    python benchmarks/scale_problems.py blocks 7 OUT     # OUT/blocks.pddl, OUT/blocks-7.pddl
    python benchmarks/scale_problems.py arms 7 OUT       # OUT/arms.pddl, OUT/arms-7.pddl
    python benchmarks/scale_problems.py switches 20 OUT  # OUT/switches.pddl, ...-20.pddl

``blocks N``: a blocksworld with a hand and a table (pick-up, put-down, stack, unstack;
a block may slip from the hand onto the table), N blocks in one tower in the initial
state, the reverse tower as the goal. Every arrangement is reachable: 65,990 states at
7 blocks, 112 ground actions. ``moves N``: the same blocks with a move from block to
block besides (the same states; 406 ground actions at 7 blocks). ``arms N``: the same
blocks, tower and goal, typed, with two arms, each of which picks up, puts down, stacks
and unstacks (with the slips of ``blocks``), pushes a clear block off another onto the
table (9 times in 10), or hands its block over to the other arm (which drops it on the
table 1 time in 10). Either arm may hold a block, so every arrangement with none, one
or two blocks held is reachable: 115,389 states at 7 blocks, 336 ground actions (the
size of the IPPC-2006 blocksworld p01 of issue 22: 103,120 states, 330 ground actions).
``switches N``: N independent switches, each turned on by its own action, which works 9
times in 10: 2**N states, every ordering of the switches is a shortest plan.
"""

from __future__ import annotations

import sys
from pathlib import Path

BLOCKS_DOMAIN = """\
(define (domain slippery-blocks)
  (:requirements :strips :probabilistic-effects)
  (:predicates (on ?x ?y) (ontable ?x) (clear ?x) (holding ?x) (handempty))
  (:action pick-up
    :parameters (?x)
    :precondition (and (clear ?x) (ontable ?x) (handempty))
    :effect (probabilistic 0.9 (and (holding ?x) (not (ontable ?x)) (not (clear ?x))
                                    (not (handempty)))))
  (:action put-down
    :parameters (?x)
    :precondition (holding ?x)
    :effect (and (ontable ?x) (clear ?x) (handempty) (not (holding ?x))))
  (:action stack
    :parameters (?x ?y)
    :precondition (and (holding ?x) (clear ?y))
    :effect (and (clear ?x) (handempty) (not (holding ?x))
                 (probabilistic 0.8 (and (on ?x ?y) (not (clear ?y)))
                                0.2 (ontable ?x))))
  (:action unstack
    :parameters (?x ?y)
    :precondition (and (on ?x ?y) (clear ?x) (handempty))
    :effect (probabilistic 0.8 (and (holding ?x) (clear ?y) (not (on ?x ?y))
                                    (not (clear ?x)) (not (handempty)))
                           0.1 (and (ontable ?x) (clear ?y) (not (on ?x ?y))))))
"""

MOVES_DOMAIN = BLOCKS_DOMAIN.replace("slippery-blocks", "slippery-moves").rstrip()[:-1] + """
  (:action move
    :parameters (?x ?y ?z)
    :precondition (and (on ?x ?y) (clear ?x) (clear ?z) (handempty) (not (= ?x ?z)))
    :effect (probabilistic 0.8 (and (on ?x ?z) (clear ?y) (not (on ?x ?y)) (not (clear ?z))))))
"""

ARMS_DOMAIN = """\
(define (domain slippery-arms)
  (:requirements :strips :typing :equality :probabilistic-effects)
  (:types block arm)
  (:predicates (on ?x ?y - block) (ontable ?x - block) (clear ?x - block)
               (holding ?a - arm ?x - block) (free ?a - arm))
  (:action pick-up
    :parameters (?x - block ?a - arm)
    :precondition (and (clear ?x) (ontable ?x) (free ?a))
    :effect (probabilistic 0.9 (and (holding ?a ?x) (not (ontable ?x)) (not (clear ?x))
                                    (not (free ?a)))))
  (:action put-down
    :parameters (?x - block ?a - arm)
    :precondition (holding ?a ?x)
    :effect (and (ontable ?x) (clear ?x) (free ?a) (not (holding ?a ?x))))
  (:action stack
    :parameters (?x ?y - block ?a - arm)
    :precondition (and (holding ?a ?x) (clear ?y))
    :effect (and (clear ?x) (free ?a) (not (holding ?a ?x))
                 (probabilistic 0.8 (and (on ?x ?y) (not (clear ?y)))
                                0.2 (ontable ?x))))
  (:action unstack
    :parameters (?x ?y - block ?a - arm)
    :precondition (and (on ?x ?y) (clear ?x) (free ?a))
    :effect (probabilistic 0.8 (and (holding ?a ?x) (clear ?y) (not (on ?x ?y))
                                    (not (clear ?x)) (not (free ?a)))
                           0.1 (and (ontable ?x) (clear ?y) (not (on ?x ?y)))))
  (:action push-off
    :parameters (?x ?y - block ?a - arm)
    :precondition (and (on ?x ?y) (clear ?x) (free ?a))
    :effect (probabilistic 0.9 (and (ontable ?x) (clear ?y) (not (on ?x ?y)))))
  (:action pass
    :parameters (?x - block ?a ?b - arm)
    :precondition (and (holding ?a ?x) (free ?b) (not (= ?a ?b)))
    :effect (and (free ?a) (not (holding ?a ?x))
                 (probabilistic 0.9 (and (holding ?b ?x) (not (free ?b)))
                                0.1 (and (ontable ?x) (clear ?x))))))
"""

SWITCHES_DOMAIN = """\
(define (domain noisy-switches)
  (:requirements :strips :probabilistic-effects :negative-preconditions)
  (:predicates (on ?s))
  (:action turn-on
    :parameters (?s)
    :precondition (not (on ?s))
    :effect (probabilistic 0.9 (on ?s))))
"""


def _tower(n: int) -> tuple[list[str], list[str], list[str]]:
    """Blocks b1..bN, the tower b1 on b2 on ... on bN, and the reverse tower."""
    names = [f"b{i}" for i in range(1, n + 1)]
    init = [f"(on {a} {b})" for a, b in zip(names, names[1:], strict=False)]
    goal = [f"(on {b} {a})" for a, b in zip(names, names[1:], strict=False)]
    return names, init, goal


def blocks_problem(n: int) -> str:
    """One tower b1 on b2 on ... on bN in the initial state; the reverse tower as goal."""
    names, init, goal = _tower(n)
    return (f"(define (problem blocks-{n}) (:domain slippery-blocks)\n"
            f"  (:objects {' '.join(names)})\n"
            f"  (:init (handempty) (clear b1) (ontable {names[-1]}) {' '.join(init)})\n"
            f"  (:goal (and {' '.join(goal)})))\n")


def arms_problem(n: int, arms: int = 2) -> str:
    """The tower and goal of :func:`blocks_problem`, typed, with ``arms`` free arms."""
    names, init, goal = _tower(n)
    hands = [f"a{i}" for i in range(1, arms + 1)]
    return (f"(define (problem arms-{n}) (:domain slippery-arms)\n"
            f"  (:objects {' '.join(names)} - block {' '.join(hands)} - arm)\n"
            f"  (:init {' '.join(f'(free {h})' for h in hands)} (clear b1) "
            f"(ontable {names[-1]})\n         {' '.join(init)})\n"
            f"  (:goal (and {' '.join(goal)})))\n")


def switches_problem(n: int) -> str:
    """Every switch off in the initial state; every switch on as the goal."""
    names = [f"s{i}" for i in range(1, n + 1)]
    return (f"(define (problem switches-{n}) (:domain noisy-switches)\n"
            f"  (:objects {' '.join(names)})\n  (:init)\n"
            f"  (:goal (and {' '.join(f'(on {s})' for s in names)})))\n")


KINDS = {"blocks": (BLOCKS_DOMAIN, blocks_problem),
         "moves": (MOVES_DOMAIN, lambda n: blocks_problem(n).replace("slippery-blocks",
                                                                     "slippery-moves")),
         "arms": (ARMS_DOMAIN, arms_problem),
         "switches": (SWITCHES_DOMAIN, switches_problem)}


def write(kind: str, n: int, out: Path) -> tuple[Path, Path]:
    """Write ``out/<kind>.pddl`` and ``out/<kind>-<n>.pddl``; return their paths."""
    domain, problem = KINDS[kind]
    out.mkdir(parents=True, exist_ok=True)
    d, p = out / f"{kind}.pddl", out / f"{kind}-{n}.pddl"
    d.write_text(domain)
    p.write_text(problem(n))
    return d, p


if __name__ == "__main__":
    if len(sys.argv) != 4 or sys.argv[1] not in KINDS:
        sys.exit(__doc__.split("\n\n")[1])
    print(*write(sys.argv[1], int(sys.argv[2]), Path(sys.argv[3])))
