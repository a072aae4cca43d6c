"""Hyper-parameters of the learners, one frozen dataclass per method.

Defaults are the paper's simulation settings (alpha 0.1, gamma 0.95, epsilon 0.1) and,
where the paper is silent, the authors' released code (N, m, the 1.3 plan-length
tolerance). ``R_max`` belongs to the task: every learner reads it from the task context.
"""

from __future__ import annotations

import ast
import inspect
import sys
from dataclasses import dataclass, fields
from functools import cache
from typing import Literal

from gdq_pddl.errors import ConfigError
from gdq_pddl.limits import MAX_NUMBER, MAX_TOLERANCE, check_count, check_real

EXPLORE_ALL = 0.1
"""The default GDQ's ``explore_all`` where the knowledge may differ from reality."""

GDQVariant = Literal["prior", "literal", "code"]
GDQ_VARIANTS: tuple[str, ...] = ("prior", "literal", "code")
"""``prior``, the default GDQ; ``literal`` and ``code``, the paper's two readings (the
default's former name ``model`` is still accepted)."""
DarlingVariant = Literal["paper", "code"]

MAX_BACKUPS = 1_000_000
"""The most model backups per real step a config accepts (the paper's settings are 3-5)."""


def check_choice(name: str, value: object, choices: tuple) -> None:
    """ConfigError unless ``value`` is one of ``choices`` (of its type: 1 is not True)."""
    if not any(isinstance(value, type(c)) and value == c for c in choices):
        raise ConfigError(f"{name} must be one of {', '.join(map(repr, choices))}, got "
                          f"{value!r}")


@cache
def _field_docs() -> dict[tuple[str, str], str]:
    """``{(class, field): docstring}`` of this module's source ({} if it has none)."""
    try:
        tree = ast.parse(inspect.getsource(sys.modules[__name__]))
    except (OSError, TypeError):
        return {}
    return {(c.name, f.target.id): inspect.cleandoc(d.value.value)
            for c in tree.body if isinstance(c, ast.ClassDef)
            for f, d in zip(c.body, c.body[1:], strict=False)
            if isinstance(f, ast.AnnAssign) and isinstance(f.target, ast.Name)
            and isinstance(d, ast.Expr) and isinstance(d.value, ast.Constant)}


def documented(cls: type) -> type:
    """Append each field's docstring (which ``help()`` does not show) to the class
    docstring, as an ``Attributes`` list."""
    docs = {f.name: doc for f in fields(cls) for base in cls.__mro__[::-1]
            if (doc := _field_docs().get((base.__name__, f.name)))}
    items = "\n".join(f"    {name}: " + doc.replace("\n", "\n        ")
                      for name, doc in docs.items())
    cls.__doc__ = f"{inspect.cleandoc(cls.__doc__ or '')}\n\nAttributes:\n{items}"
    return cls


@documented
@dataclass(frozen=True)
class LearnerConfig:
    """Parameters shared by every tabular learner."""

    alpha: float = 0.1
    """Step size of the temporal-difference update (real experience, and the sample-based
    model backups of GDQ's ``code`` variant)."""
    gamma: float = 0.95
    """Discount factor, used in every update and in OptInit's policy iteration."""
    epsilon: float = 0.1
    """Probability of a uniformly random (allowed) action instead of the greedy one."""

    def __post_init__(self) -> None:
        check_real("alpha", self.alpha, 0.0, 1.0, low_open=True)
        check_real("gamma", self.gamma, 0.0, 1.0, high_open=True)
        check_real("epsilon", self.epsilon, 0.0, 1.0)


@documented
@dataclass(frozen=True)
class QLearningConfig(LearnerConfig):
    """Q-learning: nothing beyond the shared parameters."""


@documented
@dataclass(frozen=True)
class DynaQConfig(LearnerConfig):
    """Dyna-Q: Q-learning plus ``n_backups`` model backups per real step."""

    n_backups: int = 3
    """N: model backups per real step, each on a uniformly random previously observed
    (state, action) pair (the authors' code used 3 for Dyna-Q)."""
    m: int = 0
    """A pair is used for backups once it has been tried more than ``m`` times (0, "tried
    at least once", is classic Dyna-Q; a larger m only delays planning)."""

    def __post_init__(self) -> None:
        super().__post_init__()
        check_count("n_backups", self.n_backups, MAX_BACKUPS)
        check_count("m", self.m)  # at most MAX_COUNT, as int64 holds


