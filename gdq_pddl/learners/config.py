"""Hyper-parameters of the learners, one frozen dataclass per method.

Defaults are the paper's simulation settings (alpha 0.1, gamma 0.95, epsilon 0.1) and,
where the paper is silent, the authors' released code (N, m, the 1.3 plan-length
tolerance). ``R_max`` is not a learner parameter: it belongs to the world (its world
file), and every learner reads it from the task context.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Literal

from gdq_pddl.limits import check_count, check_real

GDQVariant = Literal["paper", "code"]
DarlingVariant = Literal["paper", "code"]

MAX_BACKUPS = 1_000_000
"""The most model backups per real step a config accepts (each costs about a
microsecond; the paper's settings are 3-5)."""

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


@dataclass(frozen=True)
class QLearningConfig(LearnerConfig):
    """Q-learning: nothing beyond the shared parameters."""


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


@dataclass(frozen=True)
class GDQConfig(LearnerConfig):
    """Guided Dyna-Q (the paper's Algorithms 1-3)."""

    n_backups: int = 5
    """N: backups per real step, each on a random transition of a random plan from the
    current state (the authors' code used 5)."""
    m: int = 5
    """A pair is *known* once tried more than ``m`` times: from then on its R and T come
    from the learned model, before that from the optimistic model (authors' code: 5)."""
    variant: GDQVariant = "paper"
    """``"paper"``: OptInit runs policy iteration on the optimistic model and backups are
    expected (full) Bellman backups. ``"code"``: as the authors' released code, OptInit
    sets Q to R_max on plan pairs and backups are sample-based TD updates with alpha.
    See :mod:`gdq_pddl.learners.agents` for the side-by-side comparison."""

    optimistic_successor: Literal["start", "terminal"] = "start"
    """Where an optimistic (unknown) pair leads. ``"start"``: to s0, as Algorithm 1's
    ``T(s, a, s0) = 1`` (so optimistic values reach R_max / (1 - gamma)). ``"terminal"``:
    nowhere, the optimistic reward ends the episode (values bounded by R_max). Not in
    the paper; offered to show where the paper variant's excess optimism comes from."""
    plan_tolerance: float | None = None
    """H holds every loop-free plan up to ``(1 + plan_tolerance)`` x the shortest length.
    None means the variant's own setting: 0 for ``"paper"`` (the paper plans "a set of the
    shortest plans") and 0.3 for ``"code"`` (the authors' released planner returned
    plans up to 1.3 x the shortest). The task context must hold a plan table built with
    that tolerance (its ``darling_plans``)."""

    def __post_init__(self) -> None:
        super().__post_init__()
        if self.n_backups < 0 or self.m < 0:
            raise ValueError(f"n_backups and m must be >= 0, got {self.n_backups}, {self.m}")
        if self.optimistic_successor not in ("start", "terminal"):
            raise ValueError("optimistic_successor must be 'start' or 'terminal', got "
                             f"{self.optimistic_successor!r}")
        if self.variant not in ("paper", "code"):
            raise ValueError(f"variant must be 'paper' or 'code', got {self.variant!r}")
        if self.plan_tolerance is None:
            object.__setattr__(self, "plan_tolerance", 0.0 if self.variant == "paper" else 0.3)
        if self.plan_tolerance < 0:
            raise ValueError(f"plan_tolerance must be >= 0, got {self.plan_tolerance}")


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
    random plan action. See :mod:`gdq_pddl.learners.agents`."""

    def __post_init__(self) -> None:
        super().__post_init__()
        check_real("tolerance", self.tolerance, 0.0)
        if self.variant not in ("paper", "code"):
            raise ValueError(f"variant must be 'paper' or 'code', got {self.variant!r}")
