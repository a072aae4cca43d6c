"""Keep numba's on-disk cache of this package's compiled functions in step with the source.

numba caches a compiled function (``@numba.njit(cache=True)``) in ``__pycache__`` and
reuses it while the function's *own* file is unchanged, with the code of everything it
calls from other files baked in. The fast episode loop (``learners/episodes.py``) calls
the learning rules (``learners/gdq.py`` and the other rule modules) and the env step (``envs/model.py``): edit
``core.py`` and the loop would go on running the old rules, silently, while the Python
path runs the new ones. So on import we hash the sources of the modules with compiled
functions and, when the hash differs from the one the cache was built with, delete the
package's cache files. An installed package never changes, so this is a check of a few
files per process; a cache folder we cannot write (a read-only install) is left alone.
"""

from __future__ import annotations

import hashlib
from pathlib import Path

PACKAGE = Path(__file__).resolve().parent
JIT_FOLDERS = ("envs", "learners", "planning")
"""Subpackages whose modules have (or call) compiled functions."""
STAMP = Path("learners", "__pycache__", "jit-sources.sha256")
"""Where, under the package, the digest the cache was built with is kept."""


def sources_digest(root: Path = PACKAGE) -> str:
    """SHA-256 of every ``.py`` file of :data:`JIT_FOLDERS` under ``root``, in path order."""
    h = hashlib.sha256()
    for folder in JIT_FOLDERS:
        for path in sorted((root / folder).glob("*.py")):
            h.update(path.name.encode())
            h.update(path.read_bytes())
    return h.hexdigest()


def refresh(root: Path = PACKAGE) -> bool:
    """Delete stale numba cache files under ``root`` (see the module docstring); True
    when it did."""
    digest, stamp = sources_digest(root), root / STAMP
    try:
        if stamp.read_text() == digest:
            return False
    except OSError:
        pass
    try:
        for folder in JIT_FOLDERS:
            for pattern in ("*.nbi", "*.nbc"):
                for path in (root / folder / "__pycache__").glob(pattern):
                    path.unlink(missing_ok=True)
        stamp.parent.mkdir(exist_ok=True)
        stamp.write_text(digest)
    except OSError:
        return False
    return True
