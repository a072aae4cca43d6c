"""Run experiments: units in parallel, each saved atomically, resumable, then collected.

Layout of an output folder::

    config.json      the experiments, seeds and package versions
    units/*.npz      one finished (method, run) each, written atomically by the driver
    episodes.csv     one row per episode (written from units/ at the end)
    policies.csv     each run's final greedy policy, by index and by name
    optimal.json     V* and area relevance of each task, from the true model
    learners/*.npz   with keep_learners: each run's final learner, named as its unit

An interrupted run loses at most the units in flight; ``resume=True`` checks that the
configuration and every input file are the same and runs only what is missing.
"""

from __future__ import annotations

import ctypes
import json
import os
import signal
import socket
import sys
import time
import warnings
from collections.abc import Callable, Iterable, Iterator
from contextlib import contextmanager
from dataclasses import asdict
from importlib.metadata import PackageNotFoundError, version
from multiprocessing import get_context
from pathlib import Path

import numpy as np
from tqdm import tqdm

from gdq_pddl.errors import ConfigError
from gdq_pddl.experiments.checks import preflight
from gdq_pddl.experiments.collect import collect as collect_episodes
from gdq_pddl.experiments.folder import (
    UNIT_ARRAYS,
    FolderLock,
    ResultsError,
    changed_input,
    close_inherited_locks,
    input_hashes,
    read_config,
    read_unit,
    resume_config,
    unit_path,
)
from gdq_pddl.experiments.knowledge import is_file_name
from gdq_pddl.experiments.protocol import Experiment, Unit
from gdq_pddl.experiments.work import run_unit, warm_up
from gdq_pddl.limits import check_count, human_bytes, physical_memory
from gdq_pddl.outputs import atomic_write, output_folder, remove_temporary
from gdq_pddl.pddl.reachable import MEMORY_SHARE

__all__ = ["ResultsError", "RunInterrupted", "atomic_write", "read_unit", "run_experiments"]


class RunInterrupted(ResultsError):
    """The run was stopped (Ctrl-C, SIGTERM or SIGHUP: ``signal``); what finished is saved."""

    def __init__(self, message: str, signum: int = signal.SIGINT) -> None:
        super().__init__(message)
        self.signal = signum

    def __reduce__(self):
        return type(self), (str(self), self.signal)


class _Stopped(KeyboardInterrupt):
    """SIGTERM or SIGHUP in the driver, raised as Ctrl-C's KeyboardInterrupt would be."""

    def __init__(self, signum: int) -> None:
        super().__init__(signal.Signals(signum).name)
        self.signal = signum


STOP_SIGNALS = (signal.SIGTERM, getattr(signal, "SIGHUP", signal.SIGTERM))
"""The signals besides SIGINT (Ctrl-C) that stop a run cleanly: its workers end with it."""


@contextmanager
def _stop_on_signals() -> Iterator[None]:
    """While the block runs, SIGTERM and SIGHUP raise :class:`_Stopped` (main thread only)."""
    def stop(signum: int, _frame: object) -> None:
        raise _Stopped(signum)

    try:
        previous = {s: signal.signal(s, stop) for s in STOP_SIGNALS}
    except ValueError:  # not the main thread
        yield
        return
    try:
        yield
    finally:
        for s, handler in previous.items():
            signal.signal(s, handler)


def versions() -> dict[str, str]:
    """Versions of the packages that shape the results."""
    out = {"python": sys.version.split()[0]}
    for pkg in ("gdq_pddl", "numpy", "numba", "gymnasium", "networkx", "unified-planning"):
        try:
            out[pkg] = version(pkg)
        except PackageNotFoundError:
            out[pkg] = "not installed"
    return out


def save_unit(path: Path, result: dict[str, np.ndarray], compressed: bool = False) -> None:
    """Write the arrays ``result`` to ``path`` as an ``.npz`` file, atomically."""
    def write(tmp: Path) -> None:
        with open(tmp, "wb") as fh:
            (np.savez_compressed if compressed else np.savez)(fh, **result)

    atomic_write(path, write)


def input_files(experiments: list[Experiment]) -> list[str]:
    """The input files the experiments name (PDDL files, world files)."""
    named = [f for e in experiments for f in (*(e.pddl or ())[:3], e.world, e.knowledge)]
    return [f for f in named if f and is_file_name(f)]


def _held(out: Path) -> bool:
    """Whether ``out`` holds results: a saved unit, or the collected episodes."""
    units = out / "units"
    return (out / "episodes.csv").exists() or units.is_dir() and any(units.glob("*.npz"))


