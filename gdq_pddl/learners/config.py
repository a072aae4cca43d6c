"""Hyper-parameters of the learners, one frozen dataclass per method.

Defaults are the paper's simulation settings (alpha 0.1, gamma 0.95, epsilon 0.1) and,
where the paper is silent, the authors' released code (N, m, the 1.3 plan-length
tolerance). ``R_max`` belongs to the task: every learner reads it from the task context.
"""

from __future__ import annotations

import ast
import inspect
import math
import sys
import typing
from dataclasses import dataclass, field, fields
from functools import cache
from typing import Any, Literal

from gdq_pddl.errors import ConfigError
from gdq_pddl.limits import MAX_COUNT, MAX_NUMBER, MAX_TOLERANCE, check_count, check_real

EXPLORE_ALL = 0.1
"""The default GDQ's ``explore_all`` where the knowledge may differ from reality."""

GDQVariant = Literal["prior", "literal", "code"]
GDQ_VARIANTS: tuple[str, ...] = ("prior", "literal", "code")
"""``prior``, the default GDQ; ``literal`` and ``code``, the paper's two readings."""
DarlingVariant = Literal["paper", "code"]

MAX_BACKUPS = 1_000_000
"""The most model backups per real step a config accepts (the paper's settings are 3-5)."""


def check_choice(name: str, value: object, choices: tuple) -> None:
    """ConfigError unless ``value`` is one of ``choices`` (of its type: 1 is not True)."""
    if not any(isinstance(value, type(c)) and value == c for c in choices):
        raise ConfigError(f"{name} must be one of {', '.join(map(repr, choices))}, got "
                          f"{value!r}")


@dataclass(frozen=True)
class Range:
    """The values a number setting may take (a field's ``metadata["range"]``): from ``low``
    to ``high``, open at the ends ``low_open`` / ``high_open`` say."""

    low: float
    high: float = math.inf
    low_open: bool = False
    high_open: bool = False

    def __str__(self) -> str:
        if math.isinf(self.high):
            return f"{'>' if self.low_open else '>='} {self.low:g}"
        high = f"{self.high:_}" if isinstance(self.high, int) else f"{self.high:g}"
        return f"{'(' if self.low_open else '['}{self.low:g}, {high}" \
            f"{')' if self.high_open else ']'}"

    def check(self, name: str, value: object, whole: bool) -> None:
        """ConfigError unless ``value`` is in the range (a whole number if ``whole``)."""
        if whole:
            check_count(name, value, int(self.high))
            if value < self.low:  # type: ignore[operator]  # a count from 1 (deep agents)
                raise ConfigError(f"{name} must be a whole number in {self}, got {value!r}")
        else:
            check_real(name, value, self.low, self.high, self.low_open, self.high_open)


def real(default: float | None, low: float, high: float = math.inf, *, low_open: bool = False,
         high_open: bool = False) -> Any:
    """A number setting with its range (checked by :meth:`LearnerConfig.__post_init__`)."""
    return field(default=default, metadata={"range": Range(low, high, low_open, high_open)})


def count(default: int | None, high: int = MAX_COUNT, low: int = 0) -> Any:
    """A whole-number setting in ``[low, high]``."""
    return field(default=default, metadata={"range": Range(low, high)})


def field_range(cls: type, name: str) -> Range | None:
    """The range of the setting ``name`` of the config class ``cls`` (None: not a number)."""
    return next((f.metadata.get("range") for f in fields(cls) if f.name == name), None)


def check_fields(config: object) -> None:
    """Check every field of a config dataclass against its type (a ``Literal``'s choices,
    a bool) and its :class:`Range`; None passes where the type allows it."""
    hints = typing.get_type_hints(type(config))
    for f in fields(config):  # type: ignore[arg-type]
        value, tp = getattr(config, f.name), hints[f.name]
        args = typing.get_args(tp)
        if value is None and type(None) in args:
            continue
        kinds = [a for a in args if a is not type(None)] if type(None) in args else [tp]
        kind = kinds[0]
        if typing.get_origin(kind) is Literal:
            check_choice(f.name, value, typing.get_args(kind))
        elif kind is bool:
            check_choice(f.name, value, (True, False))
        elif (span := f.metadata.get("range")) is not None:
            span.check(f.name, value, kind is int)


