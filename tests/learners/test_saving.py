"""Save and load (:mod:`gdq_pddl.learners.saving`): a loaded learner continues bit for bit,
a policy exports and evaluates in one call, bad files are refused naming the file."""

from __future__ import annotations

import io
import json
import zipfile
from dataclasses import replace

import gymnasium
import numpy as np
import pytest
from gymnasium.wrappers import TransformReward

from gdq_pddl.envs.office import OfficeEnv
from gdq_pddl.envs.online import OnlineInstance
from gdq_pddl.envs.online_env import OnlineEnv
from gdq_pddl.envs.pddl_env import load_instance
from gdq_pddl.errors import ConfigError, OutputError, ResultsError
from gdq_pddl.learners import (
    GreedyPolicy,
    evaluate_policy,
    load_generators,
    load_learner,
    make_learner,
    office_task_context,
    pddl_task_context,
    run_episodes,
    save_learner,
)
from gdq_pddl.learners.gdq_learner import GDQ
from gdq_pddl.learners.online import online_context
from gdq_pddl.learners.saving import FORMAT_VERSION
from gdq_pddl.learners.tables import Tables

METHODS = ["Q-learning", "Dyna-Q", "DARLING", "DARLING-code", "GDQ", "GDQ-literal",
           "GDQ-code", "R-max", "R-max-shaping"]


def _arrays(learner):
    learner.q  # noqa: B018 (the default GDQ fills its untried entries when q is read)
    return [x for group in learner.tables for x in group]


@pytest.mark.parametrize("method", METHODS)
def test_a_loaded_learner_continues_bit_for_bit(ctx_c, tmp_path, method):
    """N episodes, save (learner, its generator and the env's), load into a fresh env, M
    more: the same as N + M uninterrupted."""
    env = OfficeEnv(task="C")
    whole = make_learner(method, ctx_c)
    env.reset(seed=3)
    ref = run_episodes(whole, env, 25, np.random.default_rng(4))

    part = make_learner(method, ctx_c)
    env.reset(seed=3)
    rng = np.random.default_rng(4)
    first = run_episodes(part, env, 10, rng)
    path = tmp_path / "learner.npz"
    save_learner(path, part, rng=rng, env=env.np_random)
    del part, rng

    fresh = OfficeEnv(task="C")
    learner = load_learner(path, office_task_context(fresh.world, "C"))
    gens = load_generators(path)
    fresh.np_random = gens["env"]
    rest = run_episodes(learner, fresh, 15, gens["rng"])
    for f in ("returns", "steps", "success", "area_visits"):
        assert np.array_equal(np.concatenate([getattr(first, f), getattr(rest, f)]),
                              getattr(ref, f)), f
    assert type(learner) is type(whole) and learner.config == whole.config
    assert learner.params == whole.params
    for a, b in zip(_arrays(learner), _arrays(whole), strict=True):
        assert a.dtype == b.dtype and np.array_equal(a, b)


def test_the_file_is_plain_arrays_and_a_json_header(ctx_c):
    learner = make_learner("GDQ", ctx_c)
    buf = io.BytesIO()
    save_learner(buf, learner)
    buf.seek(0)
    with np.load(buf, allow_pickle=False) as z:  # no pickled object in it
        header = json.loads(str(z["header"]))
        keys = set(z.files)
    assert header["format"] == "gdq_pddl learner" and header["format_version"] == FORMAT_VERSION
    assert header["class"] == "GDQ" and header["config"]["variant"] == "prior"
    assert {"gdq_pddl", "numpy"} <= set(header["versions"])
    assert (header["n_states"], header["n_actions"]) == (31, 95)
    every = {f"{g}.{f}" for g, grp in zip(Tables._fields, learner.tables, strict=True)
             for f in grp._fields}
    assert keys | set(header["aliases"]) == every | {"header"}


def _rewrite(src, dst, change):
    """Copy the npz ``src`` to ``dst`` with its header changed by ``change``."""
    with np.load(src, allow_pickle=False) as z:
        arrays = {k: z[k] for k in z.files}
    header = json.loads(str(arrays.pop("header")))
    change(header)
    np.savez(dst, header=np.array(json.dumps(header)), **arrays)


