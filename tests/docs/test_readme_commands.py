"""Every ``gdq-pddl`` command of README.md (and of the expected-times page,
docs/reference/times.md) runs from an empty directory, as after
``pip install .`` outside a checkout: the README names shipped files by name, not by
paths of a checkout.

The commands are taken from README.md itself (indented code blocks, and inline code
with options: prose names a command as `gdq-pddl run`), so a command added there is
tested here. Each runs in-process (:func:`gdq_pddl.cli.main`)
with an empty temporary directory as the working directory, with two explicit changes
that keep the test cheap and leave each command's point intact:

- :data:`CHEAP`: options appended to a command that runs methods, so that it runs a few
  episodes of one run (argparse keeps the last value of an option given twice);
- :data:`PLACEHOLDERS`: a template's placeholder (``--domain D``) gets a shipped name.

The protocol commands (:data:`SLOW`) run with the slow tests.
"""

from __future__ import annotations

import re
import shlex

import pytest

from gdq_pddl.cli import main
from tests.helpers import REPO_ROOT

FEW = ["--episodes", "2", "--runs", "1", "--jobs", "1"]
CHEAP = {"run": FEW, "switch": FEW, "robot": FEW, "knowledge": FEW,
         "pairs": [*FEW, "--no-report"], "scale": ["--sizes", "40", "--buildings", "1",
                                                    "--runs", "1", "--episodes", "2"]}
"""Per subcommand, what is appended: fewer episodes and runs (and ``pairs`` without its
figure), all of the command's own options and inputs kept."""

PLACEHOLDERS = {"--domain": "keys-ppddl", "--problem": "keys-ppddl-2",
                "--dynamics": "keys-ppddl", "--positions": "40", "--seed": "1"}
"""The value a placeholder (an upper-case word or ``...``) after each option stands for."""

SLOW = {"reproduce", "pairs", "knowledge", "switch", "robot"}
"""Subcommands of a fixed protocol (the paper's, all 342 pairs, every knowledge case, a
switch, the robot's): 10 s to a minute each even so, run with the slow tests
(``pytest -m slow``); ``tests/experiments`` covers them in the default suite."""


PAGES = ("README.md", "docs/reference/times.md")
"""The pages whose commands a newcomer runs first: the README and the page of every
command's expected time."""


def readme_commands() -> list[str]:
    """The ``gdq-pddl ...`` commands of :data:`PAGES`, in order, without repeats."""
    text = re.sub(r"```.*?```", "", "\n".join(
        (REPO_ROOT / page).read_text(encoding="utf-8") for page in PAGES), flags=re.S)
    blocks = [line.split("#")[0].strip() for line in text.splitlines()
              if line.startswith("    ")]
    inline = [" ".join(span.split()) for span in re.findall(r"`([^`]+)`", text)]
    tables = [" ".join(span.split()) for line in text.splitlines() if line.startswith("|")
              for span in re.findall(r"`([^`]+)`", line)]
    found = [[m.group(1).strip() for c in lines
              if (m := re.search(r"(?:^|&& |time )(gdq-pddl\b.*)", c))]
             for lines in (blocks, inline, tables)]
    # inline code without options (`gdq-pddl run`) is prose naming a command, except in
    # a table of commands
    return list(dict.fromkeys(found[0] + [c for c in found[1] if len(c.split()) > 2]
                              + found[2]))


def argv_of(command: str) -> list[str]:
    """The arguments the test runs for ``command``: placeholders filled, :data:`CHEAP`
    appended."""
    argv = shlex.split(command)[1:]
    for i in range(1, len(argv)):
        if argv[i - 1] in PLACEHOLDERS and (argv[i].isupper() or argv[i] == "..."):
            argv[i] = PLACEHOLDERS[argv[i - 1]]
    return argv + CHEAP.get(argv[0] if argv else "", [])


COMMANDS = readme_commands()


def test_the_readme_names_its_commands():
    assert "gdq-pddl reproduce" in COMMANDS
    assert "gdq-pddl run --problem keys-ppddl-2" in COMMANDS
    assert not [c for c in COMMANDS if re.search(r"\bdomains/|\bproblems/|data/", c)]


@pytest.mark.parametrize("command", [
    pytest.param(c, marks=pytest.mark.slow) if shlex.split(c)[1:2] and
    shlex.split(c)[1] in SLOW else c for c in COMMANDS])
def test_readme_command_runs_from_an_empty_directory(command, tmp_path, monkeypatch, capsys):
    monkeypatch.chdir(tmp_path)
    code = main(argv_of(command))
    assert code == 0, f"{command}: exit {code}\n{capsys.readouterr().err}"
