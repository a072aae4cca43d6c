"""A PPDDL problem explored online, timed end to end and by stage, for one or more copies of
the package side by side (a loaded machine's speed drifts: the copies take turns).

    python benchmarks/online_run.py PROBLEM [--domain D] [--episodes 100] [--runs 5]
        [--jobs 2] [--rounds 1] [--code DIR ...] [--stages-only] [--walk N]

``PROBLEM``: a PPDDL problem file (the domain too, where one file holds both, as the
IPPC-2008 boxworld files do; else ``--domain``). ``--code``: a folder holding a copy
of the package (the ``gdq_pddl`` folder's parent, put first on ``PYTHONPATH``); default:
the package this script imports. Each round runs every copy once, in the order given.

For each copy and round it prints, from a fresh process:

- ``setup``: the seconds before the first episode can start (reading and grounding the
  files, the online store, the estimates of the initial state: what
  ``gdq-pddl run --explore online`` does before any run), and the ground actions;
- ``run``: the wall seconds of
  ``gdq-pddl run --domain D --problem P --method GDQ DARLING Q-learning
  --episodes E --runs R --jobs J --explore online --no-report`` (the CPU seconds too), and
  the ratio of each copy's time to the first copy's.

- ``walk`` (with ``--walk N``, instead of ``run``): the CPU seconds of a walk that visits
  ``N`` states never visited before (:meth:`OnlineInstance.visit
  <gdq_pddl.envs.online.OnlineInstance.visit>`: each expanded, its row filled, its new
  successors estimated), as DARLING's episodes on boxworld p05 do, by the same seeded
  choices in every copy: what an online run pays per new state, without the learners.

The first run of a copy after its sources change compiles its kernels (numba caches
them): run a round with small ``--episodes`` first, or read the second round.
"""

from __future__ import annotations

import argparse
import os
import resource
import subprocess
import sys
import tempfile
import time
from pathlib import Path

SETUP = """
import sys, time
t0 = time.perf_counter()
from gdq_pddl.experiments.work import load_pddl_instance
from gdq_pddl.envs.online import OnlineInstance
try:  # the problem as a ProblemSpec (since the runner's typed specs), else a tuple
    from gdq_pddl.experiments.protocol import ProblemSpec
    spec = ProblemSpec(sys.argv[1], sys.argv[2])
except ImportError:
    spec = (sys.argv[1], sys.argv[2], "", "all-outcomes")
t1 = time.perf_counter()
inst = load_pddl_instance(spec)
t2 = time.perf_counter()
online = OnlineInstance(inst)
t3 = time.perf_counter()
print(f"{t2 - t1:.2f} {t3 - t2:.2f} {len(online.task.ops)}")
"""


WALK = """
import sys, time
import numpy as np
from gdq_pddl.experiments.work import load_pddl_instance
from gdq_pddl.envs.online import OnlineInstance
try:
    from gdq_pddl.experiments.protocol import ProblemSpec
    spec = ProblemSpec(sys.argv[1], sys.argv[2])
except ImportError:
    spec = (sys.argv[1], sys.argv[2], "", "all-outcomes")
online = OnlineInstance(load_pddl_instance(spec))
graph, rng, x, visited = online.graph, np.random.default_rng(0), 0, 0
t0 = time.process_time()
while visited < int(sys.argv[3]):
    visited += not graph.expanded[x]
    online.visit(x)
    nxt = graph.outcomes(x)[2]
    new = nxt[~graph.expanded[nxt] & ~graph.is_goal[nxt]]
    x = int(rng.choice(new if len(new) and rng.random() < 0.9 else nxt))
    x = 0 if graph.is_goal[x] else x
print(f"{time.process_time() - t0:.2f} {graph.n_states}")
"""


def walk_seconds(code: str | None, domain: str, problem: str, n: int) -> tuple[float, int]:
    """``(CPU s, states found)`` of a walk visiting ``n`` new states, in a fresh process."""
    with tempfile.TemporaryDirectory() as here:
        out = subprocess.run([sys.executable, "-P", "-c", WALK, domain, problem, str(n)],
                             check=True, capture_output=True, text=True,
                             env=environment(code), cwd=here)
    cpu, states = out.stdout.split()
    return float(cpu), int(states)


