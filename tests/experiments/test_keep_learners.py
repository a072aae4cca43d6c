"""``gdq-pddl run --keep-learners`` saves each run's final learner, and it loads; ``--resume``
goes on with the options the run began with (``--keep-learners``, ``--explore``)."""

from __future__ import annotations

import json

import numpy as np
import pytest

from gdq_pddl.learners import load_generators, load_learner, office_task_context
from gdq_pddl.resources import resolve_pddl
from tests.cli.hostile import refused
from tests.helpers import cli


def test_run_keeps_each_runs_final_learner(capsys, tmp_path, office):
    out = tmp_path / "out"
    code, text = cli(capsys, "run", "--task", "C", "--episodes", "4", "--runs", "1",
                     "--method", "GDQ", "Q-learning", "--jobs", "1",
                     "--no-report", "--keep-learners", "--out", out)
    assert code == 0, text
    ctx = office_task_context(office, "C")
    saved = sorted((out / "learners").glob("*.npz"))
    assert len(saved) == 2
    for path in saved:
        with np.load(out / "units" / path.name, allow_pickle=False) as unit:
            policy = unit["policy"]
        learner = load_learner(path, ctx)
        assert type(learner).__name__ == ("GDQ" if "__GDQ__" in path.name else "QLearning")
        assert np.array_equal(learner.greedy_policy(), policy)
        assert set(load_generators(path)) == {"rng", "env"}


# --- --resume keeps the options the run began with (issue 38) ------------------------------

def _run(capsys, out, *extra, runs=2):
    return cli(capsys, "run", "--task", "C", "--episodes", "3", "--runs", runs, "--method",
               "Q-learning", "--jobs", "1", "--no-report", "--out", out, *extra)


def _killed(out):
    """The folder as a run killed after its first unit left it."""
    (out / "episodes.csv").unlink()
    last = sorted((out / "units").glob("*.npz"))[-1]
    last.unlink()
    (out / "learners" / last.name).unlink(missing_ok=True)


@pytest.mark.parametrize(("first", "then", "named"), [
    (["--keep-learners"], [], "no --keep-learners: the run in"),
    ([], ["--keep-learners"], "--keep-learners: the run in"),
])
def test_resume_refuses_another_keep_learners(capsys, tmp_path, first, then, named):
    """Resuming without the flag kept 1 of the learners asked for, silently; with it after
    a start without, the others: now the flag is part of the run's record."""
    out = tmp_path / "o"
    assert _run(capsys, out, *first)[0] == 0
    _killed(out)
    code, text = _run(capsys, out, "--resume", *then)
    refused(code, text, named, str(out), "options.keep_learners", "--resume")
    assert _run(capsys, out, "--resume", *first)[0] == 0  # the same command goes on
    kept = sorted(p.name for p in (out / "learners").glob("*.npz")) \
        if (out / "learners").is_dir() else []
    assert len(kept) == (2 if first else 0)


def test_resume_of_a_run_recorded_before_options_reads_its_learners(capsys, tmp_path):
    """config.json without ``options`` (an older run): its kept learners say how it began,
    and a saved unit without its learner (a resume without the flag saved it) is named."""
    out = tmp_path / "o"
    assert _run(capsys, out, "--keep-learners", runs=3)[0] == 0
    _killed(out)
    config = json.loads((out / "config.json").read_text())
    del config["options"]
    (out / "config.json").write_text(json.dumps(config))
    refused(*_run(capsys, out, "--resume", runs=3), "no --keep-learners", "predates options")
    (next((out / "learners").glob("*.npz"))).unlink()  # a unit saved by a resume without
    code, text = _run(capsys, out, "--resume", "--keep-learners", runs=3)
    refused(code, text, "has no learner", "delete it")


def _pddl(capsys, out, explore, *extra):
    domain, problem, _ = resolve_pddl("keys-ppddl", "keys-ppddl-1", None)
    return cli(capsys, "run", "--domain", domain, "--problem", problem, "--episodes", "3",
               "--runs", "1", "--method", "Q-learning", "--jobs", "1", "--no-report",
               "--out", out, *(["--explore", explore] if explore else []), *extra)


