"""Where results go: output folders and files checked before anything is computed, and
writes whose failures name their file (an :class:`~gdq_pddl.errors.OutputError`)."""

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
    """Create the folder ``path`` if needed and check that files can be written in it."""
    path = Path(path)
    if path.exists() and not path.is_dir():
        raise OutputError(f"{option} {path}: is not a folder (a file or a device); "
                          "give a folder")
    try:
        path.mkdir(parents=True, exist_ok=True)
    except OSError as exc:
        raise OutputError(f"{option} {path}: cannot create the folder: "
                          f"{exc.strerror or exc}") from None
    try:  # /proc and read-only file systems look writable by their permissions
        fd, name = tempfile.mkstemp(prefix=".write-test-", dir=path)
        os.close(fd)
        os.unlink(name)
    except OSError as exc:
        raise OutputError(f"{option} {path}: cannot write in this folder: "
                          f"{exc.strerror or exc}") from None
    return path


def output_file(path: str | Path, option: str = "--out") -> Path:
    """Check that the file ``path`` can be written (a device can, a folder cannot)."""
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
    """Name ``path`` in an OSError naming no file (a full disk) raised while writing it."""
    try:
        yield
    except OSError as exc:
        if exc.filename is not None or isinstance(exc, BrokenPipeError):
            raise
        raise OutputError(f"{path}: cannot write: {exc.strerror or exc}") from None


def atomic_write(path: str | Path, write: Callable[[Path], None]) -> None:
    """Call ``write(tmp)`` then rename ``tmp`` over ``path`` with the permissions the
    umask gives a new file: readers never see half a file; a process killed midway
    leaves :data:`TEMPORARY`."""
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    with writing(path):
        fd, tmp = tempfile.mkstemp(prefix=f".{path.name}.", suffix=".tmp", dir=path.parent)
        os.close(fd)
        try:
            write(Path(tmp))
            umask = os.umask(0o22)  # reading the umask means setting it: put it straight back
            os.umask(umask)
            os.chmod(tmp, 0o666 & ~umask)  # mkstemp made it 0o600
            os.replace(tmp, path)
        finally:
            if os.path.exists(tmp):
                os.unlink(tmp)


TEMPORARY = ".*.tmp"
"""The glob of what :func:`atomic_write` leaves behind when killed mid-write."""


def remove_temporary(folder: Path) -> None:
    """Remove what a killed :func:`atomic_write` left in ``folder`` (never results)."""
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

