"""An output folder as the runner uses it: locked, its ``config.json`` read back, its
input files fingerprinted and its unit files read back or named as damaged."""

from __future__ import annotations

import contextlib
import json
import os
from collections.abc import Iterable, Mapping
from pathlib import Path

import numpy as np

from gdq_pddl.errors import OutputError, ResultsError
from gdq_pddl.experiments.protocol import Unit
from gdq_pddl.inputs import file_hash
from gdq_pddl.outputs import writing

try:
    import fcntl
except ImportError:  # pragma: no cover (not POSIX: no lock, as before)
    fcntl = None

LOCK_NAME = ".lock"


_HELD: set[int] = set()
"""File descriptors of the locks this process holds (forked workers close them)."""


class FolderLock:
    """An exclusive, non-blocking ``flock`` on ``folder/.lock`` for the ``with`` block
    (it ends with the process); entering raises :class:`ResultsError` naming the holder."""

    def __init__(self, folder: Path) -> None:
        self.path = Path(folder) / LOCK_NAME
        self.fd: int | None = None

    def __enter__(self) -> FolderLock:
        if fcntl is None:
            return self
        while True:
            fd = os.open(self.path, os.O_RDWR | os.O_CREAT, 0o644)
            try:
                fcntl.flock(fd, fcntl.LOCK_EX | fcntl.LOCK_NB)
            except OSError:
                holder = os.read(fd, 32).decode(errors="replace").strip() or "unknown"
                os.close(fd)
                raise ResultsError(f"{self.path.parent} is in use by another gdq-pddl "
                                   f"process (pid {holder}, lock {self.path}): wait for it "
                                   "to end, or choose another --out") from None
            if self._current(fd):
                break
            os.close(fd)  # its holder removed that file as it ended: lock the new one
        try:
            with writing(self.path):  # a full disk
                os.ftruncate(fd, 0)
                os.write(fd, f"{os.getpid()}\n".encode())
        except OutputError:
            os.close(fd)  # releases the lock
            raise
        self.fd = fd
        _HELD.add(fd)
        return self

    def _current(self, fd: int) -> bool:
        """Whether ``fd`` is still the file at :attr:`path` (not removed or replaced)."""
        try:
            return os.path.samestat(os.fstat(fd), os.stat(self.path))
        except FileNotFoundError:
            return False

    def __exit__(self, *exc: object) -> None:
        if self.fd is not None:
            _HELD.discard(self.fd)
            with contextlib.suppress(OSError):  # a folder removed under the run
                os.unlink(self.path)  # still locked: nobody can hold it in between
            os.close(self.fd)  # releases the lock
            self.fd = None


def close_inherited_locks() -> None:
    """In a forked worker: close the parent's lock descriptors."""
    for fd in list(_HELD):
        with contextlib.suppress(OSError):
            os.close(fd)
    _HELD.clear()


def read_config(path: Path) -> dict:
    """``config.json`` as a dict; :class:`ResultsError` naming it if it is not one."""
    try:
        raw = json.loads(path.read_text(encoding="utf-8"))
    except OSError as exc:
        raise ResultsError(f"{path}: cannot read: {exc.strerror or exc}") from None
    except ValueError as exc:  # JSONDecodeError, UnicodeDecodeError
        raise ResultsError(f"{path} is damaged (not JSON: {exc}); it records what the "
                           "folder holds, so --resume cannot go on: start again in another "
                           "--out") from None
    if not isinstance(raw, dict):
        raise ResultsError(f"{path} is damaged (a JSON {type(raw).__name__}, not an "
                           "object); --resume cannot go on: start again in another --out")
    return raw


def resume_config(out: Path, held: bool, resume: bool, results: str) -> dict | None:
    """The ``config.json`` of the run ``resume`` continues (None when not resuming); refuses
    a folder that holds ``results`` without ``resume``, and with it, one without config."""
    cfg_path = out / "config.json"
    if held and not resume:
        if cfg_path.exists():
            raise ResultsError(f"{out} already holds results: continue them with --resume, "
                               f"start again beside them with --out {free_folder(out)}, or "
                               f"delete {out} to replace them")
        raise ResultsError(f"{out} holds results ({results}) but no config.json saying of "
                           "what: they cannot be checked, so they are not reused; start "
                           f"again with --out {free_folder(out)}, or delete them")
    if not resume:
        return None
    if not cfg_path.exists():
        if held:
            raise ResultsError(f"{out}: config.json is missing, cannot check what to resume")
        raise ResultsError(f"--resume: {out} holds no run to continue (no config.json "
                           "there); to start one, give the same command without --resume")
    return read_config(cfg_path)


def free_folder(out: Path) -> Path:
    """``out`` with the first suffix ``-2``, ``-3``, ... that names nothing yet: the folder
    the message of a rerun suggests."""
    base = out if out.name else out.resolve()
    if not base.name:  # the root folder
        return Path("results-2")
    k = 2
    while (found := base.with_name(f"{base.name}-{k}")).exists():
        k += 1
    return found


def input_hashes(files: Iterable[str]) -> dict[str, str]:
    """``{file: "sha256:..."}`` of every input file (in order, without repeats)."""
    return {f: file_hash(f) for f in dict.fromkeys(files)}


def changed_input(old: Mapping, new: Mapping[str, str]) -> str | None:
    """The first input file whose hash differs between ``old`` and ``new``, or None."""
    return next((f for f, h in new.items() if f in old and old[f] != h), None)


def load_unit(path: Path, what: str, expect: Mapping[str, int]) -> dict[str, np.ndarray]:
    """The arrays of the unit file ``path``; :class:`ResultsError` naming ``what`` if it
    is damaged. ``expect``: each array the unit must hold -> its length (-1: any)."""
    try:
        with np.load(path) as saved:
            data = {k: saved[k] for k in saved.files}
    except FileNotFoundError:
        raise ResultsError(f"{path} ({what}) is missing: rerun it with the same command "
                           "and --resume") from None
    except Exception as exc:  # zipfile, numpy format and OS errors of a damaged file
        raise _damaged(path, what, f"{type(exc).__name__}: {exc}") from None
    for key, length in expect.items():
        if key not in data:
            raise _damaged(path, what, f"no array {key!r}")
        shape = data[key].shape
        if length >= 0 and (not shape or shape[0] != length):
            raise _damaged(path, what, f"{key} has {shape[0] if shape else 0} entries, "
                           f"expected {length}")
    return data


def _damaged(path: Path, what: str, why: str) -> ResultsError:
    return ResultsError(f"{path} ({what}) is damaged ({why}): delete it and run the same "
                        "command with --resume to rerun that run alone")


UNIT_ARRAYS = ("returns", "steps", "success", "areas", "tasks", "counts", "policy")
"""What :func:`~gdq_pddl.experiments.work.run_unit` saves of a unit."""
PER_EPISODE = ("returns", "steps", "success", "areas")
"""The arrays with one entry per episode."""


def unit_path(out: Path, unit: Unit) -> Path:
    """Where ``unit``'s results are saved in the output folder ``out``."""
    return out / "units" / f"{unit.key}.npz"


def read_unit(out: Path, unit: Unit, arrays: tuple[str, ...] = UNIT_ARRAYS
              ) -> dict[str, np.ndarray]:
    """The saved ``arrays`` of ``unit``; :class:`ResultsError` naming it if damaged."""
    n = unit.experiment.episodes
    return load_unit(unit_path(out, unit), f"{unit.method}, run {unit.run} of "
                     f"{unit.experiment.name}",
                     {k: n if k in PER_EPISODE else -1 for k in arrays})
