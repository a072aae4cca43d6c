"""What makes a domain like IPPC-2008 boxworld (every effect under a `when`, a drive
whose wrong destinations are three nested foralls over the cities under static `when`s)
fast to ground and to explore online: a binding whose static `when` fails is not
grounded further (gdq_pddl/pddl/ppddl_effects.py), and an action none of whose
conditions holds in a state is not applied outcome by outcome (gdq_pddl/pddl/lazy.py).
Both give what the plain way gives."""

from __future__ import annotations

import numpy as np

from gdq_pddl.pddl import ppddl_effects
from gdq_pddl.pddl.grounding import GroundOutcome
from gdq_pddl.pddl.lazy import LazyGraph
from gdq_pddl.planning.base import PlanningProblem
from tests.pddl.test_lazy import assert_same_graph

DOMAIN = """(define (domain drive)
 (:requirements :typing :conditional-effects :probabilistic-effects :rewards)
 (:types city truck)
 (:predicates (at ?t - truck ?c - city) (road ?a - city ?b - city)
              (wrong1 ?a - city ?b - city) (wrong2 ?a - city ?b - city))
 (:action drive
  :parameters (?t - truck ?a - city ?b - city)
  :effect (when (and (at ?t ?a) (road ?a ?b))
           (and (not (at ?t ?a)) (decrease (reward) 1)
            (probabilistic
             0.25 (forall (?w1 - city) (when (wrong1 ?a ?w1)
                   (forall (?w2 - city) (when (wrong2 ?a ?w2)
                    (probabilistic 1/2 (at ?t ?w1) 1/2 (at ?t ?w2))))))
             0.75 (at ?t ?b))))))
"""


def problem_text(n: int) -> str:
    cities = " ".join(f"c{i}" for i in range(n))
    facts = []
    for i in range(n):
        j, k = (i + 1) % n, (i + 2) % n
        facts += [f"(road c{i} c{j})", f"(road c{i} c{k})", f"(wrong1 c{i} c{j})",
                  f"(wrong2 c{i} c{k})"]
    return (f"(define (problem p) (:domain drive) (:objects {cities} - city t0 t1 - truck)"
            f" (:init (at t0 c0) (at t1 c1) {' '.join(facts)})"
            f" (:goal (and (at t0 c{n - 1}) (at t1 c0))))")


def load(tmp_path, n: int) -> PlanningProblem:
    (tmp_path / "d.pddl").write_text(DOMAIN)
    (tmp_path / "p.pddl").write_text(problem_text(n))
    return PlanningProblem.from_files(tmp_path / "d.pddl", tmp_path / "p.pddl")


def test_a_failed_static_when_is_not_grounded_further(tmp_path, monkeypatch):
    """Without the pruning, each drive grounds n x n inner bindings (n^3 actions x n^2):
    with it, the inner forall is grounded only under the one ?w1 whose wrong1 holds."""
    n = 9
    calls = [0]
    plain = ppddl_effects._ground_outcome

    def counted(*args, **kw):
        calls[0] += 1
        return plain(*args, **kw)

    monkeypatch.setattr(ppddl_effects, "_ground_outcome", counted)
    task = load(tmp_path, n).learner_task
    n_drives = 2 * n * n
    assert calls[0] < n_drives * 4 * n  # the plain way: n_drives * (2 + n + 2 n^2)
    drive = next(op for op in task.ops if op.name == "(drive t0 c0 c1)")
    # a wrong turn to c1 or c2 (1/2 each of 0.25), or c1 as meant (0.75)
    moved = sorted((round(o.probability, 6), tuple(sorted(task.atoms(
        next(a for _, _, a, _ in o.conditional if a))))) for o in drive.outcomes)
    assert moved == [(0.125, ("(at t0 c1)",)), (0.125, ("(at t0 c2)",)),
                     (0.75, ("(at t0 c1)",))]


def test_pruned_grounding_matches_the_plain_one(tmp_path, monkeypatch):
    """The same ground actions and outcomes with the pruning as without it."""
    pruned = load(tmp_path, 5).learner_task
    monkeypatch.setattr(ppddl_effects, "_guards", lambda o: frozenset())
    plain = load(tmp_path, 5).learner_task

    def shape(task):
        return [(op.name, op.pre, op.neg, [(o.probability, o.add, o.dele, o.stuck,
                                            o.conditional, o.reward, o.rewards)
                                           for o in op.outcomes]) for op in task.ops]

    assert shape(pruned) == shape(plain)


def test_an_action_that_changes_nothing_is_not_applied(tmp_path, monkeypatch):
    """Expanding a state applies the outcomes of the drives from the trucks' cities only
    (every other drive's `when` fails there), and still gives the enumerated graph."""
    task = load(tmp_path, 5).learner_task
    applied = [0]
    plain = GroundOutcome.apply

    def counted(self, state):
        applied[0] += 1
        return plain(self, state)

    monkeypatch.setattr(GroundOutcome, "apply", counted)
    lazy = LazyGraph(task, gains=True)
    lazy.expand([0])
    moving = sum(len(op.outcomes) for op in task.ops
                 if op.name.split()[1:3] in (["t0", "c0"], ["t1", "c1"]))
    assert 0 < applied[0] <= 2 * moving  # outcomes and the edges' own applies
    monkeypatch.setattr(GroundOutcome, "apply", plain)
    assert_same_graph(task, "id order")


def test_an_online_run_shows_its_episodes_and_the_states_found(monkeypatch):
    """A run on a problem explored online reports each episode to a progress bar (shown
    after 2 s on a terminal: slow_progress), with the states found so far."""
    from gdq_pddl.envs.online import OnlineInstance
    from gdq_pddl.envs.online_env import OnlineEnv
    from gdq_pddl.learners import episodes, make_learner, run_episodes
    from gdq_pddl.learners.online import online_context
    from tests.envs.test_online import shipped

    bars = []

    class Bar:
        def __init__(self, desc, unit, total):
            self.desc, self.total, self.n, self.states, self.closed = desc, total, 0, [], False
            bars.append(self)

        def update(self, k):
            self.n += k

        def set_postfix(self, states, refresh):
            self.states.append(states)

        def close(self):
            self.closed = True

    monkeypatch.setattr(episodes, "slow_progress", Bar)
    online = OnlineInstance(shipped("keys-ppddl", "keys-ppddl-1"))
    env = OnlineEnv(online)
    env.reset(seed=0)
    run_episodes(make_learner("Q-learning", online_context(online)), env, 5,
                 np.random.default_rng(0))
    [bar] = bars
    assert (bar.total, bar.n, bar.closed) == (5, 5, True)
    assert "online" in bar.desc and bar.states[0] >= 1
    assert bar.states == sorted(bar.states) and bar.states[-1] <= online.graph.n_states