def _no_enumeration(monkeypatch):
    def enumerated(*args, **kwargs):
        raise AssertionError("the states were enumerated")

    monkeypatch.setattr("gdq_pddl.envs.pddl_env.reachable_graph", enumerated)


@pytest.mark.parametrize(("first", "then"), [("online", "enumerate"), ("online", "auto"),
                                             ("enumerate", "online"), (None, "online")])
def test_resume_refuses_another_explore_before_any_work(capsys, tmp_path, monkeypatch,
                                                        first, then):
    """A changed --explore was found only after a full enumeration (or a memory refusal):
    now config.json is read first."""
    out = tmp_path / "o"
    assert _pddl(capsys, out, first)[0] == 0
    _no_enumeration(monkeypatch)
    monkeypatch.setattr("gdq_pddl.cli.experiments.OnlineInstance", None)  # nor explored
    code, text = _pddl(capsys, out, then, "--resume")
    refused(code, text, f"--explore {then}", str(out), "--resume")


@pytest.mark.parametrize("recorded", [True, False])
def test_resume_of_an_online_run_with_auto_goes_online_without_enumerating(
        capsys, tmp_path, monkeypatch, recorded):
    """``auto`` resuming a run that went online goes online again at once (also a run
    whose config.json predates the record of --explore: its experiment says online)."""
    out = tmp_path / "o"
    assert _pddl(capsys, out, "online")[0] == 0
    config = json.loads((out / "config.json").read_text())
    if not recorded:
        del config["options"]
        (out / "config.json").write_text(json.dumps(config))
        _no_enumeration(monkeypatch)
        code, text = _pddl(capsys, out, None, "--resume")
        assert code == 0, text
    else:
        _no_enumeration(monkeypatch)
        refused(*_pddl(capsys, out, None, "--resume"), "--explore auto", "--explore online")
        assert _pddl(capsys, out, "online", "--resume")[0] == 0


def test_a_kept_learner_of_an_online_run_is_refused_by_a_fresh_instance(capsys, tmp_path):
    """Its rows number the states its run reached: a fresh OnlineInstance of the same files
    numbers others, and loading says so (it failed later, about GreedyPolicy's actions)."""
    from gdq_pddl.envs.online import OnlineInstance
    from gdq_pddl.envs.pddl_env import PDDLInstance
    from gdq_pddl.errors import ResultsError
    from gdq_pddl.learners.online import online_context

    out = tmp_path / "o"
    assert _pddl(capsys, out, "online", "--keep-learners")[0] == 0
    kept = next((out / "learners").glob("*.npz"))
    domain, problem, _ = resolve_pddl("keys-ppddl", "keys-ppddl-1", None)
    fresh = online_context(OnlineInstance(PDDLInstance.from_files(domain, problem),
                                          estimate=None))
    with pytest.raises(ResultsError, match=r"this learner belongs to another instance "
                                           r"explored online"):
        load_learner(kept, fresh)


@pytest.mark.parametrize("explore", ["online", "enumerate"])
def test_resume_reads_a_problem_recorded_as_a_list_by_earlier_versions(capsys, tmp_path,
                                                                       monkeypatch, explore):
    """config.json of earlier versions recorded the problem as ``[domain, problem,
    dynamics, determinisation(, "online")]``: ``--resume`` reads it as its ProblemSpec,
    goes on as the run went (online: without enumerating) and records the fields."""
    out = tmp_path / "o"
    assert _pddl(capsys, out, explore)[0] == 0
    config = json.loads((out / "config.json").read_text())
    spec = config["experiments"][0]["pddl"]
    assert spec["exploration"] == explore
    config["experiments"][0]["pddl"] = [spec["domain"], spec["problem"], spec["dynamics"],
                                        spec["determinisation"],
                                        *(["online"] if explore == "online" else [])]
    del config["options"]  # as old as that: before --explore was recorded
    (out / "config.json").write_text(json.dumps(config))
    (out / "episodes.csv").unlink()
    if explore == "online":
        _no_enumeration(monkeypatch)
    code, text = _pddl(capsys, out, None, "--resume")
    assert code == 0, text
    assert json.loads((out / "config.json").read_text())["experiments"][0]["pddl"] == spec
    assert (out / "episodes.csv").exists()
