"""Sizes checked before anything is allocated (:func:`check_memory`), numbers checked
before they are used (:func:`check_real`, :func:`check_count`), and progress shown on
work that size makes slow (:func:`slow_progress`) and on the runs of an experiment
(:class:`Progress`)."""

from __future__ import annotations

import math
import numbers
import os
import sys
import threading
import time
from collections.abc import Iterable
from typing import TextIO

from tqdm import tqdm

try:
    import resource
except ImportError:  # pragma: no cover (not POSIX: no limit to read)
    resource = None

from gdq_pddl.errors import ConfigError, SizeError

MAX_NUMBER = 1e15
"""The largest magnitude a number of an input file (world, dynamics, PDDL) may have (so
that returns and ``r_max / (1 - gamma)`` stay finite)."""

MAX_COUNT = 2**62
"""The largest count (``m``, a seed) int64 arithmetic holds with room to spare."""

MAX_TOLERANCE = 100.0
"""The largest plan-length tolerance: plans of up to 101 x the shortest."""

MAX_INPUT_BYTES = 16 * 1000**2
"""The largest input file (world, domain, problem, dynamics) read: 16 MB."""

MAX_INIT_ATOMS = 100_000
"""The most atoms a PDDL problem's initial state may hold to be planned over (grounding's
memory grows with its square)."""

MAX_WORLD_POSITIONS = 30_000
"""The most positions a world may have to be planned over: its PDDL problem's initial
state has about 3.25 atoms per position, so past this it passes :data:`MAX_INIT_ATOMS`."""

MIN_ADDRESS_SPACE = 1024**3
"""The smallest address-space limit (``ulimit -v``) the command line starts under (numpy,
scipy and numba reserve virtual memory as they load, and fail below about 700 MB)."""

FALLBACK_MEMORY = 16 * 1024**3
"""What :func:`physical_memory` assumes where the system does not say."""


MEMORY_UNITS = {"": 1, "b": 1, "k": 1000, "kb": 1000, "m": 1000**2, "mb": 1000**2,
                "g": 1000**3, "gb": 1000**3, "t": 1000**4, "tb": 1000**4, "kib": 1024,
                "mib": 1024**2, "gib": 1024**3, "tib": 1024**4}
"""The units ``GDQ_PDDL_MEMORY`` takes (any case): decimal as :func:`human_bytes` writes
them, binary with an ``i``."""


def memory_override() -> int | None:
    """The bytes ``GDQ_PDDL_MEMORY`` says this machine has (``17179869184``, ``16GB``,
    ``16 GiB``, ``1.5TB``), or None where it is unset or empty; a ConfigError for any
    other text, so that a mistyped value is not silently ignored."""
    text = os.environ.get("GDQ_PDDL_MEMORY", "").strip()
    if not text:
        return None
    number = text.rstrip("bBiIkKmMgGtT ")
    unit = text[len(number):].strip().lower()
    try:
        value = float(number) * MEMORY_UNITS[unit]
    except (ValueError, KeyError):
        value = math.nan
    if not (math.isfinite(value) and 1 <= value <= MAX_NUMBER):
        raise ConfigError(f"GDQ_PDDL_MEMORY={text!r}: expected the machine's memory, a "
                          "positive size in bytes (17179869184) or with a unit (16GB, "
                          f"16GiB, 512MB), at most {MAX_NUMBER:g} bytes")
    return int(value)


def physical_memory() -> int:
    """Bytes of physical memory (``FALLBACK_MEMORY`` if unknown), or the address-space
    limit if lower; ``GDQ_PDDL_MEMORY`` overrides it (:func:`memory_override`)."""
    override = memory_override()
    if override is not None:
        return override
    try:
        have = os.sysconf("SC_PAGE_SIZE") * os.sysconf("SC_PHYS_PAGES")
    except (AttributeError, ValueError, OSError):
        have = FALLBACK_MEMORY
    return min(have, _address_space_cap())


def _address_space_cap() -> float:
    """The process's address-space limit (``ulimit -v``), or inf when there is none."""
    if resource is None:  # pragma: no cover (not POSIX)
        return math.inf
    soft = resource.getrlimit(resource.RLIMIT_AS)[0]
    return math.inf if soft == resource.RLIM_INFINITY else soft


def address_space_refusal(minimum: int = MIN_ADDRESS_SPACE) -> str | None:
    """Why the command line cannot start under this ``ulimit -v``, or None."""
    cap = _address_space_cap()
    if cap >= minimum:
        return None
    return (f"the address-space limit (ulimit -v) is {human_bytes(cap)}; gdq-pddl needs at "
            f"least {human_bytes(minimum)}, because numpy, scipy and numba reserve virtual "
            "memory as they load: raise the limit (ulimit -v)")