def test_loading_refuses_other_versions_sizes_and_damaged_files(ctx_c, tmp_path):
    path = tmp_path / "q.npz"
    save_learner(path, make_learner("Q-learning", ctx_c))
    other = tmp_path / "v2.npz"
    _rewrite(path, other, lambda h: h.update(format_version=FORMAT_VERSION + 1))
    with pytest.raises(ResultsError, match=rf"v2\.npz: file format version {FORMAT_VERSION + 1}"):
        load_learner(other, ctx_c)
    delivery = gymnasium.make("gdq_pddl/PDDL-v0", domain="delivery", problem="delivery-2")
    bigger = pddl_task_context(delivery.unwrapped.instance)
    with pytest.raises(ResultsError, match=r"q\.npz: this learner was saved for task C .* of "
                                           r"world office\.toml \(built in\), the task "
                                           r"context is problem delivery-2 "
                                           r"\(delivery-2\.pddl\)"):
        load_learner(path, bigger)
    with pytest.raises(ResultsError, match=r"q\.npz: saved for 31 states x 95 actions, the "
                                           r"task context has \d+ x \d+"):
        load_learner(path, replace(bigger, identity=None))  # a context made by hand
    (tmp_path / "junk.npz").write_bytes(b"not a zip")
    with pytest.raises(ResultsError, match=r"junk\.npz: not a gdq_pddl learner file"):
        load_learner(tmp_path / "junk.npz", ctx_c)
    with pytest.raises(ResultsError, match=r"missing\.npz: no such file"):
        load_learner(tmp_path / "missing.npz", ctx_c)
    GreedyPolicy.of(make_learner("GDQ", ctx_c)).save(tmp_path / "p.npz")
    with pytest.raises(ResultsError, match=r"p\.npz: not a gdq_pddl learner file"):
        load_learner(tmp_path / "p.npz", ctx_c)
    cut = tmp_path / "cut.npz"
    with np.load(path, allow_pickle=False) as z, zipfile.ZipFile(cut, "w") as out:
        for k in z.files:
            if k != "table.q":
                with out.open(f"{k}.npy", "w") as fh:
                    np.lib.format.write_array(fh, z[k])
    with pytest.raises(ResultsError, match=r"cut\.npz: damaged learner file"):
        load_learner(cut, ctx_c)


def test_a_greedy_policy_exports_saves_and_evaluates_in_one_call(ctx_c, tmp_path):
    learner = make_learner("GDQ", ctx_c)
    env = OfficeEnv(task="C")
    env.reset(seed=0)
    run_episodes(learner, env, 60, np.random.default_rng(0))
    policy = GreedyPolicy.of(learner)
    assert np.array_equal(policy.actions, learner.greedy_policy())
    policy.save(tmp_path / "policy.npz")
    loaded = GreedyPolicy.load(tmp_path / "policy.npz")
    assert np.array_equal(loaded.actions, policy.actions) and loaded.n_actions == 95

    made = gymnasium.make("gdq_pddl/Office-v0", task="C")
    res = evaluate_policy(made, loaded, episodes=50, seed=1)
    assert len(res) == 50 and res.success_rate > 0.8
    assert res.mean_return == pytest.approx(res.returns.mean())
    again = evaluate_policy(made, learner, episodes=50, seed=1)  # a learner: its greedy policy
    assert np.array_equal(again.returns, res.returns)
    assert np.array_equal(learner.greedy_policy(), policy.actions)  # evaluating learns nothing
    # it steps the env through its wrappers
    wrapped = evaluate_policy(TransformReward(made, lambda r: -1.0), loaded, 50, seed=1)
    assert np.array_equal(wrapped.returns, -res.steps.astype(float))


def test_a_gdq_on_a_problems_own_scale_round_trips_with_its_file_rewards(tmp_path):
    """The prior's file rewards (``prior.reward``, empty on the goal scale) are saved and
    loaded with the rest: the loaded learner continues bit for bit on courier-1."""
    def env():
        e = gymnasium.make("gdq_pddl/PDDL-v0", domain="courier", problem="courier-1")
        e.reset(seed=5)
        return e

    first_env = env()
    ctx = pddl_task_context(first_env.unwrapped.instance)
    whole = make_learner("GDQ", ctx)
    ref = run_episodes(whole, env(), 12, np.random.default_rng(6))
    part = make_learner("GDQ", ctx)
    assert part.tables.prior.reward.shape == (ctx.n_states, ctx.n_actions)
    assert part.tables.prior.reward.any()
    rng = np.random.default_rng(6)
    first = run_episodes(part, first_env, 5, rng)
    path = tmp_path / "own.npz"
    save_learner(path, part, rng=rng, env=first_env.unwrapped.np_random)
    fresh = env()
    learner = load_learner(path, pddl_task_context(fresh.unwrapped.instance))
    gens = load_generators(path)
    fresh.unwrapped.np_random = gens["env"]
    rest = run_episodes(learner, fresh, 7, gens["rng"])
    assert np.array_equal(np.concatenate([first.returns, rest.returns]), ref.returns)
    assert np.array_equal(learner.tables.prior.reward, whole.tables.prior.reward)
    for a, b in zip(_arrays(learner), _arrays(whole), strict=True):
        assert a.dtype == b.dtype and np.array_equal(a, b)


