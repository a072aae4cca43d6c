"""The scale study: a learning smoke test on 100 positions, the report of each building
and each size, and interrupted runs that resume to the same results (from the API
and the command line). The buildings themselves: test_scale_buildings.py."""

from __future__ import annotations

import numpy as np
import pytest

from gdq_pddl.cli import main


def test_learning_smoke_on_100_positions(tmp_path):
    from gdq_pddl.analysis.scale import make_scale_report
    from gdq_pddl.experiments.scale import converged_at, run_scale, save_building, steps_per_s

    [result] = run_scale(tmp_path / "scale", [100], 1, 60, buildings=1,
                         methods=["DARLING", "Q-learning"], progress=False)
    assert set(result.returns) == {"DARLING", "Q-learning"}
    assert all(steps_per_s([result], m) > 0 for m in result.returns)
    assert result.returns["DARLING"].shape == (1, 60)
    paths = make_scale_report([result], 1, 60, tmp_path)
    assert [p.name for p in paths] == ["scale.png", "scale.pdf", "REPORT.md"]
    assert "| 100 / seed 0 | 12 |" in paths[-1].read_text()
    save_building(result, tmp_path / "building-100-s0.npz")
    saved = np.load(tmp_path / "building-100-s0.npz")
    assert np.array_equal(saved["returns/DARLING"], result.returns["DARLING"])
    assert float(saved["threshold"]) == result.threshold and int(saved["seed"]) == 0
    threshold = 5.0
    assert converged_at(np.full(80, 9.0), threshold) == 50
    assert converged_at(np.r_[np.full(60, -5.0), np.full(100, 9.0)], threshold) == 96  # 36 nines
    assert converged_at(np.r_[np.full(60, 9.0), np.full(100, -5.0)], threshold) == 50  # first
    assert converged_at(np.full(80, 1.0), threshold) is None
    assert result.r_fail < result.threshold < result.v_ref


def _building(positions: int, seed: int, returns: dict[str, list[list[float]]],
              steps: int = 1000, wall_s: float = 0.5):
    """A hand-built result (step limit 20, r_max 20: R_fail -39, V_ref 10, threshold 5.1)."""
    from gdq_pddl.experiments.scale import BuildingResult

    r = BuildingResult(positions=positions, seed=seed, doors=3, n_states=10, n_actions=4,
                       plan_length=5, step_limit=20, r_max=20.0, v_ref=10.0, context_s=0.1)
    for name, rows in returns.items():
        r.returns[name] = np.asarray(rows, dtype=float)
        r.success[name] = r.returns[name] > 0
        r.steps[name], r.wall_s[name], r.table_mb[name] = steps, wall_s, 1.0
    return r


def _runs(first: float, rest: float, episodes: int = 400) -> list[float]:
    """One run: ``first`` over its first 300 episodes, then ``rest``."""
    return [first] * 300 + [rest] * (episodes - 300)


