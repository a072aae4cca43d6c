"""Where the units of a run execute (:func:`execute`): in this process, in forked worker
processes (as many as fit in memory: :func:`memory_jobs`), or on a Ray cluster; each way
yields ``(unit, result)`` as units finish. :mod:`gdq_pddl.experiments.runner` hands them
over and saves what they return.
"""

from __future__ import annotations

import os
import socket
import warnings
from collections.abc import Callable, Iterable
from multiprocessing import get_context

import numpy as np

from gdq_pddl.experiments.folder import ResultsError
from gdq_pddl.experiments.interrupts import init_worker
from gdq_pddl.experiments.protocol import Unit
from gdq_pddl.experiments.work import warm_up
from gdq_pddl.limits import human_bytes, physical_memory
from gdq_pddl.pddl.reachable import MEMORY_SHARE

Work = Callable[[Unit], dict[str, np.ndarray]]
"""What runs one unit (a module-level function: worker processes and Ray pickle it by name)."""


def execute(units: list[Unit], jobs: int | None, executor: str, address: str | None,
            work: Work, warm: Callable[[list[Unit]], int] = warm_up
            ) -> Iterable[tuple[Unit, dict[str, np.ndarray]]]:
    """``(unit, work(unit))`` for each of ``units``, in the order they finish: on
    ``executor`` ``"local"`` (``jobs`` processes, forked after ``warm``, which returns the
    bytes each adds; one runs them here) or ``"ray"`` (at ``address``, or a local instance
    of ``jobs`` CPUs)."""
    if not units:
        return iter(())
    if executor == "ray":
        return _ray(units, jobs, address, work)
    if executor != "local":
        raise ResultsError(f"unknown executor {executor!r} (known: local, ray)")
    jobs = jobs or os.cpu_count() or 1
    if jobs == 1 or len(units) == 1:
        return ((u, work(u)) for u in units)
    return _processes(units, jobs, work, warm)


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


def _processes(units: list[Unit], jobs: int, work: Work,
               warm: Callable[[list[Unit]], int]):
    # fork after a warm-up: workers inherit the compiled kernels instead of compiling again
    per_run = warm(units)
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
    pool = get_context("fork").Pool(jobs, initializer=init_worker)
    try:
        tagged = ((i, u, work) for i, u in enumerate(units))
        for i, result in pool.imap_unordered(_run_indexed, tagged):
            yield units[i], result
        pool.close()
    finally:
        pool.terminate()
        pool.join()


def _ray(units: list[Unit], jobs: int | None, address: str | None, work: Work):
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
