"""The registry (gdq_pddl.learners.registry): every list of methods reads it, a method is a
name plus settings checked against the learner's config class, names in any case."""

from __future__ import annotations

import ast
import re
from pathlib import Path

import pytest

from gdq_pddl.errors import ConfigError
from gdq_pddl.learners import registry
from gdq_pddl.learners.config import DynaQConfig, GDQConfig

PACKAGE = Path(registry.__file__).resolve().parents[1]


def test_every_list_of_methods_reads_the_registry():
    from gdq_pddl.experiments import protocol
    from gdq_pddl.experiments.knowledge import KNOWLEDGE_METHODS
    from gdq_pddl.learners.agents import METHODS

    names = tuple(e.name for e in registry.BUILT_IN)
    assert METHODS == protocol.METHODS == names
    assert set(protocol.PAPER_METHODS) <= set(protocol.DEFAULT_METHODS) | {"GDQ"}
    assert not hasattr(protocol, "SCALE_DEFAULT_METHODS")  # one default list, not aliases
    assert tuple(n for n in names if n.startswith("GDQ")) == protocol.GDQ_VARIANTS
    # every guided method, in the registry's order
    assert tuple(e.name for e in registry.BUILT_IN if e.knowledge != "none") == KNOWLEDGE_METHODS


def test_no_module_but_the_registry_declares_a_learner():
    """A list of learner names (two or more quoted names on one line) appears only in the
    registry: the others read it."""
    quoted = re.compile("|".join(f'"{re.escape(e.name)}"' for e in registry.BUILT_IN))
    lists = [f"{p.relative_to(PACKAGE)}:{i}" for p in PACKAGE.rglob("*.py")
             if p.name != "registry.py"
             for i, line in enumerate(p.read_text().splitlines(), 1)
             if len(quoted.findall(line)) >= 2]
    assert lists == []


LEARNER_MODULES = {f"learners/{m}.py" for m in (
    "__init__", "registry", "config", "rules", "tabular", "agents", "deep", "gdq", "gdq_learner",
    "gdq_paper", "rmax", "shaping", "replan")}
"""The learners' own modules (their names, classes and messages)."""
NAMING = {"analysis/sections.py": "the paper's report sections write about its methods",
          "exercises/grading.py": "each exercise grades one named learner's rule"}
"""The modules outside them that name a learner, and why."""


def test_no_code_outside_the_learners_names_a_learner():
    """No string of the package's code, outside the learners' modules and :data:`NAMING`,
    is a learner's name or alias (any case, with settings or not): it reads the registry."""
    keys = {registry.key_of(n) for e in registry.BUILT_IN + registry.DEEP
            for n in (e.name, *e.aliases)}
    found = set()
    for path in PACKAGE.rglob("*.py"):
        where = path.relative_to(PACKAGE).as_posix()
        if where in LEARNER_MODULES or where in NAMING:
            continue
        for node in ast.walk(ast.parse(path.read_text())):
            if isinstance(node, ast.Constant) and isinstance(node.value, str):
                name = node.value.partition(":")[0]
                if "_" not in name and registry.key_of(name) in keys:
                    found.add(f"{where}:{node.lineno}: {node.value!r}")
    assert sorted(found) == []


@pytest.mark.parametrize("given, canonical", [
    ("gdq", "GDQ"), ("GDQ", "GDQ"), ("dyna_q", "Dyna-Q"), ("Q-LEARNING", "Q-learning"),
    ("gdq-code", "GDQ-code"),
    ("gdq: explore_all = 0.5 , prior_weight=2", "GDQ:explore_all=0.5,prior_weight=2"),
    ("dynaq:n_backups=4", "Dyna-Q:n_backups=4"),
    ("GDQ:explore_all=none,explore_loops=true", "GDQ:explore_all=none,explore_loops=true"),
])
def test_a_method_is_a_name_in_any_case_with_settings(given, canonical):
    assert registry.canonical(given) == canonical


def test_settings_are_parsed_to_their_fields_types():
    m = registry.parse_method("GDQ:explore_all=0.5,m=3,explore_loops=yes,explore=plans")
    assert m.settings == {"explore_all": 0.5, "m": 3, "explore_loops": True,
                          "explore": "plans"}
    kwargs = m.config_kwargs({"alpha": 0.5, "not_a_field": 1})
    assert GDQConfig(**kwargs) == GDQConfig(alpha=0.5, explore_all=0.5, m=3,
                                            explore_loops=True, explore="plans")
    fixed = registry.parse_method("GDQ-code:n_backups=7")
    assert GDQConfig(**fixed.config_kwargs()) == GDQConfig(variant="code", n_backups=7)


