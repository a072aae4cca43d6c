"""The graders: each runs a student's function on seeded cases and compares what it returns
with the package's own learners (Q-learning's update, Dyna-Q's backups, GDQ's OptInit and
hybrid backup, on the office of the tutorial); the fifth, a question about GDQ's rule,
with :func:`gdq_pddl.exercises.solutions.trials_to_turn_away`, which a test checks
against GDQ's hybrid backup. The first case that differs is told in plain words: the
input, by the office's names where it has them, the expected and the returned value, and
a hint where the answer is what a known slip gives.
"""

from __future__ import annotations

import math
from collections.abc import Callable, Iterator
from dataclasses import dataclass
from functools import cache
from typing import Any

import numpy as np

from gdq_pddl.envs.office import OfficeEnv
from gdq_pddl.exercises import solutions
from gdq_pddl.learners import GDQ, GDQConfig, make_learner, office_task_context, run_episodes
from gdq_pddl.learners.context import TaskContext
from gdq_pddl.learners.gdq import hybrid_backup
from gdq_pddl.learners.learned_model import backup_known, learned_value, model_backup
from gdq_pddl.learners.tables import recompute_all_v
from gdq_pddl.learners.tabular import TabularLearner
from gdq_pddl.spaces import LearnerSpaces
from gdq_pddl.world import builtin_world

SEED = 2021
"""The seed of every grader's cases (the year of the paper)."""


@dataclass(frozen=True)
class Case:
    """One input of a student's function and what the package computes on it."""

    args: dict[str, Any]
    expected: Any
    words: str
    """The input in plain words."""
    slips: tuple[tuple[Any, str], ...] = ()
    """Answers a known slip gives on this input, each with its hint."""


@dataclass(frozen=True)
class Verdict:
    """A grader's result: passed or not, and what to tell the student."""

    passed: bool
    message: str
    cases: int = 0


# --- the office the cases come from ------------------------------------------------------------

@cache
def _office(task: str) -> tuple[TaskContext, LearnerSpaces]:
    world = builtin_world("office")
    return office_task_context(world, task), LearnerSpaces(world)


def _trained(method: str, task: str, episodes: int, seed: int, **config: Any
             ) -> TabularLearner:
    """A learner after ``episodes`` seeded episodes of ``task`` in the office."""
    context, _ = _office(task)
    learner = make_learner(method, context, **config)
    env = OfficeEnv(task=task)
    env.reset(seed=seed)
    run_episodes(learner, env, episodes, np.random.default_rng(seed))
    return learner


def _pair(spaces: LearnerSpaces, s: int, a: int) -> str:
    return f"({spaces.state_name(s)}, {spaces.action_name(a)}) [state {s}, action {a}]"


def _num(x: float) -> str:
    return f"{x:.6g}"


# --- exercise 1: the Q-learning update ---------------------------------------------------------

