"""Reading the files a user gives (failures: the caller's error naming the file), and
their fingerprints (:func:`file_hash`, what ``--resume`` compares)."""

from __future__ import annotations

import hashlib
import os
import stat
from collections.abc import Callable
from pathlib import Path

from gdq_pddl.errors import GdqError
from gdq_pddl.limits import MAX_INPUT_BYTES, human_bytes

BOM = "\ufeff"
"""The byte-order mark some editors put at the start of a UTF-8 file."""


def read_bytes(path: str | Path, fail: Callable[[str, str], GdqError],
               limit: int = MAX_INPUT_BYTES) -> bytes:
    """The bytes of the regular file ``path``, at most ``limit`` of them; on any failure
    (a device, FIFO or folder is refused before it is opened) ``fail(file name, message)``."""
    name = str(path)
    try:
        info = os.stat(path)
        if not stat.S_ISREG(info.st_mode):
            kind = "a folder" if stat.S_ISDIR(info.st_mode) else \
                "a FIFO" if stat.S_ISFIFO(info.st_mode) else "a device or other special file"
            raise fail(name, f"is {kind}, not a regular file")
        if info.st_size > limit:
            raise fail(name, _too_large(info.st_size, limit))
        fd = os.open(path, os.O_RDONLY | getattr(os, "O_NONBLOCK", 0))
        with os.fdopen(fd, "rb") as fh:
            data = fh.read(limit + 1)
    except OSError as exc:
        raise fail(name, f"cannot read: {exc.strerror or exc}") from None
    if len(data) > limit:
        raise fail(name, _too_large(len(data), limit))
    return data


def _too_large(size: int, limit: int) -> str:
    return (f"is {human_bytes(size)}, larger than the {human_bytes(limit)} an input file may "
            "have (every shipped or generated file is far smaller)")


def read_text(path: str | Path, fail: Callable[[str, str], GdqError]) -> str:
    """The UTF-8 text of ``path`` without a byte-order mark (see :func:`read_bytes`)."""
    data = read_bytes(path, fail)
    try:
        return data.decode("utf-8").removeprefix(BOM)
    except UnicodeDecodeError as exc:
        raise fail(str(path), f"not a UTF-8 text file (byte {exc.object[exc.start]:#04x} at "
                   f"offset {exc.start}); save it as UTF-8") from None


def text_hash(text: str) -> str:
    """``sha256:<hex>`` of ``text`` in UTF-8 (what :func:`file_hash` gives of its file, where
    the file has no byte-order mark)."""
    return "sha256:" + hashlib.sha256(text.encode("utf-8", "surrogatepass")).hexdigest()


def file_hash(path: str | Path) -> str:
    """``sha256:<hex>`` of the file's bytes (``missing`` when it cannot be read)."""
    try:
        return "sha256:" + hashlib.sha256(read_bytes(path, GdqError)).hexdigest()
    except GdqError:
        return "missing"
