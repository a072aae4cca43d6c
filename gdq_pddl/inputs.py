"""Reading the files a user gives (world, domain, problem, dynamics), and fingerprinting them.

:func:`read_text` turns every way a file can fail to be text (missing, a folder, no
permission, not UTF-8) into the caller's own error, naming the file; :func:`file_hash`
is what ``--resume`` compares to tell that an input changed between two runs.
"""

from __future__ import annotations

import hashlib
from collections.abc import Callable
from pathlib import Path

from gdq_pddl.errors import GdqError


def read_text(path: str | Path, fail: Callable[[str, str], GdqError]) -> str:
    """The UTF-8 text of ``path``; on any failure raise ``fail(file name, message)``."""
    try:
        return Path(path).read_text(encoding="utf-8")
    except OSError as exc:
        raise fail(str(path), f"cannot read: {exc.strerror or exc}") from None
    except UnicodeDecodeError as exc:
        raise fail(str(path), f"not a UTF-8 text file (byte {exc.object[exc.start]:#04x} at "
                   f"offset {exc.start}); save it as UTF-8") from None


def file_hash(path: str | Path) -> str:
    """``sha256:<hex>`` of the file's bytes (``missing`` when it cannot be read)."""
    try:
        return "sha256:" + hashlib.sha256(Path(path).read_bytes()).hexdigest()
    except OSError:
        return "missing"