def q_update_cases() -> list[Case]:
    """Real steps of the office (task C, an exploring GDQ's), each with a random Q table,
    alpha and gamma; the expected value is what :class:`~gdq_pddl.learners.QLearning`'s
    ``observe`` makes of ``Q(s, a)``."""
    context, spaces = _office("C")
    rng = np.random.default_rng(SEED)
    env = OfficeEnv(task="C")
    actor = GDQ(context)
    steps = []
    for episode in range(6):
        s, _ = env.reset(seed=SEED + episode)
        done = False
        while not done:
            a = actor.act(s, rng) if rng.random() < 0.7 else int(rng.integers(95))
            s2, r, terminated, truncated, _ = env.step(a)
            done = terminated or truncated
            steps.append((s, a, r, s2, terminated, truncated))
            s = s2
    ends = [t for t in steps if t[4] or t[5]]
    moves = [t for t in steps if not (t[4] or t[5])]
    chosen = ends[:4] + [moves[i] for i in rng.choice(len(moves), 16, replace=False)]
    cases = []
    for k, (s, a, r, s2, terminated, truncated) in enumerate(chosen):
        alpha, gamma = (0.1, 0.95) if k % 3 else (0.5, 0.9)
        q = np.round(rng.normal(0.0, 5.0, (context.n_states, context.n_actions)), 2)
        learner = make_learner("qlearning", context, alpha=alpha, gamma=gamma)
        learner.q[:] = q
        recompute_all_v(learner.tables.table)
        learner.observe(s, a, r, s2, terminated, truncated, rng)
        done = bool(terminated or truncated)
        args = {"q": q, "s": s, "a": a, "r": float(r), "s2": s2, "done": done,
                "alpha": alpha, "gamma": gamma}
        words = (f"the step {_pair(spaces, s, a)} paid r = {r:g} and led to "
                 f"{spaces.state_name(s2)} [state {s2}], done = {done}; alpha = {alpha}, "
                 f"gamma = {gamma}; Q(s, a) was {_num(q[s, a])}, "
                 f"max_b Q(s2, b) is {_num(q[s2].max())}")
        target = r + gamma * q[s2].max()
        slips = ((q[s, a] + alpha * (r + q[s2].max() - q[s, a]), "the discount gamma is "
                  "missing: the target is r + gamma * max_b Q(s2, b)"),
                 (q[s, a] + alpha * (target - q[s, a]), "the target bootstraps from s2 "
                  "after the episode ended: when done, the target is r alone"),
                 (r if done else target, "Q(s, a) is set to the target: it moves only a "
                  "step alpha towards it"))
        cases.append(Case(args, float(learner.q[s, a]), words, slips))
    return cases


def _same_float(got: Any, expected: float, tol: float) -> bool:
    try:
        value = float(got)
    except (TypeError, ValueError):
        return False
    return math.isclose(value, expected, rel_tol=tol, abs_tol=tol)


def _float_diff(case: Case, got: Any, tol: float = 1e-9) -> str | None:
    if _same_float(got, case.expected, tol):
        return None
    if got is None:
        return f"expected {_num(case.expected)}; the function returned None (a return missing?)"
    return f"expected {_num(case.expected)}, got {_shown(got)}" + _hint(case, got, _same_float,
                                                                    tol)


def _shown(got: Any) -> str:
    """A returned value as a student reads it (a numpy number as a number)."""
    if isinstance(got, np.generic):
        got = got.item()
    return _num(got) if isinstance(got, float) else repr(got)


def _hint(case: Case, got: Any, same: Callable[[Any, Any, float], bool], tol: float) -> str:
    for answer, hint in case.slips:
        if not same(case.expected, answer, tol) and same(got, answer, tol):
            return f".\nHint: that is the answer when {hint}"
    return ""


# --- exercise 2: Dyna-Q's planning step --------------------------------------------------------

def _model_arrays(learner: TabularLearner) -> dict[str, np.ndarray]:
    """The learned model as the stub takes it: counts, stuck and mean step costs."""
    model = learner.tables.model
    overall = model.cost_all[0] / model.cost_all[1] if model.cost_all[1] else 0.0
    with np.errstate(invalid="ignore", divide="ignore"):
        cost = np.where(model.cost_n > 0, model.cost_sum / np.maximum(model.cost_n, 1),
                        overall)
    return {"counts": learner.counts, "stuck": model.stuck.copy(), "cost": cost}


def dyna_planning_cases() -> list[Case]:
    """Dyna-Q learners after seeded episodes of tasks B and C; the pairs are the ones
    Dyna-Q's planning draws with a seeded generator, the expected table what
    :func:`~gdq_pddl.learners.learned_model.backup_known` makes of the learner's."""
    cases = []
    learners = (("B", _trained("dynaq", "B", 40, SEED, n_backups=50)),
                ("C", _trained("dynaq", "C", 15, SEED, n_backups=5, gamma=0.9)))
    for task, learner in learners:
        context, spaces = _office(task)
        t, p = learner.tables, learner.params
        known = t.model.known[:t.model.n_known[0]]
        for k, n in enumerate((1, 8, 40)):
            seed = SEED + 10 * k
            draws = np.random.default_rng(seed)
            pairs = [divmod(int(known[draws.integers(0, len(known))]), context.n_actions)
                     for _ in range(n)]
            first = ", ".join(_pair(spaces, s, a).split(" [")[0] for s, a in pairs[:3])
            words = (f"a Dyna-Q learner after {'40' if task == 'B' else '15'} episodes of "
                     f"task {task}; {n} backup(s), of {first}{', ...' if n > 3 else ''}; "
                     f"gamma = {p.gamma}, r_max = {p.r_max:g}")
            q = learner.q.copy()
            backup_known(t.table, t.model, t.plans.opt_r, p._replace(n_backups=n),
                         np.random.default_rng(seed))
            cases.append(_backups_case(task, learner, q, pairs, words))
    cases.append(_picked_pairs_case(*learners[0]))
    return cases


