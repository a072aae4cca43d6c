"""The tutorial's code blocks run, in order, in one namespace: the docs cannot rot. Its
notebook is a conversion of the same source and runs too, with its plots inline."""

from __future__ import annotations

import os
import re
import sys
from concurrent.futures import Future
from pathlib import Path

import numpy as np
import pytest

from tests.helpers import BACKGROUND, REPO_ROOT

DOCS = REPO_ROOT / "docs"


def python_blocks(path: Path) -> list[str]:
    return re.findall(r"```python\n(.*?)```", path.read_text(encoding="utf-8"), re.S)


def test_tutorial_code_blocks_run(capsys, tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)  # from an empty directory, as a reader runs them
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
    _check_tutorial_claims(namespace)
    import matplotlib.pyplot as plt

    plt.close("all")


def _check_tutorial_claims(ns: dict) -> None:
    """What the tutorial's prose says about its own results."""
    s0, gamma, r_max = ns["s0"], ns["gamma"], ns["r_max"]
    spaces, context = ns["spaces"], ns["context"]
    # the prior: at p0 the knowledge says only the two approach actions do something
    assert ns["prior"].applicable[s0].sum() == 2
    # OptInit on the prior: the greedy actions start the shortest plans, each worth the
    # return of a shortest plan that works; every other action one wasted step less
    q0 = ns["q0"]
    best = set(np.flatnonzero(q0 == q0.max()))
    assert best == set(np.flatnonzero(context.plans.first_actions[s0]))
    assert q0.max() == pytest.approx(ns["plan_return"])
    others = np.delete(q0, sorted(best))
    assert np.allclose(others, -1 + gamma * ns["plan_return"])
    # one stuck trial at d0: Q is the mean of the trial and the prior, and the news
    # reaches p0, whose greedy action now starts the other shortest plan
    demo, at_d0, ask = ns["demo"], ns["at_d0"], ns["ask"]
    assert demo.q[at_d0, ask] == pytest.approx((-r_max + ns["prior_value"]) / 2)
    assert demo.q[at_d0, ask] < ns["prior_value"] - 10
    policy = demo.greedy_policy()
    assert spaces.action_name(int(policy[s0])) == "approach p2"
    assert spaces.action_name(int(policy[at_d0])) == "approach p2"
    # exploring near the best values: the tutorial's sets are what the learner draws
    _check_exploring_sets(ns)
    # learning: GDQ well ahead of the baselines and of both older readings
    mean = {name: returns.mean() for name, returns in ns["curves"].items()}
    assert set(mean) == {"Q-learning", "Dyna-Q", "GDQ", "GDQ-literal", "GDQ-code"}
    assert mean["GDQ"] > 5 and mean["GDQ"] > max(mean["Q-learning"], mean["Dyna-Q"]) + 40
    assert mean["GDQ"] > mean["GDQ-code"] > mean["GDQ-literal"]
    assert ns["curves"]["GDQ"][:20].mean() > 0
    # GDQ-literal's OptInit: R_max / (1 - gamma) on the plan pairs, gamma times that else
    literal = ns["literal_q0"]
    assert literal.max() == pytest.approx(r_max / (1 - gamma)) == pytest.approx(400)
    assert np.median(literal) == pytest.approx(380)
    # the map: zeros before OptInit, OptInit's values, then what 300 episodes made of them
    before, after, learned = ns["tables"].values()
    assert not before.any() and np.array_equal(after, ns["optinit_q"]) and after.any()
    assert not np.array_equal(after, learned)
    # the longer route: OptInit prefers the shortest plan at p8, experience the detour
    p8, optinit_q, q = ns["p8"], ns["optinit_q"], ns["gdq"].q
    shortest, detour = spaces.action("approach", "p9"), spaces.action("goto", "p5")
    assert optinit_q[p8, shortest] > optinit_q[p8, detour]
    assert q[p8, detour] > q[p8, shortest]
    # ... and the door it learned is bad has left the exploring set, the detour joined it
    assert "approach p9" not in ns["learned_draws"] and "goto p5" in ns["learned_draws"]
    route = ns["route"]
    assert ns["lengths"] == [8, 9, 10]
    assert route[0] == ns["first"] == "approach p2"
    assert len(route) == 9 and {"gothrough p4", "gothrough p7"} <= set(route)
    _check_teaching_claims(ns)