@pytest.mark.parametrize("bad, message", [
    ("GDQ:explore_all=2", "explore_all must be a number or none in [0, 1], got 2.0"),
    ("GDQ:explore_all=x", "explore_all must be a number or none in [0, 1], got 'x'"),
    ("Dyna-Q:n_backups=-1", "n_backups must be a whole number in [0, 1_000_000], got -1"),
    ("Dyna-Q:n_backups=1.5", "n_backups must be a whole number in [0, 1_000_000]"),
    ("Q-learning:alpha=0", "alpha must be a number in (0, 1], got 0.0"),
    ("DARLING:variant=xx", "variant must be one of paper, code, got 'xx'"),
    ("GDQ:explore_loops=2", "explore_loops must be true or false, got '2'"),
    ("GDQ:prior_cost=1,prior_cost=2", "prior_cost is given twice"),
    ("GDQ:foo=1", "GDQ has no setting 'foo' (its settings: alpha, gamma"),
    ("Dyna-Q:prior_weight=1", "Dyna-Q has no setting 'prior_weight'"),
    ("GDQ:m", "'m' is not key=value"),
    ("GDQ-code:variant=literal", "GDQ-code is variant=code"),
    ("sarsa:alpha=0.1", "unknown method 'sarsa' (known: GDQ, "),
])
def test_a_bad_setting_is_refused_naming_field_type_and_range(bad, message):
    with pytest.raises(ConfigError) as err:
        registry.parse_method(bad)
    assert message in str(err.value) and "\n" not in str(err.value)
    assert str(err.value).startswith("unknown") or f"method {bad!r}" in str(err.value)


def test_ranges_live_in_the_config_fields():
    with pytest.raises(ConfigError, match=r"n_backups must be a whole number in \[0, 1_000_000\]"):
        DynaQConfig(n_backups=-1)
    with pytest.raises(ConfigError, match="explore_all must be a finite number in"):
        GDQConfig(explore_all=1.5)
    with pytest.raises(ConfigError, match="explore must be one of"):
        GDQConfig(explore="all")  # type: ignore[arg-type]
    assert str(registry.field_range(GDQConfig, "alpha")) == "(0, 1]"


def test_methods_with_settings_keep_their_learners_place_and_family():
    order = registry.order(["Q-learning", "GDQ:m=2", "zzz", "GDQ", "dyna-q"])
    assert order == ["GDQ", "GDQ:m=2", "dyna-q", "Q-learning", "zzz"]
    assert registry.family("GDQ-code:m=2") == registry.family("GDQ") == "GDQ"
    assert registry.family("DARLING-code") == "DARLING"
    assert registry.colour("GDQ") == registry.entry("gdq").colour
    assert registry.colour("GDQ:m=2") != registry.colour("GDQ")


def test_settings_table_shows_every_setting_with_its_default_and_docs():
    rows = {r[0]: r for r in registry.settings_table(registry.entry("GDQ-code"))}
    assert "variant" not in rows  # the name sets it
    assert rows["n_backups"][2] == "5" and rows["m"][2] == "5"
    assert rows["alpha"][1] == "a number in (0, 1]" and rows["alpha"][3].startswith("Step size")


# --- the command line and the runner -----------------------------------------------------------

def _cli(capsys, *argv):
    from gdq_pddl.cli import main

    code = main(list(argv))
    out = capsys.readouterr()
    return code, out.out, out.err


def test_methods_lists_every_learner_with_its_settings(capsys):
    import json

    code, out, _ = _cli(capsys, "methods", "--json")
    rows = {d["name"]: d for d in json.loads(out)}
    assert code == 0 and tuple(rows) == registry.names()
    dyna = {s["name"]: s for s in rows["Dyna-Q"]["settings"]}
    assert dyna["n_backups"]["default"] == "3"
    assert dyna["n_backups"]["type"] == "a whole number in [0, 1_000_000]"
    assert dyna["n_backups"]["doc"].startswith("N: model backups per real step")
    code, out, _ = _cli(capsys, "methods", "gdq")
    assert code == 0 and out.startswith("GDQ: ") and "explore_all" in out
    code, out, _ = _cli(capsys, "list")
    assert code == 0 and "methods (--method" in out and "  Dyna-Q " in out


@pytest.mark.parametrize("command", [
    ["run", "--task", "C"], ["switch"], ["robot"], ["knowledge"],
    ["scale", "--sizes", "40"], ["pairs"]])