def _backups_case(task: str, learner: TabularLearner, q: np.ndarray,
                  pairs: list[tuple[int, int]], words: str) -> Case:
    """The case of ``pairs`` just backed up in ``learner`` from the table ``q`` (its Q
    now, the expected table; ``q`` is put back), with the two slips of exercise 2."""
    context, _ = _office(task)
    p = learner.params
    expected = learner.q.copy()
    learner.q[:] = q
    recompute_all_v(learner.tables.table)
    args = {"q": q, **_model_arrays(learner), "goal": context.goal.copy(), "pairs": pairs,
            "gamma": p.gamma, "r_max": p.r_max}
    slips = ((_slip_table(solutions.dyna_planning, args, stuck=np.zeros_like(args["stuck"])),
              "the stuck trials are left out: each is worth -R_max and counts in n"),
             (_parallel_backups(args), "every backup reads the Q table as it was before "
              "the first: back the pairs up one after the other, each reading the values "
              "the earlier ones wrote"))
    return Case(args, expected, words, slips)


def _picked_pairs_case(task: str, learner: TabularLearner) -> Case:
    """Every pair of ``learner`` that got stuck or reached the goal, then the pairs that
    lead to their states, backed up in that order by
    :func:`~gdq_pddl.learners.learned_model.model_backup`."""
    context, spaces = _office(task)
    t, p = learner.tables, learner.params
    counts = learner.counts
    ending = np.argwhere((t.model.stuck > 0) | (counts[:, :, context.goal].sum(axis=2) > 0))
    states = set(ending[:, 0].tolist())
    feeding = np.argwhere(counts[:, :, sorted(states)].sum(axis=2) > 0)
    pairs = [(int(s), int(a)) for s, a in (*ending[:12], *feeding[:12])]
    q = learner.q.copy()
    rng = np.random.default_rng(SEED)
    for s, a in pairs:
        model_backup(t.table, t.model, t.plans.opt_r, p, s, a, rng)
    words = (f"the Dyna-Q learner after 40 episodes of task {task}; {len(pairs)} backups: "
             "first the pairs that got stuck or reached the goal, then pairs leading to "
             f"their states; gamma = {p.gamma}, r_max = {p.r_max:g}")
    return _backups_case(task, learner, q, pairs, words)


def _slip_table(solution: Callable, args: dict[str, Any], **changed: Any) -> np.ndarray:
    return solution(**{**args, **changed})


def _parallel_backups(args: dict[str, Any]) -> np.ndarray:
    q = args["q"].copy()
    for s, a in args["pairs"]:
        q[s, a] = solutions.dyna_planning(args["q"], args["counts"], args["stuck"],
                                          args["cost"], args["goal"], [(s, a)], args["gamma"],
                                          args["r_max"])[s, a]
    return q


def _same_table(got: Any, expected: np.ndarray, tol: float) -> bool:
    try:
        table = np.asarray(got, dtype=float)
    except (TypeError, ValueError):
        return False
    return table.shape == expected.shape and np.allclose(table, expected, rtol=0, atol=tol)


def _table_diff(spaces: LearnerSpaces, tol: float) -> Callable[[Case, Any], str | None]:
    def diff(case: Case, got: Any) -> str | None:
        expected = case.expected
        if _same_table(got, expected, tol):
            return None
        if got is None:
            return "the function returned None: return the Q table (a new one, or q changed)"
        try:
            table = np.asarray(got, dtype=float)
        except (TypeError, ValueError):
            return f"expected a table of shape {expected.shape}, got {type(got).__name__}"
        if table.shape != expected.shape:
            return f"expected a table of shape {expected.shape}, got shape {table.shape}"
        wrong = np.argwhere(~np.isclose(table, expected, rtol=0, atol=tol))
        s, a = (int(x) for x in wrong[0])
        return (f"{len(wrong)} entr{'y differs' if len(wrong) == 1 else 'ies differ'}; the "
                f"first, Q{_pair(spaces, s, a)}: expected {_num(expected[s, a])}, got "
                f"{_num(table[s, a])}" + _hint(case, got, _same_table, tol))
    return diff