def _check_teaching_claims(ns: dict) -> None:
    """What the prose of the class's sections says of the Dyna-Q sweep, the plans on the
    map, the wrong knowledge, the recorded episode and the older readings' curves."""
    sweep = ns["sweep"]
    firsts = {n: [int(np.argmax(r)) + 1 for r in runs] for n, runs in sweep.items()}
    assert not sweep[0].any()
    assert min(firsts[5]) >= 120 and max(firsts[5]) <= 180
    assert min(firsts[50]) >= 35 and max(firsts[50]) <= 115
    assert round(sweep[5][:, 200:].mean(), 2) == 0.98 and not sweep[5][:, :100].any()
    assert 0.2 <= sweep[50][:, :100].mean() <= 0.3
    assert round(sweep[50][:, 200:].mean(), 2) == 0.91
    assert not ns["curves"]["Dyna-Q"].max() > 0  # no success on task C
    assert ns["shortest"] == [["p0", "p1", "p3", "p5", "p6", "p7", "p17"],
                              ["p0", "p2", "p4", "p8", "p9", "p10", "p17"]]
    found = ns["wrong_knowledge"]
    locked = {k[1]: v for k, v in found.items() if k[0] == "office:locked-d3"}
    passage = {k[1]: v for k, v in found.items() if k[0] == "office:passage"}
    wrong, accurate = locked["GDQ, wrong knowledge"], locked["GDQ, accurate knowledge"]
    assert all(5 <= n <= 9 for n in wrong[1]) and not any(accurate[1])
    assert abs(wrong[0] - accurate[0]) < 0.2
    for learner in wrong[2]:
        route = ns["greedy_route"](learner)
        assert "opendoor p6" not in route and "opendoor p12" in route and len(route) == 10
    wrong, accurate = passage["GDQ, wrong knowledge"], passage["GDQ, accurate knowledge"]
    dyna = passage["Dyna-Q, no knowledge"]
    assert not any(wrong[1]) and all(n > 0 for n in accurate[1]) and all(dyna[1])
    assert 4 < accurate[0] - wrong[0] < 5 and dyna[0] < wrong[0] - 10
    assert len(ns["frames"]) == ns["steps"] + 1 == 10
    window = ns["window"]
    code = np.convolve(ns["curves"]["GDQ-code"], np.ones(window) / window, mode="valid")
    assert int(np.argmax(code > 0)) + window == 41 and int(np.argmax(code > 9)) + window == 53
    literal = ns["curves"]["GDQ-literal"]  # an episode at the goal returns more than 0
    assert (literal[:20] > 0).sum() == 4 and -40 < literal[-100:].mean() < -38


def _check_exploring_sets(ns: dict) -> None:
    """Section 5's exploring sets, recomputed in the tutorial from Q and V with the
    formula, are the actions the learner's own exploring step draws, right after OptInit
    (a fresh learner) and after the 300 episodes (section 6's learner at p8)."""
    from gdq_pddl.learners import GDQ
    from gdq_pddl.learners.gdq import _draw_near_best

    spaces, context, gdq = ns["spaces"], ns["context"], ns["gdq"]
    fresh = GDQ(context)
    rng = np.random.default_rng(0)

    def drawn(learner, s: int) -> set[str]:
        t, params = learner.tables, learner.params
        return {spaces.action_name(int(_draw_near_best(t.table, t.prior, params,
                                                         s, rng)))
                for _ in range(400)}

    for learner in (fresh, gdq):  # the tutorial's "what the max ranges over"
        allowed = ns["prior"].applicable | (learner.visits > 0)
        assert np.array_equal(allowed, learner.tables.table.allowed)
    assert ns["optinit_draws"] == {"p0": ["approach p1", "approach p2"],
                                   "p8": ["approach p9"]}
    for position, names in ns["optinit_draws"].items():
        assert drawn(fresh, spaces.state(position)) == set(names)
    assert drawn(gdq, ns["p8"]) == set(ns["learned_draws"])
    # goto p5 misses the floor at p8 by 0.003 after OptInit; its shortfall 1.3006 x
    p8, v = ns["p8"], fresh.v[ns["p8"]]
    detour = fresh.q[p8, spaces.action("goto", "p5")]
    floor = v - fresh.config.plan_tolerance * (ns["r_max"] - v)
    assert 0 < floor - detour < 0.005
    assert (ns["r_max"] - detour) / (ns["r_max"] - v) == pytest.approx(1.3006, abs=5e-5)
    # explore_all: None by default, 0.1 in the office (its knowledge may differ)
    assert gdq.config.explore_all is None and not context.exact_knowledge
    assert gdq.params.explore_all == pytest.approx(0.1)


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


NOTEBOOK_SCRIPT = """
import sys, tempfile
import nbclient, nbformat
nb = nbformat.read(sys.argv[1], as_version=4)
with tempfile.TemporaryDirectory() as cwd:
    nbclient.NotebookClient(nb, timeout=300, kernel_name="python3",
                            resources={"metadata": {"path": cwd}}).execute()
sys.stdout.write(nbformat.writes(nb))
"""
"""Executes the notebook given in a temporary directory and prints it with its outputs."""


def start_notebook(item) -> Future:
    """The notebook runs in a kernel of its own, queued when collection ends to run beside
    the other tests (``tests.helpers.Background``); the kernel's inline backend draws."""
    env = {k: v for k, v in os.environ.items() if k != "MPLBACKEND"}
    return BACKGROUND.run("tutorial notebook", [sys.executable, "-c", NOTEBOOK_SCRIPT,
                                                str(NOTEBOOK)], timeout=600, env=env)


@pytest.mark.background.with_args(start_notebook)
def test_notebook_runs_with_its_plots_inline(request):
    import nbformat

    result = start_notebook(request.node).result()
    assert result.returncode == 0, result.stderr[-2000:]
    nb = nbformat.reads(result.stdout, as_version=4)
    code = [c for c in nb.cells if c.cell_type == "code"]
    plots = [c.source for c in code
             if any("image/png" in o.get("data", {}) for o in c.outputs)]
    assert len(plots) == 4
    assert "draw_plans" in plots[0] and "draw_q" in plots[1]
    assert "curves.items()" in plots[2] and "imshow" in plots[3]
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
