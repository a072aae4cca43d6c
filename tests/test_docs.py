"""The tutorial's code blocks run, in order, in one namespace: the docs cannot rot. Its
notebook is a conversion of the same source and runs too, with its plots inline."""

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
    # the Q table on the map: zeros before OptInit, something after it
    before, after, _ = namespace["tables"].values()
    assert not before.any() and after.any()
    assert set(namespace["curves"]) >= {"Q-learning", "Dyna-Q"}
    import matplotlib.pyplot as plt

    plt.close("all")


NOTEBOOK = DOCS / "tutorial.ipynb"
REGENERATE = "jupytext --update --set-kernel python3 --to ipynb docs/tutorial.md"


def test_notebook_is_a_fresh_conversion_of_the_tutorial():
    """The committed notebook (what a teacher opens) has the tutorial's cells exactly.
    Cells are compared, not bytes: a conversion gives every cell a new random id."""
    import jupytext
    import nbformat

    fresh = jupytext.read(DOCS / "tutorial.md")
    committed = nbformat.read(NOTEBOOK, as_version=4)
    nbformat.validate(committed)
    assert [(c.cell_type, c.source) for c in committed.cells] == \
        [(c.cell_type, c.source) for c in fresh.cells], f"{NOTEBOOK} is stale: {REGENERATE}"
    assert committed.metadata.kernelspec.name == "python3", REGENERATE
    assert not any(c.get("outputs") for c in committed.cells), \
        "commit the notebook without outputs (regenerate it)"


def test_notebook_runs_with_its_plots_inline(tmp_path, monkeypatch):
    import nbclient
    import nbformat

    monkeypatch.delenv("MPLBACKEND", raising=False)  # the kernel's inline backend draws
    nb = nbformat.read(NOTEBOOK, as_version=4)
    nbclient.NotebookClient(nb, timeout=300, kernel_name="python3",
                            resources={"metadata": {"path": str(tmp_path)}}).execute()
    code = [c for c in nb.cells if c.cell_type == "code"]
    plots = [c.source for c in code
             if any("image/png" in o.get("data", {}) for o in c.outputs)]
    assert len(plots) == 2
    assert "draw_q" in plots[0] and "curves.items()" in plots[1]
    printed = "".join(o.get("text", "") for c in code for o in c.outputs)
    assert "Discrete(31) Discrete(95)" in printed and "2 plan(s) of length 8" in printed


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
