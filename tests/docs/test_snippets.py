"""Every ```python block of README.md and docs/*.md runs from an empty directory (issue
37): a block that reads ``domains/keys.pddl`` works only inside the source tree, and a
reader copying it elsewhere would find it broken.

Each file's blocks run in order in one namespace (a page's blocks build on each other),
in a fresh interpreter whose working directory is an empty temporary folder.

Opting out: a block that needs an optional extra (Stable-Baselines3) is preceded,
on the line just before its fence, by ``<!-- snippet: needs MODULE -->``; it runs when
MODULE can be imported and is left out otherwise (so it must not define names later
blocks use). Only the modules of :data:`OPTIONAL` may be named, and at most
:data:`MAX_OPT_OUTS` blocks in all may opt out.
"""

from __future__ import annotations

import importlib.util
import json
import os
import re
import subprocess
import sys
from pathlib import Path

import pytest

from tests.helpers import REPO_ROOT

PAGES = [REPO_ROOT / "README.md", *sorted((REPO_ROOT / "docs").glob("*.md"))]

BLOCK = re.compile(r"(?:<!--\s*snippet:\s*needs\s+(?P<needs>[\w.]+)\s*-->\n)?"
                   r"```python\n(?P<code>.*?)```", re.S)
"""A python block, with the opt-out marker on the line before its fence if any."""

OPTIONAL = {"sb3_contrib", "stable_baselines3", "torch"}
"""The modules an opted-out block may need: those of the ``[sb3]`` extra."""

MAX_OPT_OUTS = 3
"""The most blocks, over every page, that may opt out."""

SLOW_PAGES = {"tutorial.md"}
"""Pages whose blocks run learners for hundreds of episodes (and draw figures): slow here;
``tests/docs/test_docs.py`` runs the tutorial's from an empty directory by default."""

RUNNER = r"""
import json, pathlib, sys, traceback
blocks = json.loads(sys.argv[1])
namespace = {"__name__": "__main__"}
for i, (where, code) in enumerate(blocks):
    # each block from a file of its own, as a reader's copy would be: numba's cache=True
    # (the "Add a learner" page's rules) needs a source file to key its cache by
    path = pathlib.Path(f"snippet_{i + 1}.py").absolute()
    path.write_text(code, encoding="utf-8")
    try:
        exec(compile(code, str(path), "exec"), namespace)
    except BaseException:
        print(f"{where} failed:", file=sys.stderr)
        traceback.print_exc()
        sys.exit(1)
"""


def blocks_of(page: Path) -> list[tuple[str, str, str | None]]:
    """``(where, code, needs)`` of every python block of ``page``, in order."""
    text = page.read_text(encoding="utf-8")
    return [(f"{page.name} block {i + 1} (line {text.count(chr(10), 0, m.start('code'))})",
             m.group("code"), m.group("needs")) for i, m in enumerate(BLOCK.finditer(text))]


def pages_with_blocks() -> list:
    return [pytest.param(page, id=page.name,
                         marks=[pytest.mark.slow] if page.name in SLOW_PAGES else [])
            for page in PAGES if page.exists() and blocks_of(page)]


def test_opt_outs_are_few_and_name_an_optional_extra() -> None:
    needs = [(where, module) for page in PAGES if page.exists()
             for where, _, module in blocks_of(page) if module]
    assert len(needs) <= MAX_OPT_OUTS, needs
    assert {module for _, module in needs} <= OPTIONAL, needs


def test_the_marker_is_read() -> None:
    text = "<!-- snippet: needs torch -->\n```python\nimport torch\n```\n```python\nx = 1\n```\n"
    found = [(m.group("needs"), m.group("code")) for m in BLOCK.finditer(text)]
    assert found == [("torch", "import torch\n"), (None, "x = 1\n")]


@pytest.mark.parametrize("page", pages_with_blocks())
def test_python_blocks_run_from_an_empty_directory(page: Path, tmp_path: Path) -> None:
    run = [(where, code) for where, code, needs in blocks_of(page)
           if needs is None or importlib.util.find_spec(needs) is not None]
    env = {**os.environ, "MPLBACKEND": "Agg"}
    result = subprocess.run([sys.executable, "-c", RUNNER, json.dumps(run)], cwd=tmp_path,
                            env=env, capture_output=True, text=True, timeout=900)
    assert result.returncode == 0, result.stderr[-3000:]
