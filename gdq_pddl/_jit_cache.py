"""Keep numba's on-disk cache of this package's compiled functions in step with the source
(numba bakes in the code a function calls from other files): when the sources of
:data:`JIT_FOLDERS` change, the cache files are deleted; a damaged one (not whole
pickles) is deleted too, or numba gets a cache folder of its own.
"""

from __future__ import annotations

import contextlib
import hashlib
import io
import json
import os
import pickletools
import tempfile
from pathlib import Path

from gdq_pddl.errors import GdqError
from gdq_pddl.outputs import atomic_write

PACKAGE = Path(__file__).resolve().parent
JIT_FOLDERS = ("envs", "learners", "planning")
"""Subpackages whose modules have (or call) compiled functions."""
STAMP = Path("learners", "__pycache__", "jit-sources.sha256")
"""Where, under the package, the digest the cache was built with is kept."""
CHECKED = Path("learners", "__pycache__", "jit-checked.json")
"""Where, under the package, the cache files already read whole are listed."""
PICKLES = {".nbi": 2, ".nbc": 1}
"""How many pickles numba writes one after the other in each kind of cache file."""


def sources_digest(root: Path = PACKAGE) -> str:
    """SHA-256 of every ``.py`` file of :data:`JIT_FOLDERS` under ``root``, in path order."""
    h = hashlib.sha256()
    for folder in JIT_FOLDERS:
        for path in sorted((root / folder).glob("*.py")):
            h.update(path.name.encode())
            h.update(path.read_bytes())
    return h.hexdigest()


def cache_files(root: Path = PACKAGE) -> list[Path]:
    """numba's cache files (index and data) under ``root``."""
    return [path for folder in JIT_FOLDERS for pattern in ("*.nbi", "*.nbc")
            for path in sorted((root / folder / "__pycache__").glob(pattern))]


def refresh(root: Path = PACKAGE) -> bool:
    """Delete stale and damaged numba cache files; True when the sources changed."""
    digest, stamp = sources_digest(root), root / STAMP
    try:
        fresh = stamp.read_text() == digest
    except OSError:
        fresh = False
    if fresh:
        remove_damaged(root)
        return False
    try:
        for path in cache_files(root):
            path.unlink(missing_ok=True)
        stamp.parent.mkdir(exist_ok=True)
        stamp.write_text(digest)
    except OSError:
        remove_damaged(root)
        return False
    return True


def is_whole(data: bytes, pickles: int) -> bool:
    """Whether ``data`` is exactly ``pickles`` complete pickles, one after the other."""
    stream = io.BytesIO(data)
    try:
        for _ in range(pickles):
            for _op in pickletools.genops(stream):
                pass
    except (ValueError, EOFError, KeyError):  # cut short, or not a pickle at all
        return False
    return stream.tell() == len(data)


def remove_damaged(root: Path = PACKAGE) -> list[Path]:
    """Delete the cache files under ``root`` that are not whole pickles; returns them."""
    record_path = root / CHECKED
    try:
        record = json.loads(record_path.read_text())
        if not isinstance(record, dict):
            record = {}
    except (OSError, ValueError):
        record = {}
    checked: dict[str, list[int]] = {}
    damaged: list[Path] = []
    for path in cache_files(root):
        try:
            info = path.stat()
            key, mark = str(path.relative_to(root)), [info.st_size, info.st_mtime_ns]
            if record.get(key) == mark:
                checked[key] = mark
                continue
            if is_whole(path.read_bytes(), PICKLES[path.suffix]):
                checked[key] = mark
            else:
                damaged.append(path)
        except OSError:  # removed meanwhile by another process: numba sees it missing
            continue
    stuck = False
    for path in damaged:
        try:
            path.unlink(missing_ok=True)
        except OSError:
            stuck = True
    if stuck and "NUMBA_CACHE_DIR" not in os.environ:
        os.environ["NUMBA_CACHE_DIR"] = str(Path(tempfile.gettempdir()) /
                                            f"gdq_pddl-numba-{getattr(os, 'getuid', os.getpid)()}")
    if checked != record:
        _write_record(record_path, checked)
    return damaged


def _write_record(path: Path, checked: dict[str, list[int]]) -> None:
    """Save the list of files read whole (nothing if the folder is read-only)."""
    with contextlib.suppress(OSError, GdqError):
        atomic_write(path, lambda tmp: tmp.write_text(json.dumps(checked)))
