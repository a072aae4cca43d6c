"""What the package does with published PPDDL domains: one row per domain folder, with the
constructs its files use, whether a small problem runs (enumerated or online) or the line
that refuses it, and a measured run of that problem.

    python benchmarks/support_table.py DIR_OR_PROBLEM ... [--budget 300] [--episodes 100]
        [--runs 3] [--method GDQ DARLING Q-learning] [--seed 1] [--out FILE.md]

Each argument is a folder of one domain's files (the IPPC-2006/2008 and pddlgym layouts:
``domain.pddl`` and problem files, or files that hold a domain and its problem each, as
the IPPC-2008 boxworld files do) or one problem file (its domain in the same file or in
``domain.pddl`` beside it). In a folder the problem measured is the first by name
(``p01...``) that parses: the small one; a folder whose problems are in a ``problems/``
folder beside its ``domain.pddl`` gives the first of those. A folder with a domain file
and no problem (a published domain whose problems are not public) still gets a row: the
constructs its domain uses, and ``not run: no problem file``.

For each it prints one Markdown row:

- the domain's name and the problem measured;
- the constructs the domain's text uses, read by the package's own s-expression reader
  (``probabilistic``, ``when``, ``forall``, ``exists``, ``or``, ``imply``, reward effects,
  a ``probabilistic`` under a ``forall``...);
- ``enumerated`` (with the reachable states and V*) or ``online``, or the one line with
  which ``gdq-pddl run`` refuses the problem (exit 2), or ``past the budget``;
- the measured row: each method's mean return per episode over every episode and run,
  its success rate, and the wall seconds of the whole command (from a fresh process,
  ``--jobs 1``, killed at ``--budget`` seconds).

The command run for each problem is printed under the table, so any row can be rerun.
"""

from __future__ import annotations

import argparse
import json
import os
import re
import shlex
import subprocess
import sys
import tempfile
import time
from dataclasses import dataclass
from pathlib import Path

import pandas as pd

from gdq_pddl.errors import GdqError
from gdq_pddl.pddl.parser import parse_domain, read_problem
from gdq_pddl.pddl.sexpr import Node, Reader, read_pddl_text

METHODS = ("GDQ", "DARLING", "Q-learning")
WATCHED = ("probabilistic", "when", "forall", "exists", "or", "imply", "oneof", "=")
"""The connectives a row names where a domain's effects or conditions use them."""


@dataclass(frozen=True)
class Case:
    """One domain folder's files: the domain file and the problem measured."""

    label: str
    domain: Path
    problem: Path | None
    """``None`` for a folder that holds a domain and no problem."""


def _defines(path: Path) -> set[str]:
    """``{"domain", "problem"}``: what the file's ``(define (domain ...))`` and ``(define
    (problem ...))`` forms define, found in its text (a file the reader refuses, for a
    construct outside the language, is still found, so that its row says why)."""
    try:
        text = read_pddl_text(path)
    except (GdqError, OSError, UnicodeDecodeError):
        return set()
    return set(re.findall(r"\(\s*define\s*\(\s*(domain|problem)\b", text.lower()))


def find_case(arg: str) -> Case:
    """The domain and the problem measured for a folder or a problem file (the folder's
    ``problems/`` folder when the folder itself holds none), or the domain alone."""
    path = Path(arg)
    folder = path if path.is_dir() else path.parent
    domains = [f for f in sorted(folder.glob("*.pddl"))
               if "domain" in _defines(f) and "problem" not in _defines(f)]
    files = sorted(path.glob("*.pddl")) if path.is_dir() else [path]
    if path.is_dir() and not any("problem" in _defines(f) for f in files):
        files = sorted((path / "problems").glob("*.pddl"))
    for problem in files:
        kinds = _defines(problem)
        if "problem" not in kinds:
            continue
        domain = problem if "domain" in kinds else next(
            (f for f in domains if f != problem), None)
        if domain is not None:
            return Case(folder.name, domain, problem)
    if path.is_dir() and domains:
        return Case(folder.name, domains[0], None)
    raise SystemExit(f"{arg}: no problem file with its domain found (a folder of .pddl files "
                     "or a problem file was expected)")


def _walk(node: Node, under_forall: bool, found: set[str]) -> None:
    items = node.items
    if not items:
        return
    head = items[0].symbol
    if head in WATCHED:
        found.add(head)
    if head == "probabilistic" and under_forall:
        found.add("probabilistic under forall")
    if head in ("increase", "decrease") and len(items) > 1 and (
            items[1].symbol == "reward" or (items[1].items and
                                            items[1].items[0].symbol == "reward")):
        found.add("reward effects")
    if head in ("increase", "decrease") and "total-cost" in items[1].text():
        found.add("total-cost")
    for child in items[1:]:
        _walk(child, under_forall or head == "forall", found)


