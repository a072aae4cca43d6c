"""Independent probabilistic effects kept factored (issue 40, item 1): past
FACTORED_ABOVE outcomes a ground action is its parts, drawn one outcome a part and never
listed. Its distribution is the interpreter's (exactly, by the parts' product on small
cases; and by the draws, within a sound tolerance); it is the listing's, outcome by
outcome with what each earns, where the product can still be listed; the env steps it by
drawing; the knowledge lists each part's outcomes one at a time; a learner's model makes
room for its many successors; enumeration refuses it, and `--explore auto` goes online."""

from __future__ import annotations

import json
from itertools import product

import numpy as np
import pytest

from gdq_pddl.cli import main
from gdq_pddl.envs.online import OnlineInstance
from gdq_pddl.envs.online_env import OnlineEnv
from gdq_pddl.envs.pddl_env import PDDLInstance
from gdq_pddl.errors import TooManyStates
from gdq_pddl.learners import make_learner, pddl_task_context, run_episodes
from gdq_pddl.learners.online import online_context
from gdq_pddl.pddl import factored as factoring
from gdq_pddl.pddl.factored import combine
from gdq_pddl.pddl.reachable import reachable_graph
from tests.helpers import expanded_rows
from tests.pddl.ippc import grounded, interpreted_factored_agrees, random_domain

# A network of computers as in IPPC-2008 sysadmin-slp (written here in our own words):
# reboot ?x earns 1 for each computer up, brings ?x up 9 times in 10, and every other
# computer goes down with 1/20, or with 1/5 more where a computer linked to it is down.
SYSADMIN = """(define (domain net) (:requirements :adl :probabilistic-effects :rewards)
  (:types comp)
  (:predicates (up ?c - comp) (conn ?c ?d - comp))
  (:action reboot :parameters (?x - comp)
    :effect (and (forall (?d - comp) (when (up ?d) (increase (reward) 1)))
                 (probabilistic 9/10 (up ?x))
                 (forall (?d - comp)
                   (and (probabilistic 1/5 (when (exists (?c - comp)
                                                   (and (conn ?c ?d) (not (up ?c))
                                                        (not (= ?d ?x))))
                                             (not (up ?d))))
                        (probabilistic 1/20 (when (not (= ?d ?x)) (not (up ?d)))))))))
"""


def network(n: int) -> str:
    """The problem of ``n`` computers in a ring, with a link across, nothing up."""
    objects = " ".join(f"c{i}" for i in range(n))
    links = " ".join(f"(conn c{i} c{(i + 1) % n})" for i in range(n)) + " (conn c0 c2)"
    return (f"(define (problem net-{n}) (:domain net) (:objects {objects} - comp)\n"
            f"  (:init {links}) (:goal (forall (?c - comp) (up ?c)))\n"
            "  (:goal-reward 500) (:metric maximize (reward)))\n")


def test_random_factored_effects_agree_with_the_interpreter(monkeypatch):
    """Every random domain of the forall property test, each action with choices kept
    factored (FACTORED_ABOVE = 1): in every state the interpreter reaches, the parts'
    product is its distribution, and 2,000 draws of the parts in each of the first three
    states match it (5 standard deviations)."""
    monkeypatch.setattr(factoring, "FACTORED_ABOVE", 1)
    compared = 0
    for seed in range(30):
        rng = np.random.default_rng(1000 + seed)
        compared += interpreted_factored_agrees(*random_domain(rng, choices=True),
                                                np.random.default_rng(seed), draws=2000)
    assert compared > 150  # the seeds do exercise factored actions


def test_the_parts_product_is_the_listing_outcome_by_outcome(monkeypatch):
    """Five computers (2 x 4^4 = 512 outcomes: listed by default). Factored, the parts'
    product gives in every state each reboot's same next states, failed trials and
    rewards with the same probabilities."""
    listed, _ = grounded(SYSADMIN, network(5))
    monkeypatch.setattr(factoring, "FACTORED_ABOVE", 1)
    factored, _ = grounded(SYSADMIN, network(5))
    assert factored.facts == listed.facts
    for a, b in zip(listed.ops, factored.ops, strict=True):
        assert not a.factored and b.factored and b.product_size() == 512
        assert len(b.parts) == 5 and len(b.outcomes) == 1 + 1 + 4 * 3
        for state in range(1 << len(listed.facts)):
            want: dict[tuple, float] = {}
            for o in a.outcomes:
                key = (o.apply(state), o.stuck, round(o.gain(state), 9))
                want[key] = want.get(key, 0.0) + o.probability
            got: dict[tuple, float] = {}
            for pick in product(*b.parts):
                o = combine(pick)
                key = (o.apply(state), o.stuck, round(o.gain(state), 9))
                got[key] = got.get(key, 0.0) + o.probability
            assert got.keys() == want.keys()
            assert all(got[k] == pytest.approx(p, abs=1e-12) for k, p in want.items())


