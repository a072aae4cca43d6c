"""Run experiments: units in parallel, each saved atomically, resumable, then collected.

Layout of an output folder::

    config.json      the experiments, seeds and package versions
    units/*.npz      one finished (method, run) each, written atomically by the driver
    episodes.csv     one row per episode (written from units/ at the end)
    policies.csv     each run's final greedy policy, by index and by name
    optimal.json     V* and area relevance of each task, from the true model
    learners/*.npz   with keep_learners: each run's final learner, named as its unit

An interrupted run loses at most the units in flight; ``resume=True`` checks that the
configuration and every input file are the same and runs only what is missing. Where the
units run is :mod:`~gdq_pddl.experiments.executors`; how a stop is caught,
:mod:`~gdq_pddl.experiments.interrupts`.
"""

from __future__ import annotations

import json
import os
import signal
import sys
import time
from collections.abc import Callable, Mapping
from dataclasses import asdict
from importlib.metadata import PackageNotFoundError, version
from pathlib import Path
from typing import Any

import numpy as np

from gdq_pddl.errors import ConfigError
from gdq_pddl.experiments.checks import preflight
from gdq_pddl.experiments.collect import collect as collect_episodes
from gdq_pddl.experiments.executors import Work, execute
from gdq_pddl.experiments.folder import (
    UNIT_ARRAYS,
    FolderLock,
    ResultsError,
    changed_input,
    input_hashes,
    read_config,
    read_unit,
    resume_config,
    unit_path,
)
from gdq_pddl.experiments.interrupts import RunInterrupted, stop_on_signals
from gdq_pddl.experiments.knowledge import is_file_name
from gdq_pddl.experiments.protocol import Experiment, ProblemSpec, Unit
from gdq_pddl.experiments.work import run_unit, warm_up
from gdq_pddl.limits import Progress, check_count
from gdq_pddl.outputs import atomic_write, output_folder, remove_temporary

__all__ = ["ResultsError", "RunInterrupted", "atomic_write", "read_unit", "run_experiments"]


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
    named = [f for e in experiments
             for f in (*(e.pddl.files if e.pddl else ()), e.world, e.knowledge)]
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


OPTION_FLAGS = {"keep_learners": "--keep-learners", "explore": "--explore"}
"""The options config.json records under ``options`` (what ``--resume`` compares), and
the command-line flag that sets each."""


def _flag(key: str, value: object) -> str:
    """An option's value as the command line says it."""
    flag = OPTION_FLAGS.get(key, key)
    if isinstance(value, bool):
        return flag if value else f"no {flag}"
    return f"{flag} {value}"


def recorded_options(out: Path, old: Mapping[str, Any]) -> dict[str, Any]:
    """The options of the run ``old`` (its config.json) began with; where it predates
    their record: ``keep_learners`` as its saved units say (None: nothing saved)."""
    options = old.get("options")
    if isinstance(options, dict):
        return dict(options)
    units = out / "units"
    if not (units.is_dir() and any(units.glob("*.npz"))):
        return {}
    learners = out / "learners"
    return {"keep_learners": learners.is_dir() and any(learners.glob("*.npz"))}


def check_options(out: Path, old: Mapping[str, Any], options: Mapping[str, Any]) -> None:
    """Refuse to resume the run of ``old`` (its config.json) with other ``options``,
    naming the option, what the run began with and what the command gives."""
    recorded = recorded_options(out, old)
    for key, value in options.items():
        if key in recorded and recorded[key] != value:
            said = f"config.json options.{key}" if isinstance(old.get("options"), dict) \
                else "its saved units/ and learners/: its config.json predates options"
            raise ResultsError(f"{_flag(key, value)}: the run in {out} began with "
                               f"{_flag(key, recorded[key])} ({said}); "
                               "--resume needs the same command line, so that every run of "
                               "it is done alike")


def resumed_exploration(out: Path, explore: str) -> str:
    """How ``--explore explore`` goes on with the run in ``out`` (``--resume``), read from
    its config.json before any work: ``online`` or ``enumerate`` as the run went (for
    ``auto``: what it chose then, so it is not chosen again by enumerating first), or
    ``explore`` itself where the folder holds no run. Refuses another ``--explore`` than
    the run began with (or, where it predates that record, than the way it went)."""
    path = out / "config.json"
    if not path.is_file():
        return explore  # nothing to continue: resume_config says so
    old = read_config(path)
    exps = upgraded(old.get("experiments"))
    went = "online" if isinstance(exps, list) and any(
        isinstance(e, dict) and isinstance(e.get("pddl"), dict) and
        e["pddl"].get("exploration") == "online" for e in exps) else "enumerate"
    recorded = recorded_options(out, old).get("explore")
    if recorded is not None:
        check_options(out, old, {"explore": explore})
    elif explore != "auto" and explore != went:
        raise ResultsError(f"--explore {explore}: the run in {out} explored its problem "
                           f"{'online' if went == 'online' else 'by enumerating its states'} "
                           "(config.json); --resume needs the same command line")
    return went if explore == "auto" else explore