# --- exercise 3: OptInit -----------------------------------------------------------------------

def optinit_cases() -> list[Case]:
    """The office's tasks A-E and some settings: the expected table is a fresh GDQ
    learner's Q after its OptInit."""
    cases = []
    for task, config in (("A", {}), ("B", {}), ("C", {}), ("C", {"gamma": 0.8}),
                         ("D", {"prior_cost": 0.5}), ("E", {"gamma": 0.99})):
        context, spaces = _office(task)
        learner = GDQ(context, GDQConfig(**config))
        p = learner.params
        args = {"next_state": context.prior.next_state.copy(), "goal": context.goal.copy(),
                "gamma": p.gamma, "r_max": p.r_max, "step_cost": p.prior_cost}
        goal = ", ".join(spaces.state_name(s) for s in np.flatnonzero(context.goal))
        words = (f"the office's knowledge, task {task} (goal states: {goal}); gamma = "
                 f"{p.gamma}, r_max = {p.r_max:g}, step_cost = {p.prior_cost:g}")
        cases.append(Case(args, learner.q.copy(), words))
    return cases


def _optinit_diff(spaces: LearnerSpaces) -> Callable[[Case, Any], str | None]:
    table_diff = _table_diff(spaces, 1e-6)

    def diff(case: Case, got: Any) -> str | None:
        message = table_diff(case, got)
        if message is None:
            return None
        goal = case.args["goal"]
        table = np.asarray(got, dtype=float)
        if table.shape == case.expected.shape and np.allclose(
                table[~goal], case.expected[~goal], rtol=0, atol=1e-6):
            message += ".\nHint: only the goal states' rows differ: they are 0 (the " \
                       "episode is over there)"
        return message
    return diff


# --- exercise 4: GDQ's hybrid backup -----------------------------------------------------------

def hybrid_backup_cases() -> list[Case]:
    """Pairs of a GDQ learner after seeded episodes of task C (known and unknown, ones
    the knowledge says apply and ones it says do nothing, ones into the goal), with
    several m and w: the expected value is :func:`~gdq_pddl.learners.gdq.hybrid_backup`."""
    context, spaces = _office("C")
    learner = _trained("gdq", "C", 30, SEED)
    t, p = learner.tables, learner.params
    visits, prior_next = t.model.visits, t.prior.next_state
    rng = np.random.default_rng(SEED)
    applicable = prior_next >= 0
    into_goal = applicable & context.goal[np.maximum(prior_next, 0)]
    groups = (("tried, applicable", (visits > 0) & applicable & ~context.goal[:, None]),
              ("tried, does nothing by the knowledge", (visits > 0) & ~applicable),
              ("tried once, applicable", (visits == 1) & applicable),
              ("untried, applicable", (visits == 0) & applicable),
              ("untried, does nothing by the knowledge", (visits == 0) & ~applicable),
              ("into the goal", into_goal))
    cases = []
    for m, w in ((0, 1.0), (2, 1.0), (0, 0.0), (1, 3.0)):
        params = p._replace(m=m, prior_weight=w)
        few = (visits > 0) & (visits <= m)
        for label, mask in (*groups, ("tried at most m times, applicable", few & applicable),
                            ("tried at most m times, does nothing by the knowledge",
                             few & ~applicable)):
            pairs = np.argwhere(mask & ~context.goal[:, None])
            if not len(pairs):
                continue
            s, a = (int(x) for x in pairs[rng.integers(len(pairs))])
            x = int(prior_next[s, a])
            leads = "does nothing (-1)" if x < 0 else f"leads to {spaces.state_name(x)}"
            cases.append(_hybrid_case(learner, params, s, a, f"the pair {_pair(spaces, s, a)} "
                                      f"({label}): by the knowledge it {leads}; tried "
                                      f"{int(visits[s, a])} time(s), ", no_gamma=True))
    return cases + _passage_cases()