def test_the_env_draws_a_factored_action_as_listed(monkeypatch):
    """The online env steps reboot c0 in the initial state 4,000 times: each next state
    and reward comes as often as the listing says (5 standard deviations, plus a draw)."""
    listed = PDDLInstance.from_texts(SYSADMIN, network(5))
    s0 = listed.problem.learner_task.init
    reboot = next(op for op in listed.problem.learner_task.ops if op.name == "(reboot c0)")
    want: dict[tuple, float] = {}
    for o in reboot.outcomes:
        key = (o.apply(s0), o.gain(s0))
        want[key] = want.get(key, 0.0) + o.probability
    monkeypatch.setattr(factoring, "FACTORED_ABOVE", 1)
    online = OnlineInstance(PDDLInstance.from_texts(SYSADMIN, network(5)))
    assert online.graph.factored.all()
    k = next(i for i, op in enumerate(online.task.ops) if op.name == "(reboot c0)")
    env = OnlineEnv(online)
    env.reset(seed=3)
    counts: dict[tuple, int] = {}
    draws = 4000
    for _ in range(draws):
        env.reset()
        _, reward, terminated, _, _ = env.step(k)
        assert not terminated
        key = (online.graph.mask(env._x), reward)  # costs nothing: the reward is the gain
        counts[key] = counts.get(key, 0) + 1
    assert counts.keys() <= want.keys()
    for key, p in want.items():
        sd = (p * (1 - p) / draws) ** 0.5
        assert abs(counts.get(key, 0) / draws - p) <= 5 * sd + 1 / draws, (key, p)


def test_a_factored_pairs_prior_reward_is_the_listed_ones(monkeypatch):
    """On the problem's own scale a pair's prior reward is the most its outcomes earn:
    of a factored reboot, each part's most added up, which is the listing's most (five
    computers, enumerated without factoring) in every state a run expands."""
    listed = PDDLInstance.from_texts(SYSADMIN, network(5))
    enumerated = pddl_task_context(listed).prior_reward
    monkeypatch.setattr(factoring, "FACTORED_ABOVE", 1)
    online = OnlineInstance(PDDLInstance.from_texts(SYSADMIN, network(5)))
    env = OnlineEnv(online)
    env.reset(seed=0)
    run_episodes(make_learner("Q-learning", online_context(online)), env, 10,
                 np.random.default_rng(1))
    checked = 0
    for row, s, k in expanded_rows(online, listed):
        assert np.array_equal(online.columns[row, :k], listed.graph.offered[s, :k])
        assert np.allclose(online.prior_reward[row, :k], enumerated[s, :k])
        checked += 1
    assert checked > 5


def test_the_determinisation_grows_with_the_sum_of_the_parts():
    """Seven computers: 2 x 4^6 = 8,192 outcomes, past FACTORED_ABOVE. The knowledge
    lists every part at its most likely outcome (c0 up, nothing else down: one outcome),
    then each other outcome of one part alone (1 + 1 + 6 x 3), and plans on all that
    change something (all-outcomes: not c0 staying down with nothing else happening), or
    on the first (most-likely)."""
    assert factoring.FACTORED_ABOVE == 4096
    learner, planner = grounded(SYSADMIN, network(7))
    reboot = next(op for op in learner.ops if op.name == "(reboot c0)")
    assert reboot.factored and reboot.product_size() == 8192
    assert len(reboot.outcomes) == 1 + 1 + 6 * 3
    assert reboot.outcomes[0].apply(0) == learner.mask({"(up c0)"})
    assert reboot.outcomes[1].apply(0) == 0 and not reboot.outcomes[1].moves()
    assert reboot.known == (0, *range(2, 20))
    assert len(planner.ops) < 7 * 50  # STRIPS variants of the conditional effects
    likely, _ = grounded(SYSADMIN, network(7), "most-likely")
    assert all(op.known == (0,) for op in likely.ops)


