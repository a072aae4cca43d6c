"""``gdq-pddl exercises``: list the graded exercises, write their stubs, grade a student's
answer (exit 0 on a pass, 1 on a fail, 2 on bad usage)."""

from __future__ import annotations

import argparse
from pathlib import Path

from gdq_pddl.cli.common import POSITIVE
from gdq_pddl.exercises import EXERCISES, check, exercise, write_stubs

EXIT_FAIL = 1


def register_exercises(sub) -> None:
    p = sub.add_parser(
        "exercises", help="graded exercises: list them, write the stubs, check an answer",
        description="Graded exercises in the order of the tutorial (docs/exercises.md). "
                    "`gdq-pddl exercises` lists them; `init DIR` writes one stub per exercise "
                    "into DIR; `check N [FILE]` runs your function of exercise N on seeded "
                    "cases against the package's learners and says what differs (exit 0 on "
                    "a pass, 1 on a fail).")
    p.set_defaults(func=cmd_list_exercises)
    actions = p.add_subparsers(title="actions", metavar="ACTION")
    listing = actions.add_parser("list", help="the exercises, in the order of the lesson")
    listing.set_defaults(func=cmd_list_exercises)
    init = actions.add_parser("init", help="write the stubs into a folder",
                              description="Write one stub per exercise into DIR (made if "
                                          "missing); the reference solutions are not "
                                          "written.")
    init.add_argument("dir", type=Path, metavar="DIR")
    init.add_argument("--force", action="store_true",
                      help="replace stubs already in DIR (your answers in them are lost)")
    init.set_defaults(func=cmd_init)
    grade = actions.add_parser("check", help="grade your answer to exercise N",
                               description="Run your function of exercise N on seeded cases "
                                           "and compare it with the package's learners: exit "
                                           "0 when every case agrees, 1 at the first that "
                                           "does not (told in plain words).")
    grade.add_argument("number", type=POSITIVE, metavar="N", help="the exercise's number")
    grade.add_argument("file", type=Path, nargs="?", metavar="FILE",
                       help="your file (default: the stub's name in the current folder)")
    grade.set_defaults(func=cmd_check)


def cmd_list_exercises(args: argparse.Namespace) -> int:
    for e in EXERCISES:
        print(f"{e.number}. {e.title} (tutorial {e.section}): {e.function}() in {e.file_name}")
    print("Write the stubs with `gdq-pddl exercises init DIR`, then grade one with "
          "`gdq-pddl exercises check N DIR/FILE`.")
    return 0


def cmd_init(args: argparse.Namespace) -> int:
    paths = write_stubs(args.dir, overwrite=args.force)
    for path in paths:
        print(path)
    first = paths[0]
    print(f"Fill in each function, then: gdq-pddl exercises check 1 {first}")
    return 0


def cmd_check(args: argparse.Namespace) -> int:
    exercise(args.number)  # a number out of range is bad usage, before any work
    verdict = check(args.number, args.file)
    print(verdict.message)
    return 0 if verdict.passed else EXIT_FAIL
