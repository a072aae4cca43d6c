"""sysadmin-slp problems in the form of the IPPC-2008 generator (issue 40, item 1), for
when the competition's own p01-p15 are not at hand, and a run of each.

    python benchmarks/sysadmin_problems.py write OUT 10 20 30 40 50   # OUT/sysadmin-<n>.pddl
    python benchmarks/sysadmin_problems.py run DOMAIN OUT 10 20       # a short run of each
    python benchmarks/sysadmin_problems.py ground DOMAIN 10 20 50     # grounding time

A problem of ``n`` computers, as the competition's generator writes them: a directed
ring ``(conn comp<i> comp<i+1>)``, ``n // 2`` extra links drawn at random (seeded by
``n``) between computers at least two apart, no computer up at the start, and every
computer up as the goal (goal reward 500, metric maximize reward). The domain is the
competition's public ``sysadmin-slp`` domain file, read as published (not shipped here).
``reboot ?x``'s effect draws, for every other computer, whether it goes down: its
outcomes are a product of one draw per computer, ``2 x 4^(n-1)`` of them, kept factored
past 4096 (:data:`gdq_pddl.pddl.factored.FACTORED_ABOVE`).

``ground`` grounds each (the best of 3 below 50 computers, else once) and prints the time
and a hash of every ground action (to compare two checkouts: run it under each one's
``PYTHONPATH`` in turn).
``run`` times ``gdq-pddl run --method GDQ DARLING Q-learning --episodes 10 --runs 1
--jobs 1`` on each (the problem goes online: its actions are factored) and prints the
mean return, success rate and time of each method.
"""

from __future__ import annotations

import random
import subprocess
import sys
import time
from pathlib import Path


def problem_text(n: int, seed: int | None = None) -> str:
    """A sysadmin-slp problem of ``n`` computers (at least 3): the ring, ``n // 2``
    extra links (drawn with ``seed``, default ``n``), nothing up, all up as the goal."""
    if n < 3:
        raise ValueError(f"n = {n}: a ring with extra links needs at least 3 computers")
    rnd = random.Random(n if seed is None else seed)
    links = {(i, (i + 1) % n) for i in range(n)}
    while len(links) < n + n // 2:
        i = rnd.randrange(n)
        links.add((i, (i + 2 + rnd.randrange(n - 2)) % n))
    init = "\n".join(f"    (conn comp{i} comp{j})" for i, j in sorted(links))
    objects = " ".join(f"comp{i}" for i in range(n))
    return (f"(define (problem sysadmin-{n})\n  (:domain sysadmin-slp)\n"
            f"  (:objects {objects} - comp)\n  (:init\n{init}\n  )\n"
            "  (:goal (forall (?c - comp) (up ?c)))\n  (:goal-reward 500)\n"
            "  (:metric maximize (reward)))\n")


def write(out: Path, sizes: list[int]) -> list[Path]:
    """Write ``out/sysadmin-<n>.pddl`` for each size; return their paths."""
    out.mkdir(parents=True, exist_ok=True)
    paths = []
    for n in sizes:
        path = out / f"sysadmin-{n}.pddl"
        path.write_text(problem_text(n))
        paths.append(path)
    return paths


def run(domain: Path, out: Path, sizes: list[int]) -> None:
    """A short run of each size (the module docstring), its figures printed."""
    import pandas as pd

    for path in write(out, sizes):
        folder = out / f"run-{path.stem}"
        start = time.perf_counter()
        subprocess.run(["gdq-pddl", "run", "--domain", str(domain), "--problem", str(path),
                        "--method", "GDQ", "DARLING", "Q-learning", "--episodes", "10",
                        "--runs", "1", "--jobs", "1", "--seed", "1", "--no-report",
                        "--out", str(folder)], check=True)
        took = time.perf_counter() - start
        table = pd.read_csv(folder / "episodes.csv").groupby("method")[
            ["return", "success"]].mean()
        print(f"{path.stem}: {took:.1f} s")
        print(table.to_string())


def ground_times(domain: Path, sizes: list[int]) -> None:
    """Print the grounding time and the ground actions' hash of each size."""
    import hashlib

    from gdq_pddl.pddl import ground, parse_domain, parse_problem

    dom = parse_domain(domain.read_text(), str(domain))
    for n in sizes:
        problem = parse_problem(problem_text(n), dom, f"sysadmin-{n}")
        took = []
        for _ in range(3 if n < 50 else 1):
            start = time.perf_counter()
            task = ground(dom, problem)
            took.append(time.perf_counter() - start)
        digest = hashlib.sha256(repr([(op.name, op.pre, op.neg, op.outcomes, op.known,
                                       op.parts) for op in task.ops]).encode()).hexdigest()
        print(f"sysadmin-{n}: grounded in {min(took):.3f} s, actions {digest[:16]}")


def main(argv: list[str]) -> int:
    if len(argv) >= 3 and argv[0] == "write":
        for path in write(Path(argv[1]), [int(n) for n in argv[2:]]):
            print(path)
        return 0
    if len(argv) >= 3 and argv[0] == "ground":
        ground_times(Path(argv[1]), [int(n) for n in argv[2:]])
        return 0
    if len(argv) >= 4 and argv[0] == "run":
        run(Path(argv[1]), Path(argv[2]), [int(n) for n in argv[3:]])
        return 0
    print(__doc__, file=sys.stderr)
    return 2


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
