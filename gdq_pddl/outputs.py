"""Where results go: one check of an output folder or file, before anything is computed.

Every command that writes (``run``, ``switch``, ``robot``, ``reproduce``, ``knowledge``,
``scale``, ``report``, ``building``, ``problem``) calls :func:`output_folder` or
:func:`output_file` first, so an existing file given as ``--out``, a path under a file,
``/dev/null``, ``/proc`` or a read-only file system is one clear
:class:`~gdq_pddl.errors.OutputError` naming the path, not a traceback after the work.
"""

from __future__ import annotations

import os
import tempfile
from pathlib import Path

from gdq_pddl.errors import OutputError


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