@documented
@dataclass(frozen=True)
class GDQConfig(LearnerConfig):
    """Guided Dyna-Q: ``"prior"`` (the default: the action knowledge as an optimistic prior
    over every pair, :mod:`gdq_pddl.learners.gdq`), ``"literal"`` (the paper's Algorithms
    1-3 read literally) or ``"code"`` (as the authors' released code); ``docs/learners.md``
    compares them. The ``prior`` defaults were chosen on tasks A-D only
    (``docs/decisions.md``)."""

    variant: GDQVariant = "prior"
    """Which GDQ (above)."""
    n_backups: int | None = None
    """N: simulated backups per real step (default 5). ``prior``: prioritised sweeping
    recomputes pair values until at least N are done, finishing every state it takes
    from the queue; ``literal`` and ``code``: backups of a random transition of a random
    plan from the current state (the authors' code)."""
    m: int | None = None
    """A knowledge-applicable pair is *known* once tried more than ``m`` times: from then
    on its model is learned, before that the optimistic one. Default 0 for ``prior``
    (where a pair the knowledge says does nothing is known after its first trial
    whatever ``m``), 5 for the others (the authors' code)."""
    prior_weight: float = 1.0
    """``prior`` only: a known pair's model is the posterior mean with the prior as this
    many pseudo-observations, ``(w * prior + n * learned) / (w + n)`` after ``n``
    trials; 0 is the plain empirical model."""
    explore: Literal["values", "plans", "applicable"] = "values"
    """``prior`` only: what exploring steps draw from (but for the ``explore_all`` share):
    ``"values"``, the actions whose value is within ``plan_tolerance`` of the state's
    (``q >= v - plan_tolerance * (r_max - v)``: DARLING's length tolerance carried to
    GDQ's own values, so that at first, on accurate knowledge, they are the plans' first
    actions, and an action learned to be worse leaves them); ``"plans"``, the first
    actions of the plans within ``plan_tolerance`` from the current state (DARLING's set;
    every action in a state with no plan); ``"applicable"``, every action the knowledge
    says can do something here. Why ``"values"``: ``docs/decisions.md``."""
    explore_loops: bool = False
    """``prior`` with ``explore="values"`` only: whether an exploring step may draw a move
    that the next greedy step would undo, where the knowledge says it leads to a state
    whose greedy action leads straight back (a two-step loop: put a block down, pick it
    up again). False: such moves are left out, as DARLING's plans are loop-free. Why:
    ``docs/decisions.md``."""
    explore_all: float | None = None
    """``prior`` only: this share of exploring steps draws from every action instead,
    one never tried in the current state first (any action once all were). Above 0 the
    knowledge never forbids an action; on accurate knowledge every such step is wasted.
    None: 0.1 where the knowledge may differ from reality (the office, a STRIPS domain
    with a dynamics file), 0 where it is reality's own actions and outcomes (a PPDDL
    domain: no action or outcome can be missing from it;
    :attr:`~gdq_pddl.learners.context.TaskContext.exact_knowledge`)."""
    explore_all_last_step: bool = True
    """``prior`` only: whether the ``explore_all`` share applies also in a state from which
    the knowledge reaches the goal in one action (where an action it lacks cannot
    shorten the route). ``False`` spares most of the cost of ``explore_all`` on short
    tasks; why it is not the default: ``docs/decisions.md``."""
    prior_cost: float = 1.0
    """``prior`` only: the step cost the prior charges (the planner counts actions). On
    a problem's own reward scale at most ``r_max / step_limit``, so that no plan within
    the step limit is worth less to the prior than doing nothing, and charged besides
    the file's rewards (``TaskContext.prior_reward``; ``docs/decisions.md``)."""
    sweep_threshold: float = 1e-6
    """``prior`` only: a state-value change smaller than this is not propagated."""
    optimistic_successor: Literal["start", "terminal"] = "start"
    """``literal`` only: where an optimistic (unknown) pair leads. ``"start"``: to s0, as
    Algorithm 1's ``T(s, a, s0) = 1``. ``"terminal"`` (not in the paper): the optimistic
    reward ends the episode, which shows where the excess optimism comes from."""
    plan_tolerance: float | None = None
    """H holds every loop-free plan up to ``(1 + plan_tolerance)`` x the shortest length.
    None: 0 for ``"literal"`` (the paper's "shortest plans"), 0.3 for ``"code"`` (the
    authors' planner) and ``"prior"`` (which uses them only to explore). The task context
    must hold a plan table built with that tolerance (its ``darling_plans``)."""

    def __post_init__(self) -> None:
        super().__post_init__()
        if self.variant == "model":  # the default's former name
            object.__setattr__(self, "variant", "prior")
        check_choice("variant", self.variant, GDQ_VARIANTS)
        prior = self.variant == "prior"
        for name, default in (("n_backups", 5), ("m", 0 if prior else 5),
                              ("plan_tolerance", 0.0 if self.variant == "literal" else 0.3)):
            if getattr(self, name) is None:
                object.__setattr__(self, name, default)
        check_count("n_backups", self.n_backups, MAX_BACKUPS)
        check_count("m", self.m)
        check_real("plan_tolerance", self.plan_tolerance, 0.0, MAX_TOLERANCE)
        check_choice("optimistic_successor", self.optimistic_successor, ("start", "terminal"))
        check_choice("explore", self.explore, ("values", "plans", "applicable"))
        if self.explore_all is not None:
            check_real("explore_all", self.explore_all, 0.0, 1.0)
        check_choice("explore_all_last_step", self.explore_all_last_step, (True, False))
        check_choice("explore_loops", self.explore_loops, (True, False))
        for name in ("prior_weight", "prior_cost", "sweep_threshold"):
            check_real(name, getattr(self, name), 0.0, MAX_NUMBER)


@documented
@dataclass(frozen=True)
class DarlingConfig(LearnerConfig):
    """DARLING (Leonetti, Iocchi & Stone 2016): Q-learning over plan-restricted actions."""

    tolerance: float = 0.3
    """Plans up to (1 + tolerance) x the shortest length define the allowed actions;
    the task context's DARLING plan table must have been built with this tolerance."""
    variant: DarlingVariant = "paper"
    """``"paper"``: Leonetti et al.'s DARLING; the plan actions are the only ones it may
    choose, when exploring and in the max of the update alike. ``"code"``: as the GDQ
    authors' released agent runs it (``docs/learners.md``): the greedy choice and the
    max range over *all* actions, and a non-plan action is replaced by a random plan
    action."""

    def __post_init__(self) -> None:
        super().__post_init__()
        check_real("tolerance", self.tolerance, 0.0, MAX_TOLERANCE)
        check_choice("variant", self.variant, ("paper", "code"))