def test_scale_report_gives_each_building_and_each_size_over_its_buildings(tmp_path):
    from gdq_pddl.analysis.scale import MARKERS, draw, report
    from gdq_pddl.experiments.scale import convergence, paired_difference

    # GDQ converges at 50 (every run), DARLING at 343 on seed 0 only (after 300 episodes
    # of -39, 43 of 13 lift the 50-episode average over 5.1), Q-learning never.
    a = _building(100, 0, {"GDQ": [_runs(10, 10), _runs(6, 10)],
                           "DARLING": [_runs(-39, 13), _runs(-39, 13)],
                           "Q-learning": [_runs(-39, -39), _runs(-39, -39)]})
    b = _building(100, 1, {"GDQ": [_runs(10, 10), _runs(10, 10)],
                           "DARLING": [_runs(0, 0), _runs(2, 0)],
                           "Q-learning": [_runs(-39, -39), _runs(-39, -39)]}, wall_s=1.5)
    c = _building(300, 0, {"GDQ": [_runs(10, 10)] * 2, "DARLING": [_runs(0, 10)] * 2,
                           "Q-learning": [_runs(-39, -39)] * 2})
    results = [a, b, c]
    assert convergence([a], "DARLING") == (343.0, 2, 2)
    assert convergence([a, b], "DARLING") == (343.0, 2, 4)
    assert convergence([a, b], "GDQ") == (50.0, 4, 4)
    assert paired_difference([a], "GDQ", "DARLING") == pytest.approx((47.0, 2.0))  # 49, 45
    assert paired_difference([b], "GDQ", "DARLING") == pytest.approx((9.0, 1.0))  # 10, 8
    mean, se = paired_difference([a, b], "GDQ", "DARLING")
    assert (mean, se) == pytest.approx((28.0, np.std([49, 45, 10, 8], ddof=1) / 2))
    text = report(results, 2, 400, tmp_path).read_text()
    assert "| 100 / seed 0 | 50 (2/2) | 343 (2/2) | > 400 (0/2) |" in text
    assert "| 100 / seed 1 | 50 (2/2) | > 400 (0/2) | > 400 (0/2) |" in text
    assert "| **100 / all 2** | 50 (4/4) | 343 (2/4) | > 400 (0/4) |" in text
    assert "| 300 / seed 0 | 50 (2/2) |" in text and "**300 / all" not in text
    first = text.split("## Mean return over the first 300 episodes")[1]
    assert "| 100 / seed 0 | 8.0 | -39.0 | -39.0 |" in first  # the first 300 only
    assert "| **100 / all 2** | 9.0 | -19.0 | -39.0 |" in first
    diff = text.split("## GDQ minus each method: mean return over the first 300 episodes")[1]
    assert "| 100 / seed 0 | +47.0 ± 2.0 | +47.0 ± 2.0 |" in diff
    assert f"| **100 / all 2** | +28.0 ± {se:.1f} | +48.0 ± 1.0 |" in diff
    every = text.split("## Mean return over all 400 episodes")[1]
    assert "| 100 / seed 0 | 8.5 | -26.0 | -39.0 |" in every
    steps = text.split("## Env steps/s")[1]
    assert "| 100 / seed 0 | 2,000 | 2,000 | 2,000 |" in steps
    assert "| **100 / all 2** | 1,000 | 1,000 | 1,000 |" in steps  # 2000 steps in 2 s
    fig = draw(results, 400)
    conv, gaps, speed = fig.axes
    for axis, methods in ((conv, 3), (gaps, 2), (speed, 3)):
        lines = axis.get_lines()
        markers = [ln for ln in lines if ln.get_marker() in MARKERS]  # no error-bar caps
        shapes = {ln.get_marker() for ln in markers}
        assert len(markers) == methods * len(results) and shapes == {"o", "s"}, axis
        through = [ln for ln in lines if ln.get_label() in a.returns]
        assert len(through) == methods  # one line per method through the two sizes
        assert all(len(ln.get_xdata()) == 2 for ln in through)
    opened = [ln for ln in conv.get_lines() if ln.get_fillstyle() == "none"]
    assert len(opened) == 3 + 1  # Q-learning on all three, DARLING on seed 1


QUIET = {"progress": False}
SMALL = {"sizes": [40], "buildings": 2, "runs": 2, "episodes": 30,
         "methods": ["DARLING", "Q-learning"]}


def _interrupt_after(monkeypatch, k: int) -> list:
    """Make the scale runs raise KeyboardInterrupt (as Ctrl-C) once ``k`` units are done;
    returns the list of the units started, as ``(method, (building seed, size, run))``."""
    from gdq_pddl.experiments import scale

    real, started = getattr(scale.run_scale_unit, "real", scale.run_scale_unit), []

    def run_scale_unit(unit):
        if len(started) == k:
            raise KeyboardInterrupt
        positions, seed = scale.building_of(unit.experiment.world)
        started.append((unit.method, (seed, positions, unit.run)))
        return real(unit)

    run_scale_unit.real = real
    monkeypatch.setattr(scale, "run_scale_unit", run_scale_unit)
    return started