def test_every_command_refuses_a_bad_method_spec_in_one_line(capsys, tmp_path, command):
    code, out, err = _cli(capsys, *command, "--method", "GDQ:explore_all=2", "--episodes",
                          "1", "--runs", "1", "--out", str(tmp_path / "out"))
    assert code == 2 and err.count("\n") == 1 and "Traceback" not in err
    assert "explore_all must be a number or none in [0, 1], got 2.0" in err


def test_a_spec_reaches_the_learner_in_the_runner():
    """The experiment's alpha, gamma and epsilon are defaults a method's settings override."""
    from gdq_pddl.experiments.protocol import Experiment, Hyper
    from gdq_pddl.experiments.work import context_of, instance_of, make_learner

    exp = Experiment("t", (("C", 1),), methods=("dyna_q:n_backups=7,alpha=0.3", "q-learning"),
                     runs=1, hyper=Hyper(alpha=0.5, gamma=0.9, epsilon=0.2))
    assert exp.methods == ("Dyna-Q:n_backups=7,alpha=0.3", "Q-learning")
    ctx = context_of(exp, instance_of(exp, "C"))
    learner = make_learner(exp.methods[0], ctx, exp.hyper)
    assert (learner.config.n_backups, learner.config.alpha, learner.config.gamma,
            learner.config.epsilon) == (7, 0.3, 0.9, 0.2)
    plain = make_learner(exp.methods[1], ctx, exp.hyper)
    assert (plain.config.alpha, plain.config.gamma, plain.config.epsilon) == (0.5, 0.9, 0.2)
    with pytest.raises(ConfigError, match="unknown method 'sarsa'"):
        Experiment("t", (("C", 1),), methods=("sarsa",))


@pytest.mark.parametrize("cached", [False, True])
def test_the_command_line_says_once_that_it_compiles_on_first_use(capsys, tmp_path,
                                                                   monkeypatch, cached):
    from gdq_pddl.cli import common

    monkeypatch.setattr(common, "loops_cached", lambda methods: cached)
    code, _, err = _cli(capsys, "run", "--task", "C", "--method", "q-learning", "--episodes",
                        "1", "--runs", "1", "--jobs", "1", "--no-report", "--out",
                        str(tmp_path / "out"))
    assert code == 0 and err.count("compiling the learners' code") == (0 if cached else 1)


def test_the_cache_is_asked_for_the_loop_of_each_rules_class_a_run_uses(ctx_c):
    """The compiled loop is cached per rules class: one a run compiled is found, one no
    learner has is not (its first use would compile), and the methods of a run are asked
    by their rules classes (Q-learning and DARLING share one)."""
    from typing import NamedTuple

    from gdq_pddl.envs.office import OfficeEnv
    from gdq_pddl.learners import make_learner
    from gdq_pddl.learners.episodes import loop_cached, loops_cached
    from gdq_pddl.learners.rules import TDRules
    from tests.helpers import run

    class NoLearnersRules(NamedTuple):
        """A rules class no loop was compiled for (Q-learning's rules, another class)."""

        act = TDRules.act
        observe = TDRules.observe

    run(make_learner("Q-learning", ctx_c), OfficeEnv(task="C"), 2, 0, fast=True)
    assert loop_cached({TDRules}) and loops_cached({"q-learning", "DARLING"})
    assert not loop_cached({TDRules, NoLearnersRules})


def test_the_default_gdq_and_the_papers_gdq_are_separate_learners(ctx_c):
    """GDQ-literal and GDQ-code are registered with their own class, PaperGDQ, whose rules
    are the paper's (plain epsilon-greedy acting, backups along plans); a GDQ made with a
    paper variant is one, and neither class takes the other's variant."""
    from gdq_pddl.learners import GDQ, GDQConfig, PaperGDQ, make_learner
    from gdq_pddl.learners.gdq import act as gdq_act
    from gdq_pddl.learners.tables import act_plain

    assert registry.entry("GDQ").learner_class() is GDQ
    assert {registry.entry(n).learner_class() for n in ("GDQ-literal", "GDQ-code")} == {PaperGDQ}
    assert not issubclass(PaperGDQ, GDQ) and not issubclass(GDQ, PaperGDQ)
    code = make_learner("gdq:variant=code", ctx_c)
    assert type(code) is PaperGDQ and type(GDQ(ctx_c, GDQConfig(variant="literal"))) is PaperGDQ
    assert code.act_rule is act_plain and make_learner("GDQ", ctx_c).act_rule is gdq_act
    with pytest.raises(ConfigError, match="variant 'prior' is the default GDQ"):
        PaperGDQ(ctx_c, GDQConfig())

    class MyGDQ(GDQ):
        """A subclass of the default GDQ."""

    with pytest.raises(ConfigError, match="is the default GDQ"):
        MyGDQ(ctx_c, GDQConfig(variant="code"))