def _difference(old: object, new: list) -> str:
    """What differs between two ``experiments`` lists of config.json, in words."""
    if isinstance(old, list) and len(old) == len(new):
        for o, n in zip(old, new, strict=True):
            if not isinstance(o, dict):
                break
            for key, value in n.items():
                if o.get(key) != value:
                    return f"experiment {n.get('name')}: {key} was {o.get(key)}, now {value}"
    return "the experiments differ"


def prepare(out: Path, experiments: list[Experiment], resume: bool,
            arrays: tuple[str, ...] = UNIT_ARRAYS) -> list[Unit]:
    """Check or create ``out``; return the units still to run (saved ones are reused on
    ``resume`` when ``config.json`` says they are of the same experiments and inputs)."""
    units = [u for e in experiments for u in e.units()]
    check_unit_keys(units)
    config = {"experiments": [asdict(e) for e in experiments],  # what --resume compares
              "inputs": input_hashes(input_files(experiments))}
    old = resume_config(out, _held(out), resume, "units/*.npz or episodes.csv")
    if old is not None:
        new = json.loads(json.dumps(config["experiments"]))
        if old.get("experiments") != new:
            raise ResultsError(f"{out} holds results of a different configuration "
                               f"({_difference(old.get('experiments'), new)}); --resume "
                               "needs the same command line")
        inputs = old.get("inputs") if isinstance(old.get("inputs"), dict) else {}
        changed = changed_input(inputs, config["inputs"])
        if changed:
            raise ResultsError(f"{changed} changed since the run in {out} began (its content "
                               "differs from what config.json records): resuming would mix "
                               "results of both versions; restore it, or start again in "
                               "another --out")
    for folder in (out, out / "units", out / "learners"):
        remove_temporary(folder)  # what a write killed midway left
    config |= {"versions": versions(), "started": time.strftime("%Y-%m-%d %H:%M:%S")}
    atomic_write(out / "config.json", lambda tmp: tmp.write_text(json.dumps(config, indent=2)))
    done = [u for u in units if unit_path(out, u).exists()]
    if resume:
        for u in done:  # a damaged unit file: say which, before running the others
            read_unit(out, u, arrays)
    return [u for u in units if not unit_path(out, u).exists()]


def check_unit_keys(units: list[Unit]) -> None:
    """Refuse units that would be saved under one file name, naming both and the file."""
    seen: dict[str, Unit] = {}
    for u in units:
        other = seen.setdefault(u.key, u)
        if other is not u:
            raise ResultsError(
                f"{other.method} run {other.run} of experiment {other.experiment.name!r} "
                f"(schedule {_schedule(other)}) and {u.method} run {u.run} of experiment "
                f"{u.experiment.name!r} (schedule {_schedule(u)}) would both be saved as "
                f"units/{u.key}.npz; give the experiments distinct names")


def _schedule(unit: Unit) -> str:
    return " then ".join(f"{t} x {n}" for t, n in unit.experiment.schedule)


def saved_units(out: Path, experiments: list[Experiment]) -> int:
    """How many units of ``experiments`` are saved in ``out``."""
    return sum(unit_path(Path(out), u).exists() for e in experiments for u in e.units())


def check_jobs(jobs: int | None) -> int:
    """The number of processes ``jobs`` asks for (None: every core); ConfigError if < 1."""
    if jobs is None:
        return os.cpu_count() or 1
    check_count("jobs", jobs)
    if jobs < 1:
        raise ConfigError(f"jobs must be at least 1, got {jobs}")
    return jobs


def run_unit_keeping_learner(unit: Unit) -> dict[str, np.ndarray]:
    """:func:`run_unit` returning the final learner's file too (Ray takes no partial)."""
    return run_unit(unit, keep_learner=True)


Work = Callable[[Unit], dict[str, np.ndarray]]
"""What runs one unit (a module-level function: worker processes and Ray pickle it by name)."""


