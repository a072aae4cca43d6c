"""Plain helpers the tests share (fixtures live in ``tests/conftest.py``).

Import them as ``from tests.helpers import ...``: ``tests`` and its layer folders are
packages, so pytest puts the repository root on ``sys.path`` wherever a test file lives.
"""

from __future__ import annotations

import os
import subprocess
import sys
import threading
from concurrent.futures import Future, ThreadPoolExecutor, wait
from pathlib import Path

import numpy as np

from gdq_pddl.cli import main
from gdq_pddl.learners import run_episodes

REPO_ROOT = Path(__file__).resolve().parent.parent
"""The repository checkout (``domains/``, ``problems/``, ``docs/``, ``examples/`` ...)."""
DYNAMICS = REPO_ROOT / "gdq_pddl" / "data" / "dynamics"
"""The shipped dynamics files (``keys.toml``, ``office.toml`` ...)."""


class Recording:
    """Wraps a learner and records the (state, action) pairs it executes."""

    def __init__(self, learner) -> None:
        self.learner, self.pairs = learner, []
        self.q = learner.q

    @property
    def states(self) -> list[int]:
        return [s for s, _ in self.pairs]

    @property
    def actions(self) -> list[int]:
        return [a for _, a in self.pairs]

    def act(self, s, rng):
        a = self.learner.act(s, rng)
        self.pairs.append((s, a))
        return a

    def observe(self, *args):
        self.learner.observe(*args)

    def start_task(self, ctx):
        self.learner.start_task(ctx)

    def greedy_policy(self):
        return self.learner.greedy_policy()


def corridor_text(nav: float, doors: list[tuple[float, float]], ring: bool = False,
                  world: str = "", sections: str = "") -> str:
    """A world file: a corridor x0 - y0 | z0 - x1 - y1 | z1 - x2 ... with a door of
    ``(success, stuck)`` between each y and z (and x0 - last when ``ring``); ``world``
    adds keys to its ``[world]`` table, ``sections`` tables before the doors."""
    names, edges, tables = ["x0"], [], []
    for i, (success, stuck) in enumerate(doors):
        y, z, x = f"y{i}", f"z{i}", f"x{i + 1}"
        edges += [(names[-1], y), (y, z), (z, x)]
        names += [y, z, x]
        tables.append(f'[doors.d{i}]\nsides = ["{y}", "{z}"]\nsuccess = {success!r}\n'
                      f"stuck = {stuck!r}\n")
    if ring and len(names) > 2:
        edges.append((names[0], names[-1]))
    adjacency = ", ".join(f'["{a}", "{b}"]' for a, b in edges)
    return (f"[world]\n{world}navigation_success = {nav!r}\n"
            f"positions = [{', '.join(repr(n) for n in names)}]\n"
            f"adjacency = [{adjacency}]\n\n{sections}" + "\n".join(tables))


def run(learner, env, n, seed, fast=None):
    """``n`` episodes of ``learner`` on ``env`` reset with ``seed``, its draws from
    ``seed + 1``."""
    env.reset(seed=seed)
    return run_episodes(learner, env, n, np.random.default_rng(seed + 1), fast=fast)


def cli(capsys, *argv) -> tuple[int, str]:
    """Exit status and everything printed; an exception escaping main fails the test."""
    try:
        code = main([str(a) for a in argv])
    except SystemExit as exc:  # argparse's errors
        code = exc.code
    out = capsys.readouterr()
    return code, out.out + out.err


