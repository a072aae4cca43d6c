"""Run experiments: units in parallel, each saved atomically, resumable, then collected.

Layout of an output folder::

    config.json      the experiments, seeds and package versions
    units/*.npz      one finished (method, run) each, written atomically by the driver
    episodes.csv     one row per episode (written from units/ at the end)
    policies.csv     each run's final greedy policy, by index and by name
    optimal.json     V* and area relevance of each task, from the true model

A run that is interrupted (Ctrl-C, or killed) loses at most the units in flight;
``resume=True`` checks that the configuration is the same and runs only what is missing.

What a unit returns and what is collected at the end can be swapped (``work`` and
``collect`` of :func:`run_experiments`): ``gdq-pddl pairs`` keeps only returns and
successes per unit and collects one row per run instead of one per episode
(:mod:`gdq_pddl.experiments.pairs`).
"""

from __future__ import annotations

import json
import os
import signal
import sys
import tempfile
import time
from collections.abc import Callable, Iterable
from dataclasses import asdict
from multiprocessing import get_context
from pathlib import Path

import numpy as np

from gdq_pddl.errors import GdqError
from gdq_pddl.experiments.protocol import Experiment, Unit
from gdq_pddl.experiments.work import run_unit


class ResultsError(GdqError):
    """An output folder cannot be used as asked."""


class RunInterrupted(ResultsError):
    """The run was interrupted (Ctrl-C); what finished is saved and ``--resume`` goes on."""


def config_of(experiments: list[Experiment]) -> dict:
    """The JSON-able description of a list of experiments (what --resume compares)."""
    return {"experiments": [asdict(e) for e in experiments]}


def versions() -> dict[str, str]:
    """Versions of the packages that shape the results."""
    from importlib.metadata import PackageNotFoundError, version

    out = {"python": sys.version.split()[0]}
    for pkg in ("gdq_pddl", "numpy", "numba", "gymnasium", "networkx", "unified-planning"):
        try:
            out[pkg] = version(pkg)
        except PackageNotFoundError:
            out[pkg] = "not installed"
    return out


def atomic_write(path: Path, write: Callable[[Path], None]) -> None:
    """Call ``write(tmp)`` then rename ``tmp`` over ``path``: readers never see half a file."""
    path.parent.mkdir(parents=True, exist_ok=True)
    fd, tmp = tempfile.mkstemp(prefix=f".{path.name}.", suffix=".tmp", dir=path.parent)
    os.close(fd)
    try:
        write(Path(tmp))
        os.replace(tmp, path)
    finally:
        if os.path.exists(tmp):
            os.unlink(tmp)


def save_unit(path: Path, result: dict[str, np.ndarray]) -> None:
    def write(tmp: Path) -> None:
        with open(tmp, "wb") as fh:
            np.savez(fh, **result)

    atomic_write(path, write)


def prepare(out: Path, experiments: list[Experiment], resume: bool) -> list[Unit]:
    """Check or create ``out``; return the units still to run."""
    config = config_of(experiments)
    cfg_path = out / "config.json"
    if cfg_path.exists():
        old = json.loads(cfg_path.read_text())
        if not resume:
            raise ResultsError(f"{out} already holds results: continue them with --resume, "
                               "or choose another --out")
        if old.get("experiments") != json.loads(json.dumps(config))["experiments"]:
            raise ResultsError(f"{out} holds results of a different configuration; "
                               "--resume needs the same command line")
    elif resume and (out / "units").exists():
        raise ResultsError(f"{out}: config.json is missing, cannot check what to resume")
    # a run killed in the middle of a write leaves its temporary file (never a unit file:
    # those appear only by an atomic rename); remove them before going on
    for stale in (out / "units").glob(".*.tmp") if (out / "units").exists() else ():
        stale.unlink(missing_ok=True)
    config |= {"versions": versions(), "started": time.strftime("%Y-%m-%d %H:%M:%S")}
    atomic_write(cfg_path, lambda tmp: tmp.write_text(json.dumps(config, indent=2)))
    units = [u for e in experiments for u in e.units()]
    keys = [u.key for u in units]
    if len(set(keys)) != len(keys):
        raise ResultsError("two experiments share a name and schedule; give them distinct names")
    return [u for u in units if not (out / "units" / f"{u.key}.npz").exists()]


Work = Callable[[Unit], dict[str, np.ndarray]]
"""What runs one unit (a module-level function: worker processes and Ray pickle it by name)."""


def run_experiments(experiments: list[Experiment], out: Path, jobs: int | None = None,
                    executor: str = "local", address: str | None = None,
                    resume: bool = False, progress: bool = True, work: Work = run_unit,
                    collect: Callable[[Path, list[Experiment]], None] | None = None) -> Path:
    """Run every unit of ``experiments`` not yet in ``out`` with ``work``, then collect the
    results with ``collect`` (default: :func:`gdq_pddl.experiments.collect.collect`)."""
    if collect is None:
        from gdq_pddl.experiments.collect import collect

    out = Path(out)
    pending = prepare(out, experiments, resume)
    total = sum(e.runs * len(e.methods) for e in experiments)
    # the longest units first, so the last ones to finish are short
    pending.sort(key=lambda u: -u.experiment.episodes)
    bar = _progress(total, total - len(pending), progress)
    units_dir = out / "units"
    try:
        for unit, result in _execute(pending, jobs, executor, address, work):
            save_unit(units_dir / f"{unit.key}.npz", result)
            bar.update(1)
    except KeyboardInterrupt:
        bar.close()
        done = len(list(units_dir.glob("*.npz"))) if units_dir.exists() else 0
        raise RunInterrupted(f"interrupted: {done} of {total} runs are saved in {out}; "
                           "continue with the same command and --resume") from None
    bar.close()
    collect(out, experiments)
    return out


def _progress(total: int, initial: int, enabled: bool):
    from tqdm import tqdm

    return tqdm(total=total, initial=initial, unit="run", desc="runs", dynamic_ncols=True,
                disable=not enabled or not sys.stderr.isatty())


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


def _ignore_sigint() -> None:
    signal.signal(signal.SIGINT, signal.SIG_IGN)  # the driver handles Ctrl-C for everyone


def _run_indexed(job: tuple[int, Unit, Work]) -> tuple[int, dict[str, np.ndarray]]:
    return job[0], job[2](job[1])


def _processes(units: list[Unit], jobs: int, work: Work = run_unit):
    # fork after a warm-up: workers inherit the compiled kernels instead of compiling again
    from gdq_pddl.experiments.work import warm_up

    warm_up(units)
    # multiprocessing.Pool, not ProcessPoolExecutor: on Ctrl-C the workers in flight are
    # terminated, and an executor whose workers were terminated can hang the interpreter
    # at exit (its manager thread waits on a half-written result pipe).
    pool = get_context("fork").Pool(jobs, initializer=_ignore_sigint)
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
        import ray
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
    import socket

    host, sep, port = address.removeprefix("ray://").rpartition(":")
    if not sep or not port.isdigit():
        return  # "auto" and other forms: let Ray resolve them
    try:
        socket.create_connection((host or "127.0.0.1", int(port)), timeout=timeout).close()
    except OSError as exc:
        raise ResultsError(f"cannot reach a Ray cluster at {address}: {exc.strerror or exc}"
                           ) from None