def human_bytes(n: float) -> str:
    """``1.5 GB``, ``17.7 TB``: decimal units, three significant digits."""
    for unit in ("B", "kB", "MB", "GB", "TB"):
        if abs(n) < 1000:
            return f"{n:.3g} {unit}"
        n /= 1000
    return f"{n:.3g} PB"


def check_memory(need: float, what: str, fix: str) -> None:
    """Raise :class:`SizeError` if ``need`` bytes exceed the machine's memory; ``what``
    names the setting that needs them, ``fix`` what to change."""
    have = physical_memory()
    if need > have:
        raise SizeError(f"{what} would need {human_bytes(need)} of memory, more than this "
                        f"machine has ({human_bytes(have)}); {fix}")


def check_real(name: str, value: object, low: float, high: float = math.inf,
               low_open: bool = False, high_open: bool = False) -> None:
    """Raise :class:`~gdq_pddl.errors.ConfigError` unless ``value`` is a finite real (not
    a bool) from ``low`` to ``high``, open at the ends ``low_open`` / ``high_open`` say."""
    ok = isinstance(value, numbers.Real) and not isinstance(value, bool) \
        and math.isfinite(value)
    if ok:
        ok = (value > low if low_open else value >= low) and \
            (value < high if high_open else value <= high)
    if not ok:
        where = f"{'>' if low_open else '>='} {low:g}" if math.isinf(high) else \
            f"in {'(' if low_open else '['}{low:g}, {high:g}{')' if high_open else ']'}"
        raise ConfigError(f"{name} must be a finite number {where}, got {value!r}")


def check_count(name: str, value: object, high: int = MAX_COUNT) -> None:
    """Raise a ConfigError unless ``value`` is an integer (not a bool) in ``[0, high]``."""
    if not isinstance(value, numbers.Integral) or isinstance(value, bool) or \
            not 0 <= value <= high:
        raise ConfigError(f"{name} must be a whole number in [0, {high:_}], got {value!r}")


def slow_progress(desc: str, unit: str, total: int | None = None,
                  iterable: Iterable | None = None) -> tqdm:
    """A progress bar on stderr that shows only after 2 s, and only on a terminal
    (``TQDM_DISABLE=1`` silences it): grounding, state enumeration, models, value iteration."""
    return tqdm(iterable, total=total, desc=desc, unit=unit, delay=2.0, disable=None,
                leave=False)


PROGRESS_EVERY = 30.0
"""Seconds between the progress lines of :class:`Progress` where stderr is no terminal."""


class Progress:
    """How far ``total`` units of work are, on stderr: a tqdm bar on a terminal; elsewhere
    (a log file, CI) the line ``DESC: k of N UNIT done (T s)`` every
    :data:`PROGRESS_EVERY` seconds, from a timer thread, until :meth:`close` (a
    compiled call that holds the interpreter delays a line until it returns).
    ``enabled=False`` shows nothing; ``TQDM_DISABLE=1`` silences the bar, not the lines."""

    def __init__(self, total: int, initial: int = 0, desc: str = "runs", unit: str = "run",
                 enabled: bool = True, stream: TextIO | None = None) -> None:
        self.total, self.n, self.desc, self.unit = total, initial, desc, unit
        self._stream = stream or sys.stderr
        self._t0 = time.monotonic()
        self._stop = threading.Event()
        terminal = self._stream.isatty()
        self._bar = tqdm(total=total, initial=initial, unit=unit, desc=desc,
                         dynamic_ncols=True, file=self._stream,
                         disable=not enabled or not terminal)
        self._thread = None
        if enabled and not terminal:
            self._thread = threading.Thread(target=self._lines, name="gdq-pddl progress",
                                            daemon=True)
            self._thread.start()

    def line(self) -> str:
        """The progress line: ``runs: 3 of 10 runs done (95 s)``."""
        return f"{self.desc}: {self.n} of {self.total} {self.unit}s done " \
            f"({time.monotonic() - self._t0:.0f} s)"

    def _lines(self) -> None:
        while not self._stop.wait(PROGRESS_EVERY):
            print(self.line(), file=self._stream, flush=True)

    def update(self, k: int = 1) -> None:
        """``k`` more units are done."""
        self.n += k
        self._bar.update(k)

    def close(self) -> None:
        """Stop showing progress (the bar is closed, the lines end)."""
        self._stop.set()
        self._bar.close()