class Background:
    """Subprocesses that run on the second core beside the tests before them.

    A test marked ``@pytest.mark.background.with_args(start)`` has ``start(item)`` called when
    collection ends (``tests/conftest.py``); ``start`` calls :meth:`run`, which queues the
    command and returns a future of its ``CompletedProcess``. The test calls ``start`` again
    and waits on that same future. One command at a time, in the tests' order: the suite
    spends most of its time in one process, so the other core is otherwise idle.
    """

    def __init__(self) -> None:
        self.pool = ThreadPoolExecutor(1, thread_name_prefix="background")
        self.futures: dict[str, Future] = {}
        self.running: set[subprocess.Popen] = set()
        self.lock, self.stopped = threading.Lock(), False

    def run(self, key: str, argv: list[str], timeout: float = 600, **kwargs) -> Future:
        """``subprocess.run(argv, capture_output=True, text=True, **kwargs)``, once per key."""
        with self.lock:
            if key not in self.futures:
                self.futures[key] = self.pool.submit(self._run, argv, timeout, kwargs)
            return self.futures[key]

    def after(self, future: Future, timeout: float = 900) -> None:
        """The commands queued from now on start once ``future`` is done (or after
        ``timeout`` seconds)."""
        self.pool.submit(wait, [future], timeout)

    def _run(self, argv: list[str], timeout: float, kwargs) -> subprocess.CompletedProcess:
        with self.lock:
            if self.stopped:
                raise RuntimeError("the test session has ended")
            proc = subprocess.Popen(argv, stdout=subprocess.PIPE, stderr=subprocess.PIPE,
                                    text=True, **kwargs)
            self.running.add(proc)
        try:
            out, err = proc.communicate(timeout=timeout)
        finally:
            proc.kill()
            proc.communicate()
            with self.lock:
                self.running.discard(proc)
        return subprocess.CompletedProcess(argv, proc.returncode, out, err)

    def stop(self) -> None:
        """Kill what runs and drop what waits (the session is over)."""
        with self.lock:
            self.stopped = True
            for future in self.futures.values():
                future.cancel()
            for proc in self.running:
                proc.kill()
        self.pool.shutdown(wait=True)


BACKGROUND = Background()


WARM_KERNELS = """
import warnings
warnings.simplefilter("ignore")
import numpy as np
from gdq_pddl.envs.office import CompactEnv, OfficeEnv
from gdq_pddl.learners import METHODS, make_learner, office_task_context, run_episodes
from gdq_pddl.learners.episodes import loops_cached
if not loops_cached(METHODS):
    office = OfficeEnv(task="C")
    compact = CompactEnv(task="C", world=office.world)
    ctx = office_task_context(office.world, "C")
    learners = {}
    def run(name, base):
        if name not in learners:
            learners[name] = make_learner(name, ctx)
        base.reset(seed=0)
        run_episodes(learners[name], base, 3, np.random.default_rng(0))
    for name in ["FF-Replan", "R-max", "Dyna-Q-shaping", "GDQ", "Q-shaping", "Dyna-Q"]:
        run(name, compact if name != "Dyna-Q" else office)
        run(name, office if name != "Dyna-Q" else compact)
    for name in ["Q-learning", "GDQ-code"]:
        run(name, compact)
    for name in METHODS:
        run(name, compact)
        run(name, office)
"""
"""Compiles every learner's kernels into numba's on-disk cache (the one this process uses),
in about the reverse of the order the main process first needs them, so that the two
(and the early subprocesses: the notebook, the examples) load what the other compiled
instead of compiling the same kernels side by side: first the rules classes the early
tests do not run (FF-Replan's, R-max's, a shaping learner's, then the default GDQ's, whose
OptInit the main process has compiled by then, the other shaping learner's), each loop on
both kinds of dynamics (the compact env's first); then Dyna-Q's loops (the office one
first: the notebook and the main process need it next); then the compact loops of
Q-learning and the paper's GDQ, whose office loops and OptInit the early tests compile;
then every learner on both, which loads what is left. Nothing when the loops are cached
already."""


WARMER = Background()
"""Runs :data:`WARM_KERNELS` beside :data:`BACKGROUND`'s queue, not in it: queued first,
its 90 s of compiling on a fresh checkout held up the subprocesses the early tests wait
for (tests/docs), and the main process sat idle."""


def start_warm_kernels() -> Future:
    """Start :data:`WARM_KERNELS` when collection ends: on a fresh checkout the main
    process then loads most learners' kernels instead of compiling them itself. Only a
    cache warmer: a test never waits for it, and whatever it has not compiled yet a test
    compiles (numba writes its cache files whole, and a damaged one is recompiled)."""
    env = {**os.environ, "PYTHONPATH": os.pathsep.join(
        [str(REPO_ROOT), os.environ.get("PYTHONPATH", "")])}
    return WARMER.run("warm kernels", [sys.executable, "-c", WARM_KERNELS], env=env,
                      timeout=900, cwd=REPO_ROOT)


def expanded_rows(online, base):
    """``(row, state, k)`` for each row of OnlineInstance ``online`` whose state was
    expanded: ``state`` the same state's index in ``base`` (the enumerated instance of the
    same problem), ``k`` the row's columns in use (both list a state's ground actions in
    the same order, so the first ``k`` columns compare)."""
    for row in range(online.n_rows):
        x = online.state_of(row)
        if x >= 0 and online.graph.expanded[x]:
            yield row, base.graph.index[online.graph.mask(x)], \
                int((online.columns[row] >= 0).sum())