def test_enumeration_refuses_factored_actions_in_one_line():
    learner, _ = grounded(SYSADMIN, network(7))
    with pytest.raises(TooManyStates) as err:
        reachable_graph(learner, source="net-7.pddl")
    message = str(err.value)
    assert "(reboot c0) has 8,192 outcomes, kept as 7 independent parts" in message
    assert "--explore online" in message and "\n" not in message


def test_a_learners_model_makes_room_for_many_successors():
    """A factored pair meets more next states than the model's first slots: GDQ and
    Dyna-Q record them all (without the room, a step past the slots raised)."""
    online = OnlineInstance(PDDLInstance.from_texts(SYSADMIN, network(7)))
    for method in ("GDQ", "Dyna-Q"):
        learner = make_learner(method, online_context(online))
        k0 = learner.max_successors
        s, a = online.learner_start, int(online.columns[online.learner_start, 0])
        rng = np.random.default_rng(0)
        for s2 in range(k0 + 5):
            learner.observe(s, a, -1.0, s2 + 1, False, False, rng)
        assert learner.max_successors > k0
        assert learner.tables.model.visits[s, 0] == k0 + 5


def test_learners_run_on_a_factored_problem():
    """GDQ, DARLING and Q-learning learn online on seven computers (every action
    factored): each step draws each part, and the episodes end."""
    online = OnlineInstance(PDDLInstance.from_texts(SYSADMIN, network(7)))
    for method in ("GDQ", "DARLING", "Q-learning"):
        env = OnlineEnv(online)
        env.reset(seed=0)
        records = run_episodes(make_learner(method, online_context(online)), env, 3,
                               np.random.default_rng(1))
        assert (records.steps > 0).all()
    assert online.graph.n_states > 20


