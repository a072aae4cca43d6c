"""The tutorial's code blocks run, in order, in one namespace: the docs cannot rot."""

from __future__ import annotations

import re
from pathlib import Path

DOCS = Path(__file__).resolve().parent.parent / "docs"


def python_blocks(path: Path) -> list[str]:
    return re.findall(r"```python\n(.*?)```", path.read_text(encoding="utf-8"), re.S)


def test_tutorial_code_blocks_run(capsys):
    blocks = python_blocks(DOCS / "tutorial.md")
    assert len(blocks) >= 8
    namespace: dict = {"__name__": "tutorial"}
    for i, block in enumerate(blocks):
        try:
            exec(compile(block, f"tutorial.md block {i + 1}", "exec"), namespace)
        except Exception as exc:  # name the block that broke
            raise AssertionError(f"tutorial block {i + 1} failed: {exc!r}\n{block}") from exc
    out = capsys.readouterr().out
    assert "Discrete(31) Discrete(95)" in out
    assert "2 plan(s) of length 8" in out
    # the claims the prose makes about these runs
    assert namespace["results"]["code"] > namespace["results"]["paper"]
    assert namespace["lengths"] == [8, 9, 10]
    assert "approach p2" in namespace["first"]