def _passage_cases() -> list[Case]:
    """``goto p17`` at ``p8``, which the knowledge says does nothing, tried once where
    reality has the corridor p8-p17 (``gdq-pddl knowledge``, case passage): with m = 2
    too, a pair the knowledge says does nothing is known after its first trial."""
    context, spaces = _office("C")
    learner = GDQ(context)
    s, a = spaces.state("p8"), spaces.action("goto", "p17")
    s2 = spaces.state("p17")
    learner.observe(s, a, context.r_max, s2, True, False, np.random.default_rng(SEED))
    head = (f"the pair {_pair(spaces, s, a)}: the knowledge says it does nothing (-1), but "
            "reality has a corridor p8-p17 and its one trial reached the goal, ")
    return [_hybrid_case(learner, learner.params._replace(m=m), s, a, head, no_gamma=False)
            for m in (0, 2)]


def _hybrid_case(learner: TabularLearner, params: Any, s: int, a: int, head: str,
                 no_gamma: bool) -> Case:
    """The pair ``(s, a)`` of a GDQ ``learner`` under ``params`` (its m and w): the
    expected value is :func:`~gdq_pddl.learners.gdq.hybrid_backup`; the words ``head``
    then the numbers; the slips of exercise 4 (``no_gamma``: the discount one too)."""
    t, p = learner.tables, learner.params
    visits, prior_next = t.model.visits, t.prior.next_state
    learned = float(learned_value(t.model.slots, t.model.stuck, visits, t.model.cost_sum,
                                  t.model.cost_n, t.model.cost_all, t.table.goal, t.table.v,
                                  params, s, a)) if visits[s, a] else 0.0
    expected = float(hybrid_backup(t.table, t.model, prior_next, t.prior.reward,
                                   t.prior.dead, params, s, a))
    m, w = params.m, params.prior_weight
    args = {"s": s, "a": a, "v": t.table.v.copy(), "goal": learner.context.goal.copy(),
            "prior_next": prior_next.copy(), "visits": visits.copy(), "learned": learned,
            "m": m, "w": w, "gamma": p.gamma, "r_max": p.r_max, "prior_cost": p.prior_cost}
    words = f"{head}learned = {_num(learned)}; m = {m}, w = {w:g}, gamma = {p.gamma}, " \
        f"r_max = {p.r_max:g}"
    wrong_rule = solutions.hybrid_backup(**{**args, "prior_next": np.where(
        prior_next < 0, s, prior_next)}) if prior_next[s, a] < 0 else math.nan
    slips = ((wrong_rule, "a pair the knowledge says does nothing waits for m trials too: "
              "it is known after its first trial"),)
    if no_gamma:
        slips += ((_no_gamma_prior(args), "the prior's backup lacks the discount: it is "
                   "-prior_cost + gamma * V(x)"),)
    return Case(args, expected, words, slips)


def _no_gamma_prior(args: dict[str, Any]) -> float:
    """The hybrid backup with a prior backup that forgets gamma (a slip)."""
    gamma = args["gamma"]
    v = args["v"] / gamma  # so that gamma * v is the undiscounted v
    return solutions.hybrid_backup(**{**args, "v": v})


# --- exercise 5: wrong knowledge ---------------------------------------------------------------

def wrong_knowledge_cases() -> list[Case]:
    """A jammed door d0 (values from a fresh GDQ learner), then
    seeded random values; the expected count is the reference solution's, checked against
    GDQ's hybrid backup in ``tests/exercises``."""
    cases = [_jammed_door_case()]
    rng = np.random.default_rng(SEED)
    for k in range(24):
        prior = round(float(rng.uniform(0.0, 15.0)), 2)
        alternative = round(prior - float(rng.uniform(0.1, 8.0)), 2)
        trial = round(alternative - float(rng.uniform(0.2, 15.0)), 2)
        if k % 8 == 3:
            alternative = round(prior + 1.5, 2)  # the prior already below
        if k % 8 == 5:
            trial = round(alternative + 0.5, 2)  # failing is no worse: never
        w = float(rng.choice([0.5, 1.0, 2.0, 5.0]))
        m = int(rng.choice([0, 0, 1, 3]))
        cases.append(_turn_case(prior, trial, alternative, w, m, "chosen at random"))
    return cases


