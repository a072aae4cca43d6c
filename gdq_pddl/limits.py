"""Sizes checked before anything is allocated, and numbers checked before they are used.

A world file's ``step_limit``, ``--episodes`` or ``--runs`` can ask for arrays no machine
holds. Each place that allocates in proportion to one of them estimates the bytes first
(:func:`check_memory`) and raises :class:`~gdq_pddl.errors.SizeError` naming the
setting, the size it would need and the memory there is, instead of growing until the
operating system kills the process or numpy fails deep inside a computation.

The range checks (:func:`check_real`, :func:`check_count`) are what every configuration
dataclass and option calls, so a NaN, ``2.5`` backups or ``10**12`` of them is refused
where it is given, not deep inside a compiled loop. Every number an input file gives
(world, dynamics, PDDL) is at most :data:`MAX_NUMBER` in size.
"""

from __future__ import annotations

import math
import numbers
import os

try:
    import resource
except ImportError:  # pragma: no cover (not POSIX: no limit to read)
    resource = None

from gdq_pddl.errors import ConfigError, SizeError

MAX_NUMBER = 1e15
"""The largest magnitude a number of an input file (world, dynamics, PDDL) may have: far
beyond any reward or cost, and small enough that a return (a sum over an episode's
steps) and ``r_max / (1 - gamma)`` stay finite."""

MAX_COUNT = 2**62
"""The largest count (``m``, a seed) int64 arithmetic holds with room to spare."""

MAX_TOLERANCE = 100.0
"""The largest plan-length tolerance: plans of up to 101 x the shortest length (the paper
uses 0.3). Past it a "tolerance" is a tour, not a near-shortest plan; and the bound
``(1 + tolerance) x L`` still grows with it, past every loop-free plan (clingo grounds a
horizon per step up to it) and, near 1e308, past any float."""

MAX_INPUT_BYTES = 16 * 1000**2
"""The largest input file (world, domain, problem, dynamics) read: 16 MB, a few times a
generated building of 100,000 positions (5 MB), far past any published PDDL problem."""

MAX_INIT_ATOMS = 100_000
"""The most atoms a PDDL problem's initial state may hold to be planned over (a generated
building of 10,000 positions has 32,500, planned in seconds): the grounded task keeps a
bitmask over every fact per action, so its memory grows with the square of this."""

MAX_WORLD_POSITIONS = 30_000
"""The most positions a world may have to be planned over: its PDDL problem's initial
state has about 3.25 atoms per position, so past this it passes :data:`MAX_INIT_ATOMS`."""

MIN_ADDRESS_SPACE = 1024**3
"""The smallest address-space limit (``ulimit -v``) the command line starts under: numpy's
BLAS, scipy and numba's LLVM reserve virtual memory as they load, and below about 700 MB
they fail inside the import (a MemoryError traceback) or, under 500 MB, OpenBLAS spins
forever retrying its allocation. 1 GiB leaves room for a run's own arrays."""

FALLBACK_MEMORY = 16 * 1024**3
"""What :func:`physical_memory` assumes where the system does not say."""


def physical_memory() -> int:
    """Bytes of physical memory of this machine (``FALLBACK_MEMORY`` if unknown), or the
    process's address-space limit if lower.

    ``GDQ_PDDL_MEMORY`` (bytes) overrides it, for tests and for sharing a machine.
    """
    override = os.environ.get("GDQ_PDDL_MEMORY")
    if override and override.isdigit():
        return int(override)
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
    """Why the command line cannot start under this process's ``ulimit -v`` (below
    ``minimum`` bytes), or None when it can."""
    cap = _address_space_cap()
    if cap >= minimum:
        return None
    return (f"the address-space limit (ulimit -v) is {human_bytes(cap)}; gdq-pddl needs at "
            f"least {human_bytes(minimum)}, because numpy, scipy and numba reserve virtual "
            "memory as they load: raise the limit (ulimit -v)")


def human_bytes(n: float) -> str:
    """``1.5 GB``, ``17.7 TB``: decimal units, three significant digits."""
    for unit in ("B", "kB", "MB", "GB", "TB", "PB"):
        if abs(n) < 1000 or unit == "PB":
            return f"{n:.3g} {unit}"
        n /= 1000
    return f"{n:.3g} PB"  # pragma: no cover (the loop always returns)


def check_memory(need: float, what: str, fix: str) -> None:
    """Raise :class:`SizeError` if ``need`` bytes exceed the machine's memory.

    ``what`` says what needs them (``"world.step_limit = 2000000000: V* ..."``, naming the
    setting at fault) and ``fix`` what to change.
    """
    have = physical_memory()
    if need > have:
        raise SizeError(f"{what} would need {human_bytes(need)} of memory, more than this "
                        f"machine has ({human_bytes(have)}); {fix}")


def check_real(name: str, value: object, low: float, high: float = math.inf,
               low_open: bool = False, high_open: bool = False) -> None:
    """Raise :class:`~gdq_pddl.errors.ConfigError` (a ValueError) unless ``value`` is a
    finite real number (not a bool) in the interval from ``low`` to ``high``, open at
    the ends ``low_open`` / ``high_open`` say."""
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
    """Raise :class:`~gdq_pddl.errors.ConfigError` (a ValueError) unless ``value`` is an
    integer (``int`` or a numpy integer, not a bool and not ``2.0``) in ``[0, high]``."""
    if not isinstance(value, numbers.Integral) or isinstance(value, bool) or \
            not 0 <= value <= high:
        raise ConfigError(f"{name} must be a whole number in [0, {high:_}], got {value!r}")