@cache
def _module_docs(module: str) -> dict[tuple[str, str], str]:
    """``{(class, field): docstring}`` of a module's source ({} if it has none)."""
    try:
        tree = ast.parse(inspect.getsource(sys.modules[module]))
    except (OSError, TypeError, KeyError):
        return {}
    return {(c.name, f.target.id): inspect.cleandoc(d.value.value)
            for c in tree.body if isinstance(c, ast.ClassDef)
            for f, d in zip(c.body, c.body[1:], strict=False)
            if isinstance(f, ast.AnnAssign) and isinstance(f.target, ast.Name)
            and isinstance(d, ast.Expr) and isinstance(d.value, ast.Constant)}


def field_doc(cls: type, name: str) -> str:
    """The docstring under the field ``name`` of ``cls`` or of a base class ("" if none)."""
    for base in cls.__mro__:
        if doc := _module_docs(base.__module__).get((base.__name__, name)):
            return doc
    return ""


def documented(cls: type) -> type:
    """Append each field's docstring (which ``help()`` does not show) to the class
    docstring, as an ``Attributes`` list."""
    docs = {f.name: doc for f in fields(cls) if (doc := field_doc(cls, f.name))}
    items = "\n".join(f"    {name}: " + doc.replace("\n", "\n        ")
                      for name, doc in docs.items())
    cls.__doc__ = f"{inspect.cleandoc(cls.__doc__ or '')}\n\nAttributes:\n{items}"
    return cls


@documented
@dataclass(frozen=True)
class LearnerConfig:
    """Parameters shared by every tabular learner."""

    alpha: float = real(0.1, 0.0, 1.0, low_open=True)
    """Step size of the temporal-difference update (real experience, and the sample-based
    model backups of GDQ's ``code`` variant)."""
    gamma: float = real(0.95, 0.0, 1.0, high_open=True)
    """Discount factor, used in every update and in OptInit's policy iteration."""
    epsilon: float = real(0.1, 0.0, 1.0)
    """Probability of a uniformly random (allowed) action instead of the greedy one."""

    def __post_init__(self) -> None:
        self._resolve()
        check_fields(self)

    def _resolve(self) -> None:
        """Fill in the defaults that depend on other fields (before the checks)."""


@documented
@dataclass(frozen=True)
class QLearningConfig(LearnerConfig):
    """Q-learning: nothing beyond the shared parameters."""


@documented
@dataclass(frozen=True)
class DynaQConfig(LearnerConfig):
    """Dyna-Q: Q-learning plus ``n_backups`` model backups per real step."""

    n_backups: int = count(3, MAX_BACKUPS)
    """N: model backups per real step, each on a uniformly random previously observed
    (state, action) pair (the authors' code used 3 for Dyna-Q)."""
    m: int = count(0)
    """A pair is used for backups once it has been tried more than ``m`` times (0, "tried
    at least once", is classic Dyna-Q; a larger m only delays planning)."""


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
    n_backups: int | None = count(None, MAX_BACKUPS)
    """N: simulated backups per real step (default 5). ``prior``: prioritised sweeping
    recomputes pair values until at least N are done, finishing every state it takes
    from the queue; ``literal`` and ``code``: backups of a random transition of a random
    plan from the current state (the authors' code)."""
    m: int | None = count(None)
    """A knowledge-applicable pair is *known* once tried more than ``m`` times: from then
    on its model is learned, before that the optimistic one. Default 0 for ``prior``
    (where a pair the knowledge says does nothing is known after its first trial
    whatever ``m``), 5 for the others (the authors' code)."""
    prior_weight: float = real(1.0, 0.0, MAX_NUMBER)
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
    explore_all: float | None = real(None, 0.0, 1.0)
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
    prior_cost: float = real(1.0, 0.0, MAX_NUMBER)
    """``prior`` only: the step cost the prior charges (the planner counts actions). On
    a problem's own reward scale at most ``r_max / step_limit``, so that no plan within
    the step limit is worth less to the prior than doing nothing, and charged besides
    the file's rewards (``TaskContext.prior_reward``; ``docs/decisions.md``)."""
    sweep_threshold: float = real(1e-6, 0.0, MAX_NUMBER)
    """``prior`` only: a state-value change smaller than this is not propagated."""
    optimistic_successor: Literal["start", "terminal"] = "start"
    """``literal`` only: where an optimistic (unknown) pair leads. ``"start"``: to s0, as
    Algorithm 1's ``T(s, a, s0) = 1``. ``"terminal"`` (not in the paper): the optimistic
    reward ends the episode, which shows where the excess optimism comes from."""
    plan_tolerance: float | None = real(None, 0.0, MAX_TOLERANCE)
    """H holds every loop-free plan up to ``(1 + plan_tolerance)`` x the shortest length.
    None: 0 for ``"literal"`` (the paper's "shortest plans"), 0.3 for ``"code"`` (the
    authors' planner) and ``"prior"`` (which uses them only to explore). The task context
    must hold a plan table built with that tolerance (its ``darling_plans``)."""

    def _resolve(self) -> None:
        check_choice("variant", self.variant, GDQ_VARIANTS)
        prior = self.variant == "prior"
        for name, default in (("n_backups", 5), ("m", 0 if prior else 5),
                              ("plan_tolerance", 0.0 if self.variant == "literal" else 0.3)):
            if getattr(self, name) is None:
                object.__setattr__(self, name, default)