def test_an_interrupted_scale_run_resumes_to_the_same_results(tmp_path, monkeypatch):
    from gdq_pddl.experiments.interrupts import RunInterrupted
    from gdq_pddl.experiments.scale import run_scale, steps_per_s

    fresh = run_scale(tmp_path / "fresh", **SMALL, **QUIET)
    assert [(r.positions, r.seed) for r in fresh] == [(40, 0), (40, 1)]
    assert fresh[0].v_ref != fresh[1].v_ref  # two different buildings
    cut = tmp_path / "cut"
    _interrupt_after(monkeypatch, 5)
    with pytest.raises(RunInterrupted, match=r"5 of 8 runs are saved .*--resume"):
        run_scale(cut, **SMALL, **QUIET)
    assert len(list((cut / "units").glob("building-40-s1__*.npz"))) == 1
    assert not list(cut.glob("building-*.npz"))  # collected when every run is saved
    started = _interrupt_after(monkeypatch, 99)
    resumed = run_scale(cut, **SMALL, resume=True, **QUIET)
    # only the missing units ran, seeded by (building seed, size, run): paired methods
    assert started == [("DARLING", (1, 40, 1)), ("Q-learning", (1, 40, 0)),
                       ("Q-learning", (1, 40, 1))]
    for r, f in zip(resumed, fresh, strict=True):
        for name in SMALL["methods"]:
            assert np.array_equal(r.returns[name], f.returns[name])
            assert np.array_equal(r.success[name], f.success[name])
            saved = [np.load(cut / "units" / f"{r.name}__A__{name}__run{run}.npz")
                     for run in range(2)]
            steps = sum(int(u["steps"].sum()) for u in saved)
            assert steps_per_s([r], name) == steps / sum(float(u["wall_s"]) for u in saved)
        a, b = np.load(cut / f"{r.name}.npz"), np.load(tmp_path / "fresh" / f"{r.name}.npz")
        assert sorted(a.files) == sorted(b.files)
        for key in a.files:
            assert a[key].dtype == b[key].dtype and np.array_equal(a[key], b[key]), key
    assert not list(cut.glob("**/.*.tmp"))


def test_a_run_depends_on_its_building_and_number_only(tmp_path):
    from gdq_pddl.experiments.scale import run_scale

    both = run_scale(tmp_path / "a", **SMALL, **QUIET)[1]  # building seed 1, second of two
    kw = SMALL | {"buildings": 1, "methods": ["Q-learning", "DARLING"]}
    alone = run_scale(tmp_path / "b", **kw, seed=1, **QUIET)[0]  # the same building, first
    assert alone.name == both.name == "building-40-s1"
    for name in SMALL["methods"]:  # neither the method's place nor the other buildings count
        assert np.array_equal(alone.returns[name], both.returns[name])
    assert not np.array_equal(*both.returns["DARLING"])  # runs differ from each other


def test_scale_runs_on_two_processes_give_the_same_results(tmp_path):
    """``--jobs 2``: forked workers (after the driver compiled the loops), each building's
    context made once per process, the same returns as one process."""
    from gdq_pddl.experiments.scale import run_scale

    one = run_scale(tmp_path / "one", **SMALL, **QUIET)
    two = run_scale(tmp_path / "two", **SMALL, jobs=2, **QUIET)
    for a, b in zip(one, two, strict=True):
        assert (a.name, a.n_states, a.v_ref) == (b.name, b.n_states, b.v_ref)
        for name in SMALL["methods"]:
            assert np.array_equal(a.returns[name], b.returns[name])
            assert a.steps[name] == b.steps[name]


def test_scale_results_need_resume_and_the_same_configuration(tmp_path):
    from gdq_pddl.experiments.runner import ResultsError
    from gdq_pddl.experiments.scale import run_scale

    kw = {"sizes": [40], "buildings": 1, "runs": 1, "episodes": 5, "methods": ["Q-learning"],
          **QUIET}
    run_scale(tmp_path, **kw)
    with pytest.raises(ResultsError, match="holds results: continue them with --resume"):
        run_scale(tmp_path, **kw)
    with pytest.raises(ResultsError, match=r"different configuration \(experiment "
                                           r"building-40-s0: schedule was \[\['A', 5\]\]"):
        run_scale(tmp_path, **kw | {"episodes": 6}, resume=True)
    for other in ({"sizes": [40, 60]}, {"buildings": 2}, {"methods": ["Q-learning", "DARLING"]}):
        with pytest.raises(ResultsError, match="different configuration"):
            run_scale(tmp_path, **kw | other, resume=True)
    unit = tmp_path / "units" / "building-40-s0__A__Q-learning__run0.npz"
    before = unit.stat().st_mtime_ns
    run_scale(tmp_path, **kw, resume=True)  # nothing left to run: collects again
    assert unit.stat().st_mtime_ns == before