def constructs(case: Case) -> str:
    """The watched constructs the domain's text uses and its problem's reward, or the
    reader's refusal."""
    text = read_pddl_text(case.domain)
    try:
        domain = parse_domain(text, str(case.domain))
        problem = None if case.problem is None else read_problem(case.problem, domain)
    except GdqError as e:
        return f"refused by the reader: {str(e).splitlines()[0]}"
    found: set[str] = set()
    for form in Reader(text, str(case.domain)).forms():
        items = form.items or ()
        if len(items) > 1 and items[1].items and items[1].items[0].symbol == "domain":
            for section in items[2:]:
                if section.items and section.items[0].symbol == ":action":
                    _walk(section, False, found)
    if problem is not None and problem.goal_reward is not None:
        found.add("goal-reward")
    order = [*WATCHED, "probabilistic under forall", "reward effects", "total-cost",
             "goal-reward"]
    names = [c for c in order if c in found]
    return f"{len(domain.actions)} actions; " + (", ".join(names) or "STRIPS only")


def command(case: Case, out: Path, args: argparse.Namespace) -> list[str]:
    return ["gdq-pddl", "run", "--domain", str(case.domain), "--problem", str(case.problem),
            "--method", *args.method, "--episodes", str(args.episodes), "--runs",
            str(args.runs), "--seed", str(args.seed), "--jobs", "1", "--no-report",
            "--out", str(out)]


def measure(case: Case, args: argparse.Namespace) -> tuple[str, str, float]:
    """``(how it ran, the measured figures, wall seconds)`` of one problem's run."""
    if case.problem is None:
        return "not run: no problem file", "", 0.0
    with tempfile.TemporaryDirectory() as tmp:
        out = Path(tmp) / "out"
        cmd = command(case, out, args)
        cmd[0:1] = [sys.executable, "-m", "gdq_pddl.cli"]
        env = dict(os.environ, TQDM_DISABLE="1")
        start = time.perf_counter()
        try:
            done = subprocess.run(cmd, capture_output=True, text=True, timeout=args.budget,
                                  env=env, check=False)
        except subprocess.TimeoutExpired:
            return f"past the budget ({args.budget:g} s)", "", time.perf_counter() - start
        wall = time.perf_counter() - start
        if done.returncode != 0:
            lines = [ln for ln in done.stderr.splitlines() if ln.strip()]
            return f"refused (exit {done.returncode}): {lines[-1] if lines else '?'}", "", wall
        facts = next(iter(json.loads((out / "optimal.json").read_text()).values()), {})
        if facts.get("explored") == "online":
            how = "online"
        else:
            v_star = facts.get("v_star")
            how = f"enumerated, {facts.get('states', 0):,} states" + (
                f", V\\* {v_star:.2f}" if v_star is not None else "")
        episodes = pd.read_csv(out / "episodes.csv")
        per = episodes.groupby("method", sort=False).agg(ret=("return", "mean"),
                                                         success=("success", "mean"))
        figures = "; ".join(f"{m} {row.ret:.2f} ({100 * row.success:.0f}%)"
                            for m, row in per.iterrows())
        return how, figures, wall


def main(argv: list[str] | None = None) -> int:
    p = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    p.add_argument("paths", nargs="+", help="domain folders or problem files")
    p.add_argument("--budget", type=float, default=300.0, help="seconds per problem")
    p.add_argument("--episodes", type=int, default=100)
    p.add_argument("--runs", type=int, default=3)
    p.add_argument("--method", nargs="+", default=list(METHODS))
    p.add_argument("--seed", type=int, default=1)
    p.add_argument("--out", help="also write the table to this Markdown file")
    args = p.parse_args(argv)
    head = ["| domain | problem | constructs | runs as | mean return (success) | s |",
            "|---|---|---|---|---|---|"]
    rows, commands = [], []
    for arg in args.paths:
        case = find_case(arg)
        how, figures, wall = measure(case, args)
        problem = "-" if case.problem is None else case.problem.name
        seconds = "-" if case.problem is None else f"{wall:.0f}"
        row = (f"| {case.label} | {problem} | {constructs(case)} | {how} | "
               f"{figures or '-'} | {seconds} |")
        rows.append(row)
        if case.problem is not None:
            commands.append(shlex.join(command(case, Path("OUT"), args)))
        print(row, flush=True)
    text = "\n".join([*head, *rows, "", "Commands:", "",
                      *(f"    {c}" for c in commands), ""])
    if args.out:
        Path(args.out).write_text(text)
    print(text)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