def test_cli_runs_a_factored_problem_online(tmp_path, capsys):
    (tmp_path / "d.pddl").write_text(SYSADMIN)
    (tmp_path / "p.pddl").write_text(network(7))
    base = ["run", "--domain", str(tmp_path / "d.pddl"), "--problem",
            str(tmp_path / "p.pddl"), "--method", "GDQ", "Q-learning", "--episodes", "2",
            "--runs", "1", "--jobs", "1", "--no-report"]
    assert main([*base, "--explore", "enumerate", "--out", str(tmp_path / "e")]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and "kept as 7 independent parts" in err[0]
    assert main([*base, "--out", str(tmp_path / "run")]) == 0
    optimal = next(iter(json.loads((tmp_path / "run" / "optimal.json").read_text())
                        .values()))
    assert optimal["explored"] == "online" and "independent parts" in \
        optimal["explored_because"]
    assert len((tmp_path / "run" / "episodes.csv").read_text().splitlines()) == 1 + 2 * 2
    # the reason given, first and on resuming, is that the actions are factored, only
    assert main([*base, "--out", str(tmp_path / "run"), "--resume"]) == 0
    resumed = next(iter(json.loads((tmp_path / "run" / "optimal.json").read_text())
                        .values()))
    for info in (optimal, resumed):
        assert info["explored_because"].startswith(str(tmp_path / "p.pddl") + ": (reboot c0) "
                                                   "has 8,192 outcomes, kept as 7 independent")


def test_the_factored_effects_code_is_one_module():
    """What keeps independent effects as their parts, draws them and determinises them is
    defined in gdq_pddl/pddl/factored.py, and nowhere else: the grounder, the schema
    effects and the online store import it."""
    import ast
    from pathlib import Path

    import gdq_pddl.pddl as pkg
    names = {"FACTORED_ABOVE", "Factored", "factor", "factored_kept", "combine",
             "sample_parts", "gain_terms", "best_gain", "times", "merged", "both"}
    assert {name for name in names if hasattr(factoring, name)} == names
    for path in Path(pkg.__file__).parent.glob("*.py"):
        tree = ast.parse(path.read_text(encoding="utf-8"))
        defined = {n.name for n in tree.body if isinstance(n, ast.FunctionDef | ast.ClassDef)}
        defined |= {t.id for n in tree.body if isinstance(n, ast.Assign)
                    for t in n.targets if isinstance(t, ast.Name)}
        assert path.name == "factored.py" or not defined & names, path.name


# thirteen coins, each paying 1 with 1/2 when tossed: 2^13 = 8,192 combinations, but
# only the sums 0..13 differ, so the listing (equal effects merged) has 14 outcomes
PAY = """(define (domain pay) (:requirements :adl :probabilistic-effects :rewards)
  (:types coin) (:predicates (done))
  (:action toss :parameters () :effect (and (done)
    (forall (?c - coin) (probabilistic 1/2 (increase (reward) 1))))))
(define (problem pay-13) (:domain pay) (:objects %s - coin) (:init) (:goal (done)))
"""


def test_draws_whose_listing_fits_are_listed_not_factored():
    """The rule reads the listing after equal effects merge, not the product: 13 coins
    paying 1 each with 1/2 list 14 outcomes, a binomial of the sum, as before factoring."""
    from math import comb

    text = PAY % " ".join(f"k{i}" for i in range(13))
    learner, _ = grounded(text, text)
    toss = learner.ops[0]
    assert not toss.factored and len(toss.outcomes) == 14
    assert sorted((o.reward, o.probability) for o in toss.outcomes) == [
        (float(k), comb(13, k) / 2 ** 13) for k in range(14)]


def _listing_fits(own, draws, cap) -> bool:
    """Independently of :func:`factored.times`: whether the listing before factoring was
    made (each schema outcome's product with the draws, every prefix of draws at most
    ``cap`` distinct effects, and their sum at most ``cap``)."""
    from functools import reduce

    total = 0
    for first in own:
        for j in range(1, len(draws) + 1):
            size = len({reduce(factoring.both, (g for _, g in combo), first[1])
                        for combo in product(*draws[:j])})
            if size > cap:
                return False
        total += size if draws else 1
    return total <= cap


def test_the_factoring_rule_is_the_listings_size_exactly(monkeypatch):
    """Random parts over a few facts, conditional effects, amounts and failed trials,
    against caps of 1 to 40: an action is factored exactly where its listing passes the
    cap (where it was refused before factoring), whether the parts are separable (the
    size is the product, no listing made) or not (the listing made and stopped)."""
    rng = np.random.default_rng(7)
    facts, conds = ["a", "b", "c", "d"], ["x", "y"]

    def effect(own: str) -> tuple:  # own: the part's own facts (none shared), or ""
        pool = [own + f for f in facts]
        return (frozenset(f for f in pool if rng.random() < 0.3),
                frozenset(f for f in pool if rng.random() < 0.1),
                tuple(own + c for c in conds if rng.random() < 0.2),
                float(rng.integers(2)) if rng.random() < earns else 0.0, (),
                bool(rng.random() < 0.03))

    seen = {True: 0, False: 0}
    for trial in range(400):
        apart, earns = trial % 2 == 0, rng.choice([0.0, 0.3])
        parts = [factoring.merged([(1.0, effect(str(j) if apart else ""))
                                   for _ in range(rng.integers(1, 4))])
                 for j in range(rng.integers(2, 6))]
        own, draws = parts[0], parts[1:]
        cap = int(rng.integers(1, 41))
        monkeypatch.setattr(factoring, "FACTORED_ABOVE", cap)
        assert (factoring.factor(own, draws) is None) == _listing_fits(own, draws, cap)
        if len(own) * np.prod([len(d) for d in draws]) > cap:
            seen[factoring.separable(parts)] += 1
    assert min(seen.values()) > 20  # both ways of reading the size are exercised


def test_grounding_reads_each_exists_once_and_stops_at_a_false_static(monkeypatch):
    """Grounding sysadmin's reboot on n computers evaluates its exists over the computers
    once a (reboot, computer) pair, though two outcomes of a draw carry it, and stops each
    conjunction at its first false static literal ((conn ?c ?d): false for most ?c): about
    2 n^3 condition nodes, not the 8 n^3 of reading every literal of every copy."""
    from gdq_pddl.pddl import normalise

    plain, calls = normalise.ground_dnf, [0]

    def counted(*args, **kw):
        calls[0] += 1
        return plain(*args, **kw)

    monkeypatch.setattr(normalise, "ground_dnf", counted)
    n = 12
    grounded(SYSADMIN, network(n))
    assert calls[0] < 3 * n ** 3