def run_experiments(experiments: list[Experiment], out: Path, jobs: int | None = None,
                    executor: str = "local", address: str | None = None,
                    resume: bool = False, progress: bool = True, work: Work | None = None,
                    collect: Callable[[Path, list[Experiment]], None] | None = None,
                    log: Callable[[str], None] | None = None,
                    unit_arrays: tuple[str, ...] = UNIT_ARRAYS, keep_learners: bool = False
                    ) -> Path:
    """Run every unit of ``experiments`` not yet in ``out`` with ``work`` (default:
    :func:`run_unit`), then ``collect`` the results (default:
    :func:`gdq_pddl.experiments.collect.collect`).

    ``log`` is told how many runs are left; ``unit_arrays`` are what ``work`` saves (what
    ``--resume`` checks); ``keep_learners`` saves each run's final learner in
    ``learners/``. Ctrl-C, SIGTERM and SIGHUP end the workers and raise
    :class:`RunInterrupted`, saying what is saved and how to go on.
    """
    # read at call time: tests replace run_unit
    work = work or (run_unit_keeping_learner if keep_learners else run_unit)
    collect = collect or collect_episodes
    out = Path(out)
    wanted = check_jobs(jobs)
    preflight(experiments, wanted)
    output_folder(out)
    with FolderLock(out), _stop_on_signals():
        pending = prepare(out, experiments, resume, unit_arrays)
        processes = min(wanted, max(1, len(pending)))
        if log is not None and not pending:
            log(f"nothing to run: all {sum(len(e.units()) for e in experiments)} runs are "
                f"saved in {out}; writing its results again")
        elif log is not None and executor == "local":
            capped = f" (--jobs {jobs} capped at the runs to do)" if jobs and jobs > processes \
                else ""
            log(f"{len(pending)} run(s) to do on {processes} process(es){capped}")
        try:
            try:
                _run_pending(out, experiments, pending,
                             processes if executor == "local" else jobs, executor, address,
                             progress, work)
                _check_unchanged(out, experiments)
                collect(out, experiments)
            except KeyboardInterrupt as exc:  # Ctrl-C, or SIGTERM / SIGHUP (_Stopped)
                raise _interrupted(out, experiments, resume, exc) from None
        except Exception:
            if not resume and not _held(out):  # nothing saved: leave no config.json behind
                (out / "config.json").unlink(missing_ok=True)
            raise
    return out


def _check_unchanged(out: Path, experiments: list[Experiment]) -> None:
    """Refuse to collect runs whose input files changed while they ran (their content must
    be what config.json records)."""
    recorded = read_config(out / "config.json").get("inputs")
    changed = changed_input(recorded if isinstance(recorded, dict) else {},
                            input_hashes(input_files(experiments)))
    if changed:
        raise ResultsError(f"{changed} changed while the runs in {out} went on (its content "
                           "differs from what config.json records): some runs may have read "
                           "one version and some the other; restore it and delete the runs "
                           "saved since, or start again in another --out")


def _interrupted(out: Path, experiments: list[Experiment], resume: bool,
                 exc: KeyboardInterrupt) -> RunInterrupted:
    """What to tell after a stop: what is saved, and the command that goes on from it."""
    signum = getattr(exc, "signal", signal.SIGINT)
    what = "interrupted" if signum == signal.SIGINT else \
        f"stopped by {signal.Signals(signum).name}"
    total = sum(len(e.units()) for e in experiments)
    done = saved_units(out, experiments)
    if done == 0 and not resume:
        return RunInterrupted(f"{what} before any run was saved; nothing is kept in {out}: "
                              "to start again, give the same command (without --resume)",
                              signum)
    return RunInterrupted(f"{what}: {done} of {total} runs are saved in {out}; continue "
                          "with the same command and --resume", signum)


def _run_pending(out: Path, experiments: list[Experiment], pending: list[Unit],
                 jobs: int | None, executor: str, address: str | None, progress: bool,
                 work: Work = run_unit) -> None:
    total = sum(e.runs * len(e.methods) for e in experiments)
    # the longest units first, so the last ones to finish are short
    pending.sort(key=lambda u: -u.experiment.episodes)
    bar = tqdm(total=total, initial=total - len(pending), unit="run", desc="runs",
               dynamic_ncols=True, disable=not progress or not sys.stderr.isatty())
    units_dir = out / "units"
    try:
        for unit, result in _execute(pending, jobs, executor, address, work):
            learner = result.pop("learner", None)
            if learner is not None:  # before its unit: a saved unit has its learner
                atomic_write(out / "learners" / f"{unit.key}.npz",
                             lambda tmp, data=learner: tmp.write_bytes(data.tobytes()))
            save_unit(units_dir / f"{unit.key}.npz", result)
            bar.update(1)
    finally:
        bar.close()


def _execute(units: list[Unit], jobs: int | None, executor: str, address: str | None,
             work: Work = run_unit) -> Iterable[tuple[Unit, dict[str, np.ndarray]]]:
    if not units:
        return iter(())
    if executor == "ray":
        return _ray(units, jobs, address, work)
    if executor != "local":
        raise ResultsError(f"unknown executor {executor!r} (known: local, ray)")
    jobs = jobs or os.cpu_count() or 1
    if jobs == 1 or len(units) == 1:
        return ((u, work(u)) for u in units)
    return _processes(units, jobs, work)


def _init_worker() -> None:
    signal.signal(signal.SIGINT, signal.SIG_IGN)  # the driver handles Ctrl-C for everyone
    for s in STOP_SIGNALS:  # the driver's handlers, inherited by the fork: end quietly
        signal.signal(s, signal.SIG_DFL)
    _die_with_parent()
    close_inherited_locks()