# --- identities: a file is used only with what it belongs to (issue 38) -------------------

def test_a_learner_of_one_problem_is_refused_by_another_of_the_same_size(tmp_path):
    """keys-1 and keys-2 have the same states and actions: the sizes agree, the problem
    files do not, and the refusal names both."""
    k1, k2 = (pddl_task_context(load_instance("keys", f"keys-{i}")) for i in (1, 2))
    assert (k1.n_states, k1.n_actions) == (k2.n_states, k2.n_actions)
    path = tmp_path / "k1.npz"
    save_learner(path, make_learner("GDQ", k1))
    with pytest.raises(ResultsError, match=r"k1\.npz: this learner was saved for problem "
                                           r"keys-1 \(keys-1\.pddl\), the task context is "
                                           r"problem keys-2 \(keys-2\.pddl\): its problem"):
        load_learner(path, k2)
    assert type(load_learner(path, pddl_task_context(load_instance("keys", "keys-1")))) is GDQ
    env = gymnasium.make("gdq_pddl/PDDL-v0", domain="keys", problem="keys-2")
    with pytest.raises(ResultsError, match=r"the learner: this learner was saved for problem "
                                           r"keys-1 .*, the env is problem keys-2"):
        run_episodes(make_learner("GDQ", k1), env, 1, np.random.default_rng(0))
    header = _header(path)["identity"]
    assert header["problem name"] == "keys-1" and "sha256:" in header["problem"]


def _header(path):
    with np.load(path, allow_pickle=False) as z:
        return json.loads(str(z["header"]))


@pytest.fixture(scope="module")
def online_run():
    """A GDQ that learned 30 episodes on keys-ppddl-1 explored online, its instance."""
    instance = OnlineInstance(load_instance("keys-ppddl", "keys-ppddl-1"))
    env = OnlineEnv(instance)
    env.reset(seed=0)
    learner = make_learner("GDQ", online_context(instance))
    run_episodes(learner, env, 30, np.random.default_rng(0))
    return learner, instance, env


def test_an_online_runs_policy_and_learner_work_only_with_their_instance(online_run, tmp_path):
    """A fresh OnlineInstance of the same files numbers other states in its rows (both
    have 1024 rows allocated, so the sizes agree): its policy and learner are refused
    there by name, and work with their own instance, also after it found more states."""
    learner, instance, env = online_run
    policy = GreedyPolicy.of(learner)
    policy.save(tmp_path / "p.npz")
    save_learner(tmp_path / "l.npz", learner)
    fresh = OnlineInstance(load_instance("keys-ppddl", "keys-ppddl-1"))
    assert fresh.n_states == instance.n_states
    for p in (policy, GreedyPolicy.load(tmp_path / "p.npz")):
        with pytest.raises(ResultsError, match=r"the policy: this policy belongs to another "
                                               r"instance explored online \(states: \d+ rows"):
            evaluate_policy(OnlineEnv(fresh), p, 5)
    with pytest.raises(ResultsError, match=r"l\.npz: this learner belongs to another instance "
                                           r"explored online .* the task context: \d+ rows"):
        load_learner(tmp_path / "l.npz", online_context(fresh))
    with pytest.raises(ResultsError, match=r"the learner: this learner belongs to another "
                                           r"instance explored online"):
        run_episodes(learner, OnlineEnv(fresh), 1, np.random.default_rng(0))
    # with its own instance: the learner loads, and the policy evaluates as often as asked
    assert type(load_learner(tmp_path / "l.npz", online_context(instance))) is GDQ
    first = evaluate_policy(env, GreedyPolicy.load(tmp_path / "p.npz"), 10, seed=1)
    again = evaluate_policy(env, policy, 10, seed=1)  # its rows are the first of the env's
    assert np.array_equal(first.returns, again.returns) and first.success_rate > 0.5


def test_an_online_learner_without_identity_is_refused_there(online_run, tmp_path):
    """A file saved before identities were recorded cannot be checked against a problem
    explored online: refused, saying so (an enumerated one is not numbered by a run)."""
    learner, instance, _ = online_run
    path, old = tmp_path / "l.npz", tmp_path / "old.npz"
    save_learner(path, learner)
    _rewrite(path, old, lambda h: h.pop("identity"))
    with pytest.raises(ResultsError, match=r"old\.npz: this learner records no identity"):
        load_learner(old, online_context(instance))


