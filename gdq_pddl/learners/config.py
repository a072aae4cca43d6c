"""Hyper-parameters of the learners, one frozen dataclass per method.

Defaults are the paper's simulation settings (alpha 0.1, gamma 0.95, epsilon 0.1) and,
where the paper is silent, the authors' released code (N, m, the 1.3 plan-length
tolerance). ``R_max`` is not a learner parameter: it belongs to the world (its world
file), and every learner reads it from the task context.
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

GDQVariant = Literal["prior", "literal", "code"]
GDQ_VARIANTS: tuple[str, ...] = ("prior", "literal", "code")
"""``prior``, the default GDQ; ``literal`` and ``code``, the paper's two readings. The
default was called ``model`` before "model" came to mean only the learned model; that
name is still accepted."""
DarlingVariant = Literal["paper", "code"]

MAX_BACKUPS = 1_000_000
"""The most model backups per real step a config accepts (each costs about a
microsecond; the paper's settings are 3-5)."""

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
    """A pair is used for backups once it has been tried more than ``m`` times. Dyna-Q
    has no optimistic model to fall back on, so the default 0 means "observed at least
    once", which is classic Dyna-Q; a larger m only delays planning."""

    def __post_init__(self) -> None:
        super().__post_init__()
        check_count("n_backups", self.n_backups, MAX_BACKUPS)
        check_count("m", self.m)  # at most MAX_COUNT, as int64 holds


@documented
@dataclass(frozen=True)
class GDQConfig(LearnerConfig):
    """Guided Dyna-Q. Three variants (``docs/learners.md`` compares them):

    - ``"prior"`` (the default): the paper's idea done soundly. The action knowledge is
      an optimistic *prior* over every (state, action) pair; the learned model replaces it
      pair by pair; prioritised sweeping plans on the mix of the two
      (:mod:`gdq_pddl.learners.gdq`).
    - ``"literal"``: the paper's Algorithms 1-3 read literally (OptInit's policy
      iteration on a model where every optimistic pair leads back to s0; N expected
      backups along plans per step). It does not learn: its values inflate to
      R_max / (1 - gamma).
    - ``"code"``: as the authors' released code (Q <- R_max on plan pairs, N sample
      backups along plans within 1.3 x the shortest per step).

    The ``prior`` defaults were chosen on tasks A-D (and, for ``explore_all``, the
    corridor the knowledge lacks) only; ``docs/decisions.md`` has the measurements.
    """

    variant: GDQVariant = "prior"
    """Which GDQ (above)."""
    n_backups: int | None = None
    """N: simulated backups per real step. ``prior``: prioritised sweeping recomputes pair
    values until at least N are done, finishing every state it takes from the queue
    (so a step can recompute more than N; default 5: on tasks A-D 1, 5, 10 and 40 learn
    alike, and each costs time, ``benchmarks/learners.py speed``);
    ``literal`` and ``code``: backups of a random transition of a random plan from the
    current state (default 5, the authors' code)."""
    m: int | None = None
    """A knowledge-applicable pair is *known* once tried more than ``m`` times: from then
    on its model is learned, before that the optimistic one. Default 0 for ``prior``
    (known after one trial, the prior kept as ``prior_weight`` pseudo-observations), 5
    for the others (the authors' code). In ``prior`` a pair the knowledge says does
    nothing is known after its first trial whatever ``m``."""
    prior_weight: float = 1.0
    """``prior`` only: a known pair's model is the posterior mean with the prior as this
    many pseudo-observations, ``(w * prior + n * learned) / (w + n)`` after ``n``
    trials. It keeps one unlucky early trial (a door that failed twice) from writing off
    a route for good; 0 is the plain empirical model (measured on tasks A-D: 1 is
    better than 0, and 0.5 or 2 no different from 1)."""
    explore: Literal["plans", "applicable"] = "plans"
    """``prior`` only: what exploring steps draw from (but for the ``explore_all`` share):
    ``"plans"``, the first actions of the plans within ``plan_tolerance`` from the
    current state (DARLING's set; every action in a state with no plan);
    ``"applicable"``, every action the knowledge says can do something here (measured
    worse on every task A-D: it wanders off the routes)."""
    explore_all: float = 0.1
    """``prior`` only: this share of exploring steps draws from every action instead,
    one never tried in the current state first (any action once all were). Above 0 the
    knowledge never forbids an action: a capability it lacks is found, sooner the larger
    the share, and on accurate knowledge every such step is wasted. 0.1 (one step in a
    hundred) finds the corridor only reality has (``gdq-pddl knowledge``'s ``passage``
    case) in 4 of 10 runs within 3000 episodes, 0.25 in 10 of 10; on tasks A-D they cost
    0.04 and 0.07 return per episode against 0 (``benchmarks/gdq_settings.py``,
    ``docs/decisions.md``). Raise it when the knowledge may lack actions."""
    explore_all_last_step: bool = True
    """``prior`` only: whether the ``explore_all`` share applies also in a state from which
    the knowledge reaches the goal in one action. There an action the knowledge lacks
    cannot shorten the route, only make the last step more reliable, so ``False`` spares
    most of the cost of ``explore_all`` on short tasks: on the 120 office start/goal pairs
    where GDQ loses to DARLING, ``False`` brings GDQ minus DARLING from -0.023 to -0.011
    on average, and the corridor is found about as often (3 of 10 runs within 3000
    episodes, against 4; ``benchmarks/gdq_settings.py``). It
    is not the default because that was measured on those pairs, after every setting had
    been fixed on tasks A-D; the evaluation protocol (``docs/decisions.md``) forbids
    choosing on them."""
    prior_cost: float = 1.0
    """``prior`` only: the step cost the prior charges. The knowledge counts
    actions (the planner ignores costs), so one step costs 1 in its units."""
    sweep_threshold: float = 1e-6
    """``prior`` only: a state-value change smaller than this is not propagated."""
    optimistic_successor: Literal["start", "terminal"] = "start"
    """``literal`` only: where an optimistic (unknown) pair leads. ``"start"``: to s0, as
    Algorithm 1's ``T(s, a, s0) = 1`` (so optimistic values reach R_max / (1 - gamma)).
    ``"terminal"``: nowhere, the optimistic reward ends the episode (values bounded by
    R_max). Not in the paper; offered to show where the excess optimism comes from."""
    plan_tolerance: float | None = None
    """H holds every loop-free plan up to ``(1 + plan_tolerance)`` x the shortest length.
    None means the variant's own setting: 0 for ``"literal"`` (the paper plans "a set of
    the shortest plans"), 0.3 for ``"code"`` (the authors' released planner returned
    plans up to 1.3 x the shortest) and for ``"prior"``, which plans on its prior over
    every pair and uses these plans only to explore. The task context must hold a plan
    table built with that tolerance (its ``darling_plans``)."""

    def __post_init__(self) -> None:
        super().__post_init__()
        if self.variant == "paper":
            raise ConfigError("GDQ variant 'paper' is now called 'literal' (the paper's "
                              "Algorithms 1-3 read literally); the default is 'prior'")
        if self.variant == "model":  # the default's former name
            object.__setattr__(self, "variant", "prior")
        if self.variant not in GDQ_VARIANTS:
            raise ConfigError(f"variant must be one of {', '.join(GDQ_VARIANTS)}, got "
                              f"{self.variant!r}")
        prior = self.variant == "prior"
        for name, default in (("n_backups", 5), ("m", 0 if prior else 5),
                              ("plan_tolerance", 0.0 if self.variant == "literal" else 0.3)):
            if getattr(self, name) is None:
                object.__setattr__(self, name, default)
        check_count("n_backups", self.n_backups, MAX_BACKUPS)
        check_count("m", self.m)
        check_real("plan_tolerance", self.plan_tolerance, 0.0, MAX_TOLERANCE)
        if self.optimistic_successor not in ("start", "terminal"):
            raise ConfigError("optimistic_successor must be 'start' or 'terminal', got "
                              f"{self.optimistic_successor!r}")
        if self.explore not in ("plans", "applicable"):
            raise ConfigError(f"explore must be 'plans' or 'applicable', got {self.explore!r}")
        check_real("explore_all", self.explore_all, 0.0, 1.0)
        if not isinstance(self.explore_all_last_step, bool):
            raise ConfigError("explore_all_last_step must be True or False, got "
                              f"{self.explore_all_last_step!r}")
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
    """``"paper"``: Leonetti et al.'s DARLING as the SPEC states it; the plan actions are
    the only ones it may choose, when exploring and in the max of the update alike.
    ``"code"``: as the GDQ authors' released DARLING agent runs it, a baseline for
    comparing with their published curves, not DARLING as defined: the greedy choice and
    the update's max range over *all* actions (untried ones at 0), and an action that is
    not a plan action (the greedy one, or an epsilon draw) is replaced by a uniformly
    random plan action. See ``docs/learners.md``."""

    def __post_init__(self) -> None:
        super().__post_init__()
        check_real("tolerance", self.tolerance, 0.0, MAX_TOLERANCE)
        if self.variant not in ("paper", "code"):
            raise ConfigError(f"variant must be 'paper' or 'code', got {self.variant!r}")
