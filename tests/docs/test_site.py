"""The documentation site builds in strict mode (a broken link, a missing page or anchor,
an API name mkdocstrings cannot find: each fails it), its generated CLI page is current,
and the code of its how-to pages runs: the docs cannot rot."""

from __future__ import annotations

import re
import subprocess
import sys

import pytest

from gdq_pddl.cli import reference
from tests.helpers import REPO_ROOT

DOCS = REPO_ROOT / "docs"


def test_the_site_builds_in_strict_mode(tmp_path):
    pytest.importorskip("mkdocs")  # the test extra installs the docs extra
    pytest.importorskip("material")
    pytest.importorskip("mkdocstrings_handlers.python")
    done = subprocess.run([sys.executable, "-m", "mkdocs", "build", "--strict", "--clean",
                           "-f", str(REPO_ROOT / "mkdocs.yml"), "-d", str(tmp_path / "site")],
                          cwd=REPO_ROOT, capture_output=True, text=True, timeout=600)
    assert done.returncode == 0, done.stderr[-4000:]
    site = tmp_path / "site"
    assert (site / "index.html").exists()
    api = (site / "reference" / "api" / "index.html").read_text(encoding="utf-8")
    assert "GDQConfig" in api and "run_episodes" in api  # rendered from the docstrings
    assert ":func:<code>" not in api and ":mod:<code>" not in api  # docs/hooks/roles.py
    cli = (site / "reference" / "cli" / "index.html").read_text(encoding="utf-8")
    assert "gdq-pddl-reproduce" in cli


def test_the_cli_page_is_current():
    """The committed page is what the parser renders now. Argparse's layout changes
    between Python versions, so on another version than the page's the test checks that
    every subcommand and every option of it is on the page."""
    page = (REPO_ROOT / reference.PAGE).read_text(encoding="utf-8")
    regenerate = "regenerate it: python -m gdq_pddl.cli.reference docs/reference/cli.md"
    made_with = re.search(r"with Python (\d+\.\d+)", page)
    assert made_with, regenerate
    if made_with.group(1) == ".".join(map(str, sys.version_info[:2])):
        assert page == reference.render(), f"{reference.PAGE} is stale: {regenerate}"
        return
    parser = reference.build_parser()
    for name, sub in reference.subcommands(parser).items():
        assert f"## `gdq-pddl {name}`" in page, f"{name} missing: {regenerate}"
        for action in sub._actions:
            for option in action.option_strings:
                assert option in page, f"{name} {option} missing: {regenerate}"


def test_the_cli_page_lists_every_subcommand():
    parser = reference.build_parser()
    names = list(reference.subcommands(parser))
    assert {"run", "reproduce", "pairs", "plan", "list"} <= set(names)
    text = reference.render()
    for name in names:
        assert f"{{#gdq-pddl-{name}}}" in text
        assert f"usage: gdq-pddl {name}" in text


def python_blocks(text: str) -> list[str]:
    return re.findall(r"```python\n(.*?)```", text, re.S)


def titled_files(text: str) -> dict[str, str]:
    """The code blocks a page names a file (```pddl title="hall.pddl"```), by name."""
    return dict(re.findall(r'```\w+ title="([^"]+)"\n(.*?)```', text, re.S))


def shell_commands(text: str) -> list[str]:
    """The ``gdq-pddl`` lines of a page's ```bash blocks, comments cut."""
    return [line.split(" #")[0].strip()
            for block in re.findall(r"```bash\n(.*?)```", text, re.S)
            for line in block.splitlines() if line.strip().startswith("gdq-pddl ")]


CODE_PAGES = ["howto/world.md", "howto/pddl-domain.md", "howto/ppddl-problem.md",
              "howto/rerun.md", "howto/video.md", "reference/library.md"]
"""Pages whose code runs here, each in a temporary working directory: the files it names
are written, its ``python`` blocks run in one namespace, then its ``gdq-pddl`` commands
(with the cheap options of ``test_readme_commands``). A block that needs an optional
package (:data:`OPTIONAL`) not installed is left out."""

OPTIONAL = {"RecordVideo": "moviepy"}
"""A word of a block -> the package it needs."""


@pytest.mark.parametrize("page", CODE_PAGES)
def test_the_code_of_a_page_runs(page, tmp_path, monkeypatch):
    import importlib.util

    from gdq_pddl.cli import main
    from tests.docs.test_readme_commands import argv_of

    text = (DOCS / page).read_text(encoding="utf-8")
    monkeypatch.chdir(tmp_path)
    for name, content in titled_files(text).items():
        (tmp_path / name).write_text(content, encoding="utf-8")
    blocks = python_blocks(text)
    assert blocks or shell_commands(text), f"{page} has no code"
    namespace: dict = {"__name__": "page"}
    for i, block in enumerate(blocks):
        if any(word in block and importlib.util.find_spec(package) is None
               for word, package in OPTIONAL.items()):
            continue
        try:
            exec(compile(block, f"{page} block {i + 1}", "exec"), namespace)
        except Exception as exc:  # name the block that broke
            raise AssertionError(f"{page} block {i + 1} failed: {exc!r}\n{block}") from exc
    for command in shell_commands(text):
        code = main(argv_of(command))
        assert code == 0, f"{page}: {command}: exit {code}"
    import matplotlib.pyplot as plt

    plt.close("all")
