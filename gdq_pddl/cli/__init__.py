"""The ``gdq-pddl`` command line: bad input gives one message on stderr naming the file,
key or option at fault, and a non-zero exit, never a traceback."""

from __future__ import annotations

import argparse
import sys
import warnings
from collections.abc import Callable, Sequence
from typing import TextIO

from gdq_pddl.limits import address_space_refusal

if (_REFUSAL := address_space_refusal()) is not None:  # before numpy's BLAS and numba load
    print(f"gdq-pddl: error: {_REFUSAL}", file=sys.stderr)
    raise SystemExit(2)

from gdq_pddl.cli import exercises, experiments, methods, planning  # noqa: E402 (after the check above)
from gdq_pddl.cli.common import EXIT_ERROR  # noqa: E402
from gdq_pddl.errors import GdqError  # noqa: E402
from gdq_pddl.experiments.interrupts import RunInterrupted  # noqa: E402
from gdq_pddl.limits import memory_override  # noqa: E402
from gdq_pddl.outputs import writing  # noqa: E402

EXIT_INTERRUPTED = 130  # the shell's convention for a program ended by SIGINT


def _exit_signal(exc: BaseException) -> int:
    """128 + the signal that stopped the command (SIGINT unless SIGTERM or SIGHUP)."""
    return 128 + int(getattr(exc, "signal", EXIT_INTERRUPTED - 128))

COMMANDS: list[Callable] = [
    planning.register_problem, planning.register_building, planning.register_plan,
    planning.register_planners, planning.register_list, experiments.register_run,
    experiments.register_switch,
    experiments.register_robot, experiments.register_reproduce, experiments.register_report,
    experiments.register_knowledge, experiments.register_scale,
    experiments.register_pairs, methods.register_methods,
    exercises.register_exercises,
]


def main(argv: Sequence[str] | None = None) -> int:
    """Entry point of ``gdq-pddl``; returns the exit status."""
    parser = build_parser()
    args = parser.parse_args(argv)
    if not hasattr(args, "func"):
        parser.print_help()
        return EXIT_ERROR
    stdout, sys.stdout = sys.stdout, _NamedOutput(sys.stdout)
    formatwarning, warnings.formatwarning = warnings.formatwarning, _format_warning
    try:
        memory_override()  # a mistyped GDQ_PDDL_MEMORY is refused before any work
        code = args.func(args)
        sys.stdout.flush()  # a full disk shows here, not in the interpreter's last flush
        return code
    except RunInterrupted as exc:  # Ctrl-C, SIGTERM or SIGHUP during a run: how to go on
        print(f"gdq-pddl: {exc}", file=sys.stderr)
        return _exit_signal(exc)
    except GdqError as exc:
        print(f"gdq-pddl: error: {exc}", file=sys.stderr)
        return EXIT_ERROR
    except KeyboardInterrupt as exc:
        print("gdq-pddl: interrupted", file=sys.stderr)
        return _exit_signal(exc)
    except BrokenPipeError:  # output piped into `head` and closed early: not an error
        sys.stderr.close()
        return 0
    except OSError as exc:  # a disk filling up, a folder removed under a running command
        where = f"{exc.filename}: " if exc.filename else ""
        print(f"gdq-pddl: error: {where}{exc.strerror or exc}", file=sys.stderr)
        return EXIT_ERROR
    except MemoryError:
        print("gdq-pddl: error: out of memory; give smaller sizes (--runs, --episodes, "
              "the world's step_limit)", file=sys.stderr)
        return EXIT_ERROR
    finally:
        sys.stdout = stdout
        warnings.formatwarning = formatwarning


def _format_warning(message: Warning | str, category: type[Warning], filename: str,
                    lineno: int, line: str | None = None) -> str:
    """A warning as one line that names what it is about (a user's file, in the message),
    not the library line that raised it."""
    return f"gdq-pddl: warning: {message}\n"


class _NamedOutput:
    """``sys.stdout`` whose write errors (a full disk) name it."""

    def __init__(self, stream: TextIO) -> None:
        self.stream = stream

    def write(self, text: str) -> int:
        with writing("standard output"):
            return self.stream.write(text)

    def flush(self) -> None:
        with writing("standard output"):
            self.stream.flush()

    def __getattr__(self, name: str) -> object:
        return getattr(self.stream, name)


def build_parser() -> argparse.ArgumentParser:
    parser = argparse.ArgumentParser(
        prog="gdq-pddl",
        description="Guided Dyna-Q: reinforcement learning whose exploration is guided by "
                    "a PDDL planner. Start with `gdq-pddl plan --task C` to see the plans "
                    "the learner is given, then `gdq-pddl run --task C`. Options that take "
                    "a domain, problem, dynamics or world file also take the name of a "
                    "shipped one (`gdq-pddl list`), e.g. `gdq-pddl run --domain keys-ppddl "
                    "--problem keys-ppddl-2`; an existing file of that name wins.")
    sub = parser.add_subparsers(title="commands", metavar="COMMAND")
    for register in COMMANDS:
        register(sub)
    return parser