def _jammed_door_case() -> Case:
    """Door d0 as if jammed: the values of a fresh GDQ learner at p1 before d0 (task C)."""
    context, spaces = _office("C")
    learner = GDQ(context)
    s, door = spaces.state("p1"), spaces.action("opendoor", "p1")
    allowed = learner.tables.table.allowed[s]
    others = [b for b in np.flatnonzero(allowed) if b != door]
    prior, alternative = float(learner.q[s, door]), float(learner.q[s, others].max())
    return _turn_case(round(prior, 4), -context.r_max, round(alternative, 4), 1.0, 0,
                      "opendoor p1 at door d0 (task C), jammed, by a fresh GDQ")


def _turn_case(prior: float, trial: float, alternative: float, w: float, m: int,
               source: str) -> Case:
    args = {"prior_value": prior, "trial_value": trial, "alternative": alternative, "w": w,
            "m": m}
    expected = solutions.trials_to_turn_away(**args)
    words = (f"{source}: prior_value = {prior:g}, trial_value = {trial:g}, alternative = "
             f"{alternative:g}, w = {w:g}, m = {m}")
    slips = ()
    if expected:
        slips = ((expected - 1, "the pair is counted known after m trials: it takes more "
                  "than m"), (expected + 1, "the value must end strictly below the "
                  "alternative, not at or below it"))
    return Case(args, expected, words, slips)


def _count_diff(case: Case, got: Any) -> str | None:
    if got == case.expected and type(got) is type(case.expected) or (
            isinstance(got, int | np.integer) and not isinstance(got, bool)
            and case.expected is not None and int(got) == case.expected):
        return None
    message = f"expected {case.expected!r}, got {_shown(got)}"
    for answer, hint in case.slips:
        if got == answer:
            return f"{message}.\nHint: one off, as when {hint}"
    return message


# --- running a grader ----------------------------------------------------------------------------

GRADERS: dict[int, tuple[Callable[[], list[Case]], Callable[[], Callable[[Case, Any],
                                                                       str | None]]]] = {
    1: (q_update_cases, lambda: _float_diff),
    2: (dyna_planning_cases, lambda: _table_diff(_office("B")[1], 1e-9)),
    3: (optinit_cases, lambda: _optinit_diff(_office("C")[1])),
    4: (hybrid_backup_cases, lambda: _float_diff),
    5: (wrong_knowledge_cases, lambda: _count_diff),
}
"""Per exercise number: its cases, and the comparison of an answer with a case's."""


def _copies(args: dict[str, Any]) -> Iterator[tuple[str, Any]]:
    for key, value in args.items():
        yield key, value.copy() if isinstance(value, np.ndarray) else \
            list(value) if isinstance(value, list) else value


def grade(number: int, function: Callable, title: str) -> Verdict:
    """Run ``function`` on the cases of exercise ``number``; the first case that differs
    (or raises) fails it."""
    make_cases, make_diff = GRADERS[number]
    cases, diff = make_cases(), make_diff()
    head = f"Exercise {number} ({title})"
    for i, case in enumerate(cases, 1):
        try:
            got = function(**dict(_copies(case.args)))
        except NotImplementedError:
            return Verdict(False, f"{head}: not written yet (the function raises "
                                  f"NotImplementedError). Fill it in and check again.",
                           len(cases))
        except Exception as exc:  # the student's code: any error is theirs to see
            return Verdict(False, f"{head}: case {i} of {len(cases)} raised "
                                  f"{type(exc).__name__}: {exc}\nThe input: {case.words}.",
                           len(cases))
        problem = diff(case, got)
        if problem is not None:
            return Verdict(False, f"{head}: case {i} of {len(cases)} differs.\nThe input: "
                                  f"{case.words}.\nWhat differs: {problem}.", len(cases))
    return Verdict(True, f"{head}: all {len(cases)} cases pass.", len(cases))
