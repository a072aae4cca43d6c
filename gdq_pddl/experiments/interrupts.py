"""How a run stops: Ctrl-C, SIGTERM and SIGHUP in the driver (:func:`stop_on_signals`),
what they raise (:class:`RunInterrupted`), and a worker process that ignores them and ends
with its driver (:func:`init_worker`). :mod:`gdq_pddl.experiments.runner` says what a stop
leaves saved.
"""

from __future__ import annotations

import ctypes
import os
import signal
import sys
from collections.abc import Iterator
from contextlib import contextmanager

from gdq_pddl.experiments.folder import ResultsError, close_inherited_locks


class RunInterrupted(ResultsError):
    """The run was stopped (Ctrl-C, SIGTERM or SIGHUP: ``signal``); what finished is saved."""

    def __init__(self, message: str, signum: int = signal.SIGINT) -> None:
        super().__init__(message)
        self.signal = signum

    def __reduce__(self):
        return type(self), (str(self), self.signal)


class _Stopped(KeyboardInterrupt):
    """SIGTERM or SIGHUP in the driver, raised as Ctrl-C's KeyboardInterrupt would be."""

    def __init__(self, signum: int) -> None:
        super().__init__(signal.Signals(signum).name)
        self.signal = signum


STOP_SIGNALS = (signal.SIGTERM, getattr(signal, "SIGHUP", signal.SIGTERM))
"""The signals besides SIGINT (Ctrl-C) that stop a run cleanly: its workers end with it."""


@contextmanager
def stop_on_signals() -> Iterator[None]:
    """While the block runs, SIGTERM and SIGHUP raise :class:`_Stopped` (main thread only)."""
    def stop(signum: int, _frame: object) -> None:
        raise _Stopped(signum)

    try:
        previous = {s: signal.signal(s, stop) for s in STOP_SIGNALS}
    except ValueError:  # not the main thread
        yield
        return
    try:
        yield
    finally:
        for s, handler in previous.items():
            signal.signal(s, handler)


def init_worker() -> None:
    """The start of a worker process: Ctrl-C and the stop signals are the driver's to
    handle, the worker dies with the driver and holds none of its folder locks."""
    signal.signal(signal.SIGINT, signal.SIG_IGN)  # the driver handles Ctrl-C for everyone
    for s in STOP_SIGNALS:  # the driver's handlers, inherited by the fork: end quietly
        signal.signal(s, signal.SIG_DFL)
    _die_with_parent()
    close_inherited_locks()


PR_SET_PDEATHSIG = 1
"""Linux's ``prctl`` option: the signal a process gets when its parent dies."""


def _die_with_parent() -> None:
    """Have the kernel send this worker SIGTERM when the driver dies, SIGKILL included, so
    no worker runs on as an orphan (Linux only)."""
    if not sys.platform.startswith("linux"):
        return
    try:
        libc = ctypes.CDLL(None, use_errno=True)
        libc.prctl(PR_SET_PDEATHSIG, signal.SIGTERM, 0, 0, 0)
    except (OSError, AttributeError):  # pragma: no cover (no libc prctl)
        return
    if os.getppid() == 1:  # the driver died before the prctl took effect
        os._exit(1)