def environment(code: str | None) -> dict[str, str]:
    env = dict(os.environ, TQDM_DISABLE="1")
    env["PYTHONPATH"] = str(Path(code).resolve()) if code is not None else \
        str(Path(__file__).resolve().parents[1])
    return env


def setup_seconds(code: str | None, domain: str, problem: str) -> tuple[float, float, int]:
    """``(grounding s, online store s, ground actions)`` in a fresh process."""
    with tempfile.TemporaryDirectory() as here:  # not the working folder's package
        out = subprocess.run([sys.executable, "-P", "-c", SETUP, domain, problem],
                             check=True, capture_output=True, text=True,
                             env=environment(code), cwd=here)
    ground, store, ops = out.stdout.split()
    return float(ground), float(store), int(ops)


def run_seconds(code: str | None, domain: str, problem: str, args) -> tuple[float, float]:
    """``(wall s, CPU s of the children)`` of one ``gdq-pddl run`` in a fresh process."""
    before = resource.getrusage(resource.RUSAGE_CHILDREN)
    with tempfile.TemporaryDirectory() as out:
        t0 = time.perf_counter()
        done = subprocess.run(
            [sys.executable, "-P", "-m", "gdq_pddl.cli", "run", "--domain", domain,
             "--problem", problem, "--method", "GDQ", "DARLING", "Q-learning",
             "--episodes", str(args.episodes), "--runs", str(args.runs),
             "--jobs", str(args.jobs), "--explore", "online", "--no-report", "--out", out],
            capture_output=True, text=True, env=environment(code), cwd=out)
        wall = time.perf_counter() - t0
    if done.returncode:  # say why, and go on with the other copies
        print(f"{code}: gdq-pddl run failed: {done.stderr.strip().splitlines()[-1:]}")
        return float("nan"), float("nan")
    after = resource.getrusage(resource.RUSAGE_CHILDREN)
    return wall, (after.ru_utime - before.ru_utime) + (after.ru_stime - before.ru_stime)


def main(argv: list[str] | None = None) -> None:
    p = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    p.add_argument("problem")
    p.add_argument("--domain", help="the domain file (default: PROBLEM)")
    p.add_argument("--episodes", type=int, default=100)
    p.add_argument("--runs", type=int, default=5)
    p.add_argument("--jobs", type=int, default=2)
    p.add_argument("--rounds", type=int, default=1)
    p.add_argument("--code", nargs="+", default=[None],
                   help="folders holding copies of the package (default: this one)")
    p.add_argument("--stages-only", action="store_true", help="time the setup only")
    p.add_argument("--walk", type=int, default=0, metavar="N",
                   help="instead of a run, the CPU seconds of visiting N new states")
    args = p.parse_args(argv)
    problem = str(Path(args.problem).resolve())
    domain = str(Path(args.domain).resolve()) if args.domain else problem
    print(f"problem {problem}: --episodes {args.episodes} --runs {args.runs} "
          f"--jobs {args.jobs}, {os.cpu_count()} cores, load "
          f"{os.getloadavg()[0]:.1f}", flush=True)
    for rnd in range(args.rounds):
        first = None
        for code in args.code:
            name = code or "(this package)"
            ground, store, ops = setup_seconds(code, domain, problem)
            line = (f"round {rnd + 1} {name}: setup {ground + store:.1f} s (grounding "
                    f"{ground:.1f} s, online store {store:.1f} s; {ops} ground actions)")
            if args.walk and not args.stages_only:
                cpu, states = walk_seconds(code, domain, problem, args.walk)
                first = first or cpu
                line += (f"; walk of {args.walk} new states: {cpu:.2f} s CPU, "
                         f"{1000 * cpu / args.walk:.2f} ms a state ({states} states found), "
                         f"x{cpu / first:.2f}")
            elif not args.stages_only:
                wall, cpu = run_seconds(code, domain, problem, args)
                first = first or wall
                line += f"; run {wall:.1f} s wall, {cpu:.1f} s CPU, x{wall / first:.2f}"
            print(line, flush=True)


if __name__ == "__main__":
    main()