@documented
@dataclass(frozen=True)
class DarlingConfig(LearnerConfig):
    """DARLING (Leonetti, Iocchi & Stone 2016): Q-learning over plan-restricted actions."""

    tolerance: float = real(0.3, 0.0, MAX_TOLERANCE)
    """Plans up to (1 + tolerance) x the shortest length define the allowed actions;
    the task context's DARLING plan table must have been built with this tolerance."""
    variant: DarlingVariant = "paper"
    """``"paper"``: Leonetti et al.'s DARLING; the plan actions are the only ones it may
    choose, when exploring and in the max of the update alike. ``"code"``: as the GDQ
    authors' released agent runs it (``docs/learners.md``): the greedy choice and the
    max range over *all* actions, and a non-plan action is replaced by a random plan
    action."""


@documented
@dataclass(frozen=True)
class ShapingConfig(LearnerConfig):
    """Q-learning shaped by the knowledge's goal distance (:mod:`gdq_pddl.learners.shaping`);
    the default scale was chosen on tasks A-D (``docs/decisions.md``)."""

    scale: float = real(2.0, 0.0, MAX_NUMBER)
    """What the potential is multiplied by: ``phi = -scale * d(s)``; 0 is Q-learning."""


@documented
@dataclass(frozen=True)
class PlanShapingConfig(LearnerConfig):
    """Q-learning shaped by the plan step (Grzes and Kudenko 2008)."""

    scale: float = real(1.0, 0.0, MAX_NUMBER)
    """What the potential is multiplied by: ``phi = scale * (R_max / L) * step(s)`` (1:
    Grzes and Kudenko's ``w = R_max / L``); 0 is Q-learning."""


@documented
@dataclass(frozen=True)
class DynaQShapingConfig(DynaQConfig):
    """Dyna-Q shaped by the distance potential, in real and simulated backups."""

    scale: float = real(1.0, 0.0, MAX_NUMBER)
    """What the potential is multiplied by: ``phi = -scale * d(s)``; 0 is Dyna-Q."""


@documented
@dataclass(frozen=True)
class RMaxConfig(LearnerConfig):
    """R-max (Brafman and Tennenholtz 2002): ``epsilon`` is 0 (its name fixes it)."""

    epsilon: float = real(0.0, 0.0, 1.0)
    """Probability of a uniformly random action; 0 (the method's name fixes it)."""

    m: int = count(1, low=1)
    """A pair is known once tried ``m`` times (at least 1): from then on the learned
    model values it, before that ``V_max`` (R-max) or the potential (R-max-shaping).
    Default 1, chosen on tasks A-D (``docs/decisions.md``)."""
    tolerance: float = real(1e-6, 0.0, MAX_NUMBER, low_open=True)
    """Value iteration stops when no value changes by more than this."""
    max_sweeps: int = count(1000, low=1)
    """Value iteration stops after this many sweeps (at least 1) in any case."""


@documented
@dataclass(frozen=True)
class RMaxShapingConfig(RMaxConfig):
    """R-max with unknown pairs valued by a potential (Asmuth, Littman and Zinkov 2008)."""

    scale: float = real(2.0, 0.0, MAX_NUMBER)
    """``Phi(s) = V_max - scale * max(0, d(s) - 1)``; 0 is R-max. Default 2, chosen on
    tasks A-D (``docs/decisions.md``)."""


@documented
@dataclass(frozen=True)
class FFReplanConfig(LearnerConfig):
    """FF-Replan (Yoon, Fern and Givan 2007): ``alpha`` and ``gamma`` are not used,
    ``epsilon`` is 0 (its name fixes it)."""

    epsilon: float = real(0.0, 0.0, 1.0)
    """Probability of a uniformly random action; 0 (the method's name fixes it)."""

    determinisation: Literal["all-outcomes", "most-likely"] = "all-outcomes"
    """How a PPDDL problem's probabilistic actions are made deterministic for the
    planner: ``all-outcomes`` (the paper's), or ``most-likely``; it must be the
    problem's (``--determinisation``)."""