@pytest.mark.parametrize(("change", "message"), [
    (lambda h: h["params"].update(gamma=1.5),
     r"header key params\.gamma is 1\.5; save_learner writes what the config and the task "
     r"give: 0\.95, in \[0, 1\)"),
    (lambda h: h["config"].update(gamma=1.5), r"header key config: gamma must be a finite "
                                              r"number in \[0, 1\), got 1\.5"),
    (lambda h: h["params"].update(r_max=99.0), r"header key params\.r_max is 99\.0"),
])
def test_a_learner_header_no_save_writes_is_refused_naming_the_key(ctx_c, tmp_path, change,
                                                                     message):
    path, bad = tmp_path / "g.npz", tmp_path / "bad.npz"
    save_learner(path, make_learner("GDQ", ctx_c))
    _rewrite(path, bad, change)
    with pytest.raises(ResultsError, match=r"bad\.npz: " + message):
        load_learner(bad, ctx_c)


@pytest.mark.parametrize("value", [np.inf, -np.inf, np.nan])
def test_a_learner_file_with_non_finite_values_is_refused(ctx_c, tmp_path, value):
    path, bad = tmp_path / "q.npz", tmp_path / "bad.npz"
    save_learner(path, make_learner("Q-learning", ctx_c))
    with np.load(path, allow_pickle=False) as z:
        arrays = {k: z[k] for k in z.files}
    arrays["table.q"] = arrays["table.q"].copy()
    arrays["table.q"][3, 2] = value
    np.savez(bad, **arrays)
    with pytest.raises(ResultsError, match=r"bad\.npz: array table\.q holds .* at \(3, 2\); "
                                           r"save_learner writes only finite values"):
        load_learner(bad, ctx_c)


@pytest.mark.parametrize("name", ["x.bin", "learner", "x.npz"])
def test_save_and_load_read_the_same_path(ctx_c, tmp_path, name):
    """The path given is the path written: no ``.npz`` added (numpy's savez would)."""
    learner = make_learner("Q-learning", ctx_c)
    save_learner(str(tmp_path / name), learner)
    GreedyPolicy.of(learner).save(str(tmp_path / f"p-{name}"))
    assert sorted(p.name for p in tmp_path.iterdir()) == sorted([name, f"p-{name}"])
    assert np.array_equal(load_learner(str(tmp_path / name), ctx_c).q, learner.q)
    assert GreedyPolicy.load(str(tmp_path / f"p-{name}")).n_actions == 95


@pytest.mark.parametrize("where", ["missing/x.npz", "."])
def test_saving_where_no_file_can_be_written_is_refused_naming_it(ctx_c, tmp_path, where):
    """A missing folder, or a folder given as the file: an OutputError naming the path,
    not a bare OSError (the learner and the policy alike)."""
    learner = make_learner("Q-learning", ctx_c)
    target = tmp_path / where
    with pytest.raises(OutputError, match=r"cannot write the learner file here"):
        save_learner(target, learner)
    with pytest.raises(OutputError, match=r"cannot write the policy file here"):
        GreedyPolicy.of(learner).save(target)


def test_a_file_an_older_version_named_npz_is_pointed_to(ctx_c, tmp_path):
    save_learner(tmp_path / "x.bin.npz", make_learner("Q-learning", ctx_c))
    with pytest.raises(ResultsError, match=r"x\.bin: no such file \(.*x\.bin\.npz exists"):
        load_learner(tmp_path / "x.bin", ctx_c)


@pytest.mark.parametrize("episodes", [0, -1])
def test_evaluating_over_no_episode_is_refused(ctx_c, episodes):
    policy = GreedyPolicy.of(make_learner("GDQ", ctx_c))
    with pytest.raises(ConfigError, match=r"episodes must be"):
        evaluate_policy(OfficeEnv(task="C"), policy, episodes)


def test_a_policy_runs_where_states_are_numbered_alike(ctx_c, tmp_path):
    """A policy needs only the state numbering: the office's task C policy runs on task
    D of the same world; a keys-1 policy is refused on keys-2 (same sizes)."""
    office = GreedyPolicy.of(make_learner("Q-learning", ctx_c))
    office.save(tmp_path / "c.npz")
    assert len(evaluate_policy(OfficeEnv(task="D"), GreedyPolicy.load(tmp_path / "c.npz"),
                               2)) == 2
    k1 = pddl_task_context(load_instance("keys", "keys-1"))
    keys = GreedyPolicy.of(make_learner("Q-learning", k1))
    keys.save(tmp_path / "k1.npz")
    assert GreedyPolicy.load(tmp_path / "k1.npz").identity == keys.identity
    env = gymnasium.make("gdq_pddl/PDDL-v0", domain="keys", problem="keys-2")
    with pytest.raises(ResultsError, match=r"this policy was saved for problem keys-1 "
                                           r"\(keys-1\.pddl\), the env is problem keys-2"):
        evaluate_policy(env, GreedyPolicy.load(tmp_path / "k1.npz"), 2)
