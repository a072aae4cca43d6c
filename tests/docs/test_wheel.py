"""The wheel ships every module and every data file, and works without the source tree.

The test folders are packages, so pytest puts the repository root on ``sys.path`` and
the suite tests the source tree even after ``pip install .``; this test is what proves
the installed package instead: the domains and problems, symlinks in the source tree,
must be real copies in the wheel.
"""

from __future__ import annotations

import json
import os
import subprocess
import sys
import zipfile
from pathlib import Path

import pytest

from tests.helpers import REPO_ROOT

PACKAGE = REPO_ROOT / "gdq_pddl"


@pytest.fixture(scope="module")
def wheel(tmp_path_factory) -> Path:
    builders = pytest.importorskip("hatchling.builders.wheel")  # the test extra has it
    out = tmp_path_factory.mktemp("wheel")
    return Path(next(iter(builders.WheelBuilder(str(REPO_ROOT)).build(
        directory=str(out), versions=["standard"]))))


def test_the_wheel_holds_every_module_and_data_file(wheel: Path) -> None:
    names = set(zipfile.ZipFile(wheel).namelist())
    wanted = {p.relative_to(REPO_ROOT).as_posix() for p in PACKAGE.rglob("*")
              if p.is_file() and "__pycache__" not in p.parts}
    assert wanted - names == set()
    assert "gdq_pddl/py.typed" in names  # PEP 561: type checkers read the package's hints
    for folder in ("domains", "problems"):  # symlinks here, copies there
        assert {f"gdq_pddl/data/{folder}/{p.name}" for p in (REPO_ROOT / folder).glob("*.pddl")
                } <= names


def test_the_unpacked_wheel_plans_without_the_source_tree(wheel: Path, tmp_path) -> None:
    site = tmp_path / "site"
    zipfile.ZipFile(wheel).extractall(site)
    code = ("import gdq_pddl, sys; from gdq_pddl.cli import main; "
            "print(gdq_pddl.__file__, file=sys.stderr); "
            "main(['plan', '--problem', 'keys-ppddl-2']); "  # a shipped name, a shipped file
            "raise SystemExit(main(['plan', '--task', 'C', '--json']))")
    result = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True,
                            cwd=tmp_path, env=dict(os.environ, PYTHONPATH=str(site)),
                            timeout=300)
    assert result.returncode == 0, result.stderr[-2000:]
    assert result.stderr.splitlines()[0] == str(site / "gdq_pddl" / "__init__.py")
    text, _, plans = result.stdout.partition("{")  # the text output has no brace
    assert text.startswith("2 plan(s) of length 7")
    assert json.loads("{" + plans)["length"] == 8