def upgraded(old: object) -> object:
    """A config.json's ``experiments`` as this version records them: a problem recorded
    as the list of earlier versions becomes its :class:`ProblemSpec`'s fields (so
    ``--resume`` continues those folders); anything else as it is."""
    return [e | {"pddl": asdict(ProblemSpec.from_record(e["pddl"]))}
            if isinstance(e, dict) and isinstance(e.get("pddl"), list) else e
            for e in old] if isinstance(old, list) else old


def prepare(out: Path, experiments: list[Experiment], resume: bool,
            arrays: tuple[str, ...] = UNIT_ARRAYS,
            options: Mapping[str, Any] | None = None) -> list[Unit]:
    """Check or create ``out``; return the units still to run (saved ones are reused on
    ``resume`` when ``config.json`` says they are of the same experiments, inputs and
    ``options``: :data:`OPTION_FLAGS`)."""
    units = [u for e in experiments for u in e.units()]
    check_unit_keys(units)
    options = dict(options or {})
    config = {"experiments": [asdict(e) for e in experiments],  # what --resume compares
              "inputs": input_hashes(input_files(experiments)), "options": options}
    old = resume_config(out, _held(out), resume, "units/*.npz or episodes.csv")
    if old is not None:
        check_options(out, old, options)
        new = json.loads(json.dumps(config["experiments"]))
        recorded = upgraded(old.get("experiments"))
        if recorded != new:
            raise ResultsError(f"{out} holds results of a different configuration "
                               f"({_difference(recorded, new)}); --resume "
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
            if options.get("keep_learners") and not (out / "learners" / f"{u.key}.npz"
                                                     ).exists():
                raise ResultsError(f"{unit_path(out, u)} has no learner in "
                                   f"{out / 'learners'} (saved without --keep-learners): "
                                   "delete it and run the same command with --resume to "
                                   "rerun that run alone, its learner kept")
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


def run_experiments(experiments: list[Experiment], out: Path, jobs: int | None = None,
                    executor: str = "local", address: str | None = None,
                    resume: bool = False, progress: bool = True, work: Work | None = None,
                    collect: Callable[[Path, list[Experiment]], None] | None = None,
                    log: Callable[[str], None] | None = None,
                    unit_arrays: tuple[str, ...] = UNIT_ARRAYS, keep_learners: bool = False,
                    options: Mapping[str, Any] | None = None,
                    check: Callable[[list[Experiment], int], None] = preflight,
                    warm: Callable[[list[Unit]], int] = warm_up) -> Path:
    """Run every unit of ``experiments`` not yet in ``out`` with ``work`` (default:
    :func:`run_unit`), then ``collect`` the results (default:
    :func:`gdq_pddl.experiments.collect.collect`); ``check`` refuses, before the folder
    is touched, experiments that cannot run on that many processes (default:
    :func:`~gdq_pddl.experiments.checks.preflight`), ``warm`` compiles what forked workers
    inherit and says the bytes each adds (default: :func:`~gdq_pddl.experiments.work.warm_up`;
    both replaced by ``gdq-pddl scale``, whose units are not :func:`run_unit`'s).

    ``log`` is told how many runs are left; ``unit_arrays`` are what ``work`` saves (what
    ``--resume`` checks); ``keep_learners`` saves each run's final learner in
    ``learners/``. ``keep_learners`` and ``options`` (the command-line options that shape
    the runs but not the experiments, :data:`OPTION_FLAGS`) are recorded in config.json;
    ``resume`` refuses other values. Ctrl-C, SIGTERM and SIGHUP end the workers and raise
    :class:`RunInterrupted`, saying what is saved and how to go on.
    """
    # read at call time: tests replace run_unit
    work = work or (run_unit_keeping_learner if keep_learners else run_unit)
    collect = collect or collect_episodes
    out = Path(out)
    wanted = check_jobs(jobs)
    check(experiments, wanted)
    output_folder(out)
    with FolderLock(out), stop_on_signals():
        pending = prepare(out, experiments, resume, unit_arrays,
                          {"keep_learners": bool(keep_learners), **(options or {})})
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
                             progress, work, warm)
                _check_unchanged(out, experiments)
                collect(out, experiments)
            except KeyboardInterrupt as exc:  # Ctrl-C, or SIGTERM / SIGHUP (stop_on_signals)
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
                 work: Work = run_unit, warm: Callable[[list[Unit]], int] = warm_up
                 ) -> None:
    total = sum(e.runs * len(e.methods) for e in experiments)
    # the longest units first, so the last ones to finish are short
    pending.sort(key=lambda u: -u.experiment.episodes)
    # a bar on a terminal, else a line at least every 30 s (a log shows the run is alive)
    bar = Progress(total, total - len(pending), enabled=progress)
    units_dir = out / "units"
    try:
        for unit, result in execute(pending, jobs, executor, address, work, warm):
            learner = result.pop("learner", None)
            if learner is not None:  # before its unit: a saved unit has its learner
                atomic_write(out / "learners" / f"{unit.key}.npz",
                             lambda tmp, data=learner: tmp.write_bytes(data.tobytes()))
            save_unit(units_dir / f"{unit.key}.npz", result)
            bar.update(1)
    finally:
        bar.close()