def test_a_scale_folder_of_the_earlier_layout_is_refused_in_one_line(tmp_path, capsys):
    """Before the runner ran it, scale recorded its own config.json (sizes, buildings ...)
    and units/building-N-sS/: --resume says it cannot go on with it."""
    import json

    out = tmp_path / "old"
    (out / "units" / "building-40-s0").mkdir(parents=True)
    (out / "units" / "building-40-s0" / "Q-learning-0.npz").write_bytes(b"")
    (out / "config.json").write_text(json.dumps({"sizes": [40], "buildings": 1, "runs": 1,
                                                 "episodes": 5, "seed": 0,
                                                 "methods": ["Q-learning"]}))
    code = main(["scale", "--sizes", "40", "--buildings", "1", "--runs", "1", "--episodes",
                 "5", "--method", "Q-learning", "--jobs", "1", "--out", str(out), "--resume"])
    err = capsys.readouterr().err
    assert code == 2 and len(err.strip().splitlines()) == 1, err
    assert "different configuration" in err and "--resume" in err


def test_scale_cli_says_how_to_resume_without_a_traceback(tmp_path, monkeypatch, capsys):
    import json

    out = tmp_path / "a folder"
    argv = ["scale", "--sizes", "40", "--buildings", "1", "--method", "DARLING", "Q-learning",
            "DARLING", "--runs", "2", "--episodes", "5", "--jobs", "1", "--out", str(out)]
    _interrupt_after(monkeypatch, 2)
    assert main(argv) == 130
    err = capsys.readouterr().err
    assert "Traceback" not in err and err.strip().splitlines()[-1].startswith(
        "gdq-pddl: interrupted: 2 of 4 runs are saved in"), err
    assert err.strip().endswith("continue with the same command and --resume")
    started = _interrupt_after(monkeypatch, 99)
    assert main([*argv, "--resume"]) == 0
    assert [name for name, _ in started] == ["Q-learning", "Q-learning"]
    exps = json.loads((out / "config.json").read_text())["experiments"]
    assert exps[0]["methods"] == ["DARLING", "Q-learning"]
    assert exps[0]["world"] == "building:40:0"
    assert (out / "REPORT.md").exists() and (out / "building-40-s0.npz").exists()
    assert main(argv) == 2  # without --resume: refused
    assert "continue them with --resume" in capsys.readouterr().err
    # any registered method runs (DARLING-code too, since the registry); an unknown is refused
    assert main(["scale", "--method", "SARSA", "--out", str(tmp_path / "x")]) == 2
    assert "unknown method 'SARSA' (known: GDQ, GDQ-literal" in capsys.readouterr().err


@pytest.mark.parametrize("method", ["PPO", "dqn", "MaskablePPO"])
def test_scale_refuses_a_deep_rl_agent_in_one_line(tmp_path, capsys, monkeypatch, method):
    """With the sb3 extra, a deep-RL agent is refused before anything is written: scale
    times the compiled loops of tabular learners (it ran into the agent's missing act)."""
    from gdq_pddl.learners import registry

    monkeypatch.setattr(registry, "missing", lambda found: "")  # as if sb3 were installed
    code = main(["scale", "--sizes", "40", "--buildings", "1", "--runs", "1", "--episodes",
                 "2", "--method", "Q-learning", method, "--jobs", "1", "--out",
                 str(tmp_path / "o")])
    err = capsys.readouterr().err
    assert code == 2 and len(err.strip().splitlines()) == 1, err
    assert "cannot run in scale" in err and "gdq-pddl run" in err
    assert not (tmp_path / "o").exists()