# -- deep-RL agents (gdq_pddl.learners.deep; the sb3 extra) -------------------------

SB3_EXTRA = "sb3"
"""The extra that installs the agents' libraries."""
SB3_MODULES = ("stable_baselines3", "sb3_contrib", "torch")
"""What the agents import (all in the ``sb3`` extra)."""

Shaping = Literal["none", "distance", "plan-step"]
Observation = Literal["state", "facts", "distance"]

MAX_HIDDEN = 4096
"""The most units a hidden layer may have."""
PACKAGE_FIELDS = ("hidden", "steps", "shaping", "scale", "obs", "exploration_steps")
"""The deep settings the package reads itself; every other field is an agent's keyword."""


@documented
@dataclass(frozen=True)
class DeepConfig:
    """Settings every deep-RL agent shares (the network, the knowledge, the budget)."""

    gamma: float = real(0.95, 0.0, 1.0, high_open=True)
    """Discount factor (the experiment's gamma unless set), also the shaping's gamma."""
    learning_rate: float = real(3e-4, 0.0, 1.0, low_open=True)
    """The optimiser's step size (Stable-Baselines3's default for PPO)."""
    hidden: int = count(64, MAX_HIDDEN, low=1)
    """Units in each of the two hidden layers of the policy and value networks."""
    steps: int | None = count(None, 10**12)
    """The most training steps per task; none: as many as the task's episodes need. The
    episodes left when it is reached are played by the trained policy (greedy, no
    learning), one row each, so every run has the experiment's number of rows."""
    shaping: Shaping = "none"
    """The reward the agent learns from: the env's (``none``), or shaped by the knowledge's
    goal distance (``distance``, phi = -scale d(s)) or plan step (``plan-step``):
    ``gdq_pddl.wrappers.KnowledgeShaping``. The rows' returns are always unshaped."""
    scale: float = real(1.0, 0.0, MAX_NUMBER, low_open=True)
    """What the shaping potential is multiplied by."""
    obs: Observation = "state"
    """What the agent sees: the learner state's index (``state``, one-hot in the network),
    the true facts of the state (``facts``, ``gdq_pddl.wrappers.FactObservation``), or
    the state with the knowledge's goal distance and plan action (``distance``,
    ``gdq_pddl.wrappers.DistanceObservation``)."""

    def __post_init__(self) -> None:
        check_fields(self)

    def agent_kwargs(self) -> dict[str, Any]:
        """The agent's own keyword arguments (besides the policy, env and seed): every
        field but :data:`PACKAGE_FIELDS`."""
        return {f.name: getattr(self, f.name) for f in fields(self)
                if f.name not in PACKAGE_FIELDS}


@documented
@dataclass(frozen=True)
class PPOConfig(DeepConfig):
    """PPO and MaskablePPO: Stable-Baselines3's defaults but for the discount."""

    n_steps: int = count(2048, 10_000_000, low=1)
    """Steps collected between two updates."""
    batch_size: int = count(64, 10_000_000, low=1)
    """Minibatch size of an update."""
    n_epochs: int = count(10, 1000, low=1)
    """Passes over the collected steps in each update."""
    ent_coef: float = real(0.0, 0.0, 1.0)
    """Weight of the entropy bonus."""


@documented
@dataclass(frozen=True)
class DQNConfig(DeepConfig):
    """DQN: Stable-Baselines3's defaults but for the discount, the replay buffer and the
    exploration schedule, which is counted in steps here (SB3 counts it as a share of the
    training budget)."""

    learning_rate: float = real(1e-4, 0.0, 1.0, low_open=True)
    """The optimiser's step size (Stable-Baselines3's default for DQN)."""
    buffer_size: int = count(100_000, 10_000_000, low=1)
    """Transitions the replay buffer holds."""
    learning_starts: int = count(100)
    """Steps before the first update."""
    train_freq: int = count(4, 1_000_000, low=1)
    """Steps between two updates."""
    target_update_interval: int = count(10_000, 10**9, low=1)
    """Steps between two copies of the network to the target network."""
    exploration_steps: int = count(10_000)
    """Steps over which epsilon falls linearly from ``exploration_initial_eps`` to
    ``exploration_final_eps``."""
    exploration_initial_eps: float = real(1.0, 0.0, 1.0)
    """Epsilon at the first step."""
    exploration_final_eps: float = real(0.05, 0.0, 1.0)
    """Epsilon after ``exploration_steps`` steps."""