PR_SET_PDEATHSIG = 1
"""Linux's ``prctl`` option: the signal a process gets when its parent dies."""


def _die_with_parent() -> None:
    """Have the kernel send this worker SIGTERM when the driver dies, SIGKILL included, so
    no worker runs on as an orphan (Linux only)."""
    if not sys.platform.startswith("linux"):
        return
    try:
        libc = ctypes.CDLL(None, use_errno=True)
        libc.prctl(PR_SET_PDEATHSIG, signal.SIGTERM, 0, 0, 0)
    except (OSError, AttributeError):  # pragma: no cover (no libc prctl)
        return
    if os.getppid() == 1:  # the driver died before the prctl took effect
        os._exit(1)


def _run_indexed(job: tuple[int, Unit, Work]) -> tuple[int, dict[str, np.ndarray]]:
    return job[0], job[2](job[1])


def memory_jobs(jobs: int, per_run: int, have: int, in_use: int) -> int:
    """How many of ``jobs`` worker processes fit in memory: each adds its learner's tables
    (``per_run`` bytes) to what it shares with the parent (``in_use``, the instance and
    its plans, inherited copy-on-write), within :data:`MEMORY_SHARE` of ``have``; at
    least 1, as one process is the run itself (its tables were checked to fit)."""
    free = MEMORY_SHARE * have - in_use
    return max(1, min(jobs, int(free // max(1, per_run))))


def _resident_bytes() -> int:
    """This process's resident memory now; 0 where /proc does not say (not Linux)."""
    try:
        with open("/proc/self/statm") as f:
            return int(f.read().split()[1]) * os.sysconf("SC_PAGE_SIZE")
    except (OSError, ValueError, IndexError):
        return 0


def _processes(units: list[Unit], jobs: int, work: Work = run_unit):
    # fork after a warm-up: workers inherit the compiled kernels instead of compiling again
    per_run = warm_up(units)
    fit = memory_jobs(jobs, per_run, physical_memory(), _resident_bytes())
    if fit < jobs:  # each worker's tables on top: more would be killed for memory
        warnings.warn(f"{jobs} worker processes (--jobs) capped at {fit}: each run's "
                      f"learner tables take {human_bytes(per_run)}, and this machine has "
                      f"{human_bytes(physical_memory())} (GDQ_PDDL_MEMORY), "
                      f"{human_bytes(_resident_bytes())} of it held already", stacklevel=2)
        jobs = fit
        if jobs == 1:
            yield from ((u, work(u)) for u in units)
            return
    # multiprocessing.Pool, not ProcessPoolExecutor: on Ctrl-C the workers in flight are
    # terminated, and an executor whose workers were terminated can hang the interpreter
    # at exit (its manager thread waits on a half-written result pipe).
    pool = get_context("fork").Pool(jobs, initializer=_init_worker)
    try:
        tagged = ((i, u, work) for i, u in enumerate(units))
        for i, result in pool.imap_unordered(_run_indexed, tagged):
            yield units[i], result
        pool.close()
    finally:
        pool.terminate()
        pool.join()


def _ray(units: list[Unit], jobs: int | None, address: str | None, work: Work = run_unit):
    try:
        import ray  # optional dependency: imported only when --executor ray asks for it
    except ImportError:
        raise ResultsError("--executor ray needs the optional package ray "
                           "(pip install 'gdq_pddl[ray]')") from None
    started = not ray.is_initialized()
    if started:
        if address:
            _check_reachable(address)
        kwargs = {"address": address} if address else {"num_cpus": jobs or os.cpu_count()}
        try:
            ray.init(include_dashboard=False, log_to_driver=False, **kwargs)
        except Exception as exc:  # connection refused, bad address ...
            raise ResultsError(f"cannot reach a Ray cluster at {address or 'local'}: "
                               f"{exc}") from None
    remote = ray.remote(work)
    try:
        refs = {remote.remote(u): u for u in units}
        pending = list(refs)
        while pending:
            done, pending = ray.wait(pending, num_returns=1)
            for ref in done:
                yield refs[ref], ray.get(ref)
    finally:
        if started:
            ray.shutdown()


def _check_reachable(address: str, timeout: float = 5.0) -> None:
    """Fail fast on a ``host:port`` nobody answers (ray.init retries for minutes)."""
    host, sep, port = address.removeprefix("ray://").rpartition(":")
    if not sep or not port.isdigit():
        return  # "auto" and other forms: let Ray resolve them
    try:
        socket.create_connection((host or "127.0.0.1", int(port)), timeout=timeout).close()
    except OSError as exc:
        raise ResultsError(f"cannot reach a Ray cluster at {address}: {exc.strerror or exc}"
                           ) from None
