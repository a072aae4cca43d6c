"""Where results go: one check of an output folder or file, before anything is computed.

Every command that writes (``run``, ``switch``, ``robot``, ``reproduce``, ``knowledge``,
``scale``, ``report``, ``building``, ``problem``) calls :func:`output_folder` or
:func:`output_file` first, so an existing file given as ``--out``, a path under a file,
``/dev/null``, ``/proc`` or a read-only file system is one clear
:class:`~gdq_pddl.errors.OutputError` naming the path, not a traceback after the work.
Every write goes through :func:`writing` (or :func:`write_text`, :func:`save_figure`), so
a disk that fills up during the work is named too.
"""

from __future__ import annotations

import os
import tempfile
from collections.abc import Iterator
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
