"""Where results go: one check of an output folder or file before anything is computed
(:func:`output_folder`, :func:`output_file`), and writes that name their file when they
fail (:func:`writing`, :func:`write_text`, :func:`save_figure`, :func:`atomic_write`),
each an :class:`~gdq_pddl.errors.OutputError`.
"""

from __future__ import annotations

import os
import tempfile
from collections.abc import Callable, Iterator
from contextlib import contextmanager
from pathlib import Path
from typing import TYPE_CHECKING

from gdq_pddl.errors import OutputError

if TYPE_CHECKING:
    from matplotlib.figure import Figure


def output_folder(path: str | Path, option: str = "--out") -> Path:
    """Create the folder ``path`` if needed and check that files can be written in it.

    ``option`` names where the path came from in the message. Returns the path.
    """
    path = Path(path)
    if path.exists() and not path.is_dir():
        raise OutputError(f"{option} {path}: is not a folder (a file or a device); "
                          "give a folder")
    try:
        path.mkdir(parents=True, exist_ok=True)
    except OSError as exc:
        raise OutputError(f"{option} {path}: cannot create the folder: "
                          f"{exc.strerror or exc}") from None
    _probe(path, option)
    return path


def output_file(path: str | Path, option: str = "--out") -> Path:
    """Check that the file ``path`` can be written (its folder is created if needed).

    A folder is refused; a device such as ``/dev/null`` is accepted (writing to it
    works). Nothing is left behind if ``path`` did not exist. Returns the path.
    """
    path = Path(path)
    if path.is_dir():
        raise OutputError(f"{option} {path}: is a folder; give a file name")
    if path.parent.exists() and not path.parent.is_dir():
        raise OutputError(f"{option} {path}: {path.parent} is a file, not a folder")
    if not path.parent.exists():
        output_folder(path.parent, option)
    existed = path.exists()
    try:
        with open(path, "a", encoding="utf-8"):
            pass
    except OSError as exc:
        raise OutputError(f"{option} {path}: cannot write: {exc.strerror or exc}") from None
    if not existed and path.is_file():
        path.unlink()
    return path


@contextmanager
def writing(path: str | Path) -> Iterator[None]:
    """Name ``path`` in an OSError raised while writing it: a full disk (ENOSPC) or an I/O
    error names no file, and the command line printed a bare "No space left on device".
    An OSError that names its own file passes through, and so does a closed pipe."""
    try:
        yield
    except OSError as exc:
        if exc.filename is not None or isinstance(exc, BrokenPipeError):
            raise
        raise OutputError(f"{path}: cannot write: {exc.strerror or exc}") from None


def file_mode() -> int:
    """The permissions a new file gets under the process's umask (``0o644`` under the usual
    ``022``): what :func:`atomic_write` gives its file, since a temporary file is made
    ``0o600`` whatever the umask says."""
    mask = os.umask(0o22)  # reading the umask means setting it: put it straight back
    os.umask(mask)
    return 0o666 & ~mask


def atomic_write(path: str | Path, write: Callable[[Path], None]) -> None:
    """Call ``write(tmp)`` then rename ``tmp`` over ``path``: readers never see half a file
    (an OSError that names no file, a full disk, names ``path``). The file gets the
    permissions the umask gives a new file (:func:`file_mode`), as a plain ``open`` would.

    A process killed in the middle leaves ``.<name>.*.tmp`` next to ``path``
    (:data:`TEMPORARY`), which the next writer of that folder may remove.
    """
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    with writing(path):
        fd, tmp = tempfile.mkstemp(prefix=f".{path.name}.", suffix=".tmp", dir=path.parent)
        os.close(fd)
        try:
            write(Path(tmp))
            os.chmod(tmp, file_mode())
            os.replace(tmp, path)
        finally:
            if os.path.exists(tmp):
                os.unlink(tmp)


TEMPORARY = ".*.tmp"
"""The glob of what :func:`atomic_write` leaves behind when killed mid-write."""


def remove_temporary(folder: Path) -> None:
    """Remove what a killed :func:`atomic_write` left in ``folder`` (nothing if it is not a
    folder); a file only appears under its own name by an atomic rename, so these are
    never results."""
    if folder.is_dir():
        for stale in folder.glob(TEMPORARY):
            stale.unlink(missing_ok=True)


def write_text(path: str | Path, text: str) -> None:
    """``path.write_text(text)`` in UTF-8, through :func:`writing`."""
    with writing(path):
        Path(path).write_text(text, encoding="utf-8")


def save_figure(fig: Figure, path: str | Path, **kwargs: object) -> None:
    """``fig.savefig(path, **kwargs)``, through :func:`writing`."""
    with writing(path):
        fig.savefig(path, **kwargs)


def _probe(folder: Path, option: str) -> None:
    """Write and remove a temporary file in ``folder`` (``/proc`` and read-only file
    systems look writable by their permissions, but are not)."""
    try:
        fd, name = tempfile.mkstemp(prefix=".write-test-", dir=folder)
        os.close(fd)
        os.unlink(name)
    except OSError as exc:
        raise OutputError(f"{option} {folder}: cannot write in this folder: "
                          f"{exc.strerror or exc}") from None
