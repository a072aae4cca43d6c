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


def test_readme_code_blocks_run_and_list_every_env_id(monkeypatch):
    from gdq_pddl.envs import ENV_IDS

    readme = DOCS.parent / "README.md"
    text = readme.read_text(encoding="utf-8")
    for env_id in ENV_IDS:
        assert f'gymnasium.make("{env_id}"' in text, f"README has no example for {env_id}"
    monkeypatch.chdir(DOCS.parent)  # its paths are relative to the repository root
    namespace: dict = {"__name__": "readme"}
    for i, block in enumerate(python_blocks(readme)):
        exec(compile(block, f"README.md block {i + 1}", "exec"), namespace)
    assert namespace["info"]["action_mask"].dtype.name == "int8"
