"""Every learner, declared once: :data:`BUILT_IN` and :data:`DEEP` here, others through the
entry-point group ``gdq_pddl.learners`` of their own package (:data:`GROUP`).

A :class:`LearnerEntry` says everything the rest of the package needs of a learner: its
name and aliases, its config class and the settings its name stands for, the knowledge it
reads, whether it runs on a problem explored online, its colour and place in figures, a
one-line description, and where its class is (``"module:Class"``, imported when first
used). The lists of methods the commands, the protocol, the results and the figures use
are read from here (the paper's report sections still name the methods they write
about).

A *method* is a learner's name, optionally with settings: ``GDQ:explore_all=0.5,
prior_weight=2`` (:func:`parse_method`), checked against the config class's fields.
"""

from __future__ import annotations

import importlib
import importlib.util
import sys
import types
import typing
from collections.abc import Mapping
from dataclasses import dataclass, field, fields
from functools import cache
from importlib.metadata import entry_points
from typing import Any, Literal

from gdq_pddl.errors import ConfigError
from gdq_pddl.learners.config import (
    SB3_EXTRA,
    SB3_MODULES,
    DarlingConfig,
    DQNConfig,
    DynaQConfig,
    DynaQShapingConfig,
    FFReplanConfig,
    GDQConfig,
    LearnerConfig,
    PlanShapingConfig,
    PPOConfig,
    QLearningConfig,
    RMaxConfig,
    RMaxShapingConfig,
    ShapingConfig,
    field_doc,
    field_range,
)

GROUP = "gdq_pddl.learners"
"""The entry-point group of learners from other packages: ``NAME = "module:ENTRY"``, where
``ENTRY`` is a :class:`LearnerEntry` whose ``name`` is ``NAME``."""

Knowledge = Literal["plans", "prior", "none"]

DEFAULT_COLOUR = "#999999"


@dataclass(frozen=True)
class LearnerEntry:
    """One learner, as the registry declares it."""

    name: str
    """The method name (``--method``, results, figures); any case is accepted on input."""
    learner: str | type
    """Its class, a :class:`~gdq_pddl.learners.tabular.TabularLearner` subclass, or
    ``"module:Class"`` (imported when first used: no compilation before then)."""
    config: type[LearnerConfig]
    """The frozen dataclass of its settings (``--method NAME:key=value`` sets them)."""
    description: str
    """One line: what it does (``gdq-pddl methods``)."""
    knowledge: Knowledge = "none"
    """What it reads of the planner's knowledge: the plans, the prior model, or none."""
    fixed: Mapping[str, Any] = field(default_factory=dict)
    """The settings its name stands for (``GDQ-code``: ``variant="code"``)."""
    aliases: tuple[str, ...] = ()
    """Other names it answers to (compared as names are: any case, no ``-`` or ``_``)."""
    online: bool = True
    """Whether it can run on a problem explored online (states found as episodes reach
    them, ``gdq-pddl run --explore online``)."""
    colour: str = DEFAULT_COLOUR
    """Its colour in every figure."""
    dashes: tuple[float, ...] = ()
    """Its curves' dash pattern (on, off, ... in points; empty: solid), which tells a
    variant from the learner it reads like where colours alone are close."""
    family: str = ""
    """The learner it is a variant of (``GDQ`` for ``GDQ-code``); itself when empty."""
    label: str = ""
    """How prose names it where its name alone would be unclear (the report's verdicts)."""
    groups: frozenset[str] = frozenset()
    """The lists it is in: ``paper`` (the paper's four methods), ``default`` (what the
    commands compare unless told otherwise), ``reproduce`` (what ``gdq-pddl reproduce``
    runs on the tasks and switches), ``robot`` (the robot protocol)."""
    extra: str = ""
    """The extra of ``gdq_pddl`` that installs what it needs (``sb3``), if any."""
    requires: tuple[str, ...] = ()
    """The modules it imports that the default install lacks (installed by :attr:`extra`);
    without one of them its name is listed as needing the extra and refused
    (:func:`missing`)."""

    @property
    def base(self) -> str:
        """:attr:`family`, or the name itself."""
        return self.family or self.name

    def learner_class(self) -> type:
        """The learner class (imported now if it was given as ``"module:Class"``)."""
        if not isinstance(self.learner, str):
            return self.learner
        module, _, attr = self.learner.partition(":")
        return getattr(importlib.import_module(module), attr)


BUILT_IN: tuple[LearnerEntry, ...] = (
    LearnerEntry("GDQ", "gdq_pddl.learners.gdq_learner:GDQ", GDQConfig,
                 "Guided Dyna-Q: the knowledge as an optimistic prior model, prioritised "
                 "sweeping", "prior", colour="#D55E00",  # vermillion
                 label="GDQ, knowledge as a prior model",
                 groups=frozenset({"paper", "default", "reproduce", "robot"})),
    LearnerEntry("GDQ-literal", "gdq_pddl.learners.gdq_learner:PaperGDQ", GDQConfig,
                 "the paper's GDQ read literally: optimistic plan model, backups along "
                 "plans", "plans", {"variant": "literal"}, colour="#E69F00",  # orange
                 label="paper's GDQ read literally", dashes=(5, 2),
                 family="GDQ", groups=frozenset({"reproduce", "robot"})),
    LearnerEntry("GDQ-code", "gdq_pddl.learners.gdq_learner:PaperGDQ", GDQConfig,
                 "the paper's GDQ as the authors' code runs it: optimistic initial Q, "
                 "sampled backups along plans", "plans", {"variant": "code"},
                 colour="#CC79A7", label="authors'-code GDQ", dashes=(1, 1.5),  # purple
                 family="GDQ", groups=frozenset({"default", "reproduce", "robot"})),
    LearnerEntry("DARLING", "gdq_pddl.learners.agents:Darling", DarlingConfig,
                 "Q-learning restricted to the actions that start a plan within the "
                 "length tolerance", "plans", colour="#009E73",  # bluish green
                 groups=frozenset({"paper", "default", "reproduce"})),
    LearnerEntry("DARLING-code", "gdq_pddl.learners.agents:Darling", DarlingConfig,
                 "DARLING as the GDQ authors' agent runs it: non-plan actions replaced by "
                 "random plan actions", "plans", {"variant": "code"},
                 colour="#56B4E9", family="DARLING", dashes=(5, 2)),  # sky blue
    LearnerEntry("Dyna-Q", "gdq_pddl.learners.agents:DynaQ", DynaQConfig,
                 "Q-learning plus a learned model and N backups of random known pairs per "
                 "step", colour="#0072B2",  # blue
                 groups=frozenset({"paper", "default", "reproduce", "robot"})),
    LearnerEntry("Q-learning", "gdq_pddl.learners.agents:QLearning", QLearningConfig,
                 "epsilon-greedy Q-learning: the TD update on each real step",
                 colour="#000000",  # black
                 groups=frozenset({"paper", "default", "reproduce"})),
    LearnerEntry("Q-shaping", "gdq_pddl.learners.shaping:QShaping", ShapingConfig,
                 "Q-learning shaped by the knowledge's goal distance, phi = -scale d(s) "
                 "(Ng et al. 1999)", "plans", colour="#7f7f7f",  # grey
                 label="Q-learning shaped by the goal distance"),
    LearnerEntry("Dyna-Q-shaping", "gdq_pddl.learners.shaping:DynaQShaping",
                 DynaQShapingConfig,
                 "Dyna-Q shaped by the knowledge's goal distance in real and simulated "
                 "backups", "plans", colour="#6a3d9a",  # purple
                 label="Dyna-Q shaped by the goal distance"),
    LearnerEntry("Plan-shaping", "gdq_pddl.learners.shaping:PlanShaping", PlanShapingConfig,
                 "Q-learning shaped by the plan step reached, phi = R_max / L step(s) "
                 "(Grzes and Kudenko 2008)", "plans", colour="#b15928",  # brown
                 label="Q-learning shaped by the plan step"),
    LearnerEntry("R-max", "gdq_pddl.learners.rmax:RMax", RMaxConfig,
                 "R-max: unknown pairs worth V_max, value iteration on the known model "
                 "(Brafman and Tennenholtz 2002)", fixed={"epsilon": 0.0},
                 aliases=("Rmax",), colour="#1f78b4"),  # dark blue
    LearnerEntry("R-max-shaping", "gdq_pddl.learners.rmax:RMaxShaping", RMaxShapingConfig,
                 "R-max with unknown pairs worth a potential of the goal distance (Asmuth "
                 "et al. 2008)", "plans", fixed={"epsilon": 0.0}, colour="#33a02c",  # green
                 label="R-max shaped by the goal distance"),
    LearnerEntry("FF-Replan", "gdq_pddl.learners.replan:FFReplan", FFReplanConfig,
                 "no learning: a shortest plan of the determinised knowledge, replanned "
                 "when an outcome leaves it (Yoon et al. 2007)", "plans",
                 fixed={"epsilon": 0.0}, colour="#fb9a99",  # pink
                 label="FF-Replan (the knowledge alone)"),
)
"""The package's own learners, in the order of every figure and table."""

DEEP: tuple[LearnerEntry, ...] = tuple(
    LearnerEntry(name, f"gdq_pddl.learners.deep:{name}", config, description, online=False,
                 colour=colour, extra=SB3_EXTRA, requires=SB3_MODULES)
    for name, config, description, colour in (
        ("MaskablePPO", PPOConfig, "deep RL: sb3-contrib's MaskablePPO, drawing only the "
         "env's allowed actions", "#a6cee3"),
        ("PPO", PPOConfig, "deep RL: Stable-Baselines3's PPO, every action open", "#fdbf6f"),
        ("DQN", DQNConfig, "deep RL: Stable-Baselines3's DQN, every action open", "#cab2d6")))
"""Deep-RL agents of Stable-Baselines3 and sb3-contrib (:mod:`gdq_pddl.learners.deep`; the
``sb3`` extra): after the built-in learners in every list, figure and table, and in none of
the built-in groups (:func:`built_in_names`: what the protocol and the scale experiments
run by default)."""

REFERENCE = BUILT_IN[0].name
"""The method every other one is compared with (the library's GDQ)."""

_EXTRA = ("#F0E442", "#999999", "#8c564b", "#9467bd", "#17becf")
"""Colours of methods without one of their own (picked by the method's text)."""


def key_of(name: str) -> str:
    """What names are compared by: any case, without ``-``, ``_`` and spaces."""
    return name.lower().replace("-", "").replace("_", "").replace(" ", "")


def names(group: str | None = None) -> tuple[str, ...]:
    """Every learner's name (built-in first, in figure order; then plugins by name), or those
    in ``group`` (:attr:`LearnerEntry.groups`)."""
    return tuple(e.name for e in entries() if group is None or group in e.groups)


def built_in_names(group: str | None = None) -> tuple[str, ...]:
    """The built-in learners' names (or those in ``group``), without loading plugins."""
    return tuple(e.name for e in BUILT_IN if group is None or group in e.groups)


def variants_of(name: str) -> tuple[str, ...]:
    """The built-in learners of the family of the built-in ``name``: it and its variants."""
    base = next(e.base for e in BUILT_IN if e.name == name)
    return tuple(e.name for e in BUILT_IN if e.base == base)


@cache
def entries() -> tuple[LearnerEntry, ...]:
    """Every learner: :data:`BUILT_IN`, :data:`DEEP`, then those of the ``gdq_pddl.learners``
    entry points by name (a plugin that cannot be loaded, or repeats a name, is left out:
    :func:`plugin_problems` says why)."""
    return BUILT_IN + DEEP + tuple(e for e, _ in _plugins() if e is not None)


def refresh() -> None:
    """Read the entry points again (a package installed or removed while running)."""
    for cached in (entries, _plugins, _by_key):
        cached.cache_clear()


def plugin_problems() -> list[str]:
    """Why each plugin that is left out is left out, one line each."""
    return [why for e, why in _plugins() if e is None]


@cache
def _plugins() -> tuple[tuple[LearnerEntry | None, str], ...]:
    taken = {key_of(n) for e in BUILT_IN + DEEP for n in (e.name, *e.aliases)}
    out = []
    for ep in sorted(entry_points(group=GROUP), key=lambda ep: ep.name):
        try:
            entry = ep.load()
            if not isinstance(entry, LearnerEntry):
                raise TypeError(f"{ep.value} is a {type(entry).__name__}, not a "
                                "gdq_pddl.learners.registry.LearnerEntry")
            if key_of(entry.name) != key_of(ep.name):
                raise ValueError(f"its entry point is {ep.name!r} and its name {entry.name!r}")
            clash = [n for n in (entry.name, *entry.aliases) if key_of(n) in taken]
            if clash:
                raise ValueError(f"the name {clash[0]!r} is already taken")
        except Exception as exc:  # a broken plugin must not break every command
            out.append((None, f"learner plugin {ep.name!r} ({ep.value}) is left out: "
                              f"{type(exc).__name__}: {exc}"))
            continue
        taken.update(key_of(n) for n in (entry.name, *entry.aliases))
        out.append((entry, ""))
    return tuple(out)


@cache
def _by_key() -> dict[str, LearnerEntry]:
    return {key_of(n): e for e in entries() for n in (e.name, *e.aliases)}


def missing(found: LearnerEntry) -> str:
    """``needs `pip install 'gdq_pddl[EXTRA]'``` when a module ``found`` requires cannot be
    imported here; "" when it can run (nothing is imported to tell)."""
    for module in found.requires:
        try:
            absent = sys.modules.get(module, ...) is None or \
                importlib.util.find_spec(module) is None
        except (ImportError, ValueError):
            absent = True
        if absent:
            return f"needs `pip install 'gdq_pddl[{found.extra}]'`"
    return ""


def check_installed(found: LearnerEntry, text: str) -> None:
    """A :class:`~gdq_pddl.errors.ConfigError` when ``found`` cannot run here
    (:func:`missing`): ``method 'PPO' needs `pip install 'gdq_pddl[sb3]'```."""
    if need := missing(found):
        raise ConfigError(f"method {text!r} {need}")


def entry(name: str) -> LearnerEntry:
    """The learner named ``name`` (any case, with or without ``-`` and ``_``; an alias), or
    a :class:`~gdq_pddl.errors.ConfigError` listing the known names."""
    found = _by_key().get(key_of(name)) if isinstance(name, str) else None
    if found is None:
        raise ConfigError(f"unknown method {name!r} (known: {', '.join(names())})")
    return found


# -- methods: a name plus settings ------------------------------------------------------


@dataclass(frozen=True)
class Method:
    """A parsed ``--method``: a learner and the settings given with it."""

    text: str
    """The method as results name it: the learner's name, then ``:key=value,...`` as
    given (keys in the given order, values as typed, spaces removed)."""
    entry: LearnerEntry
    settings: Mapping[str, Any]
    """The settings given, parsed to their fields' types."""

    def config_kwargs(self, defaults: Mapping[str, Any] | None = None) -> dict[str, Any]:
        """The config's keyword arguments: ``defaults`` (of the fields the config has),
        then the settings the name stands for, then the given settings."""
        known = {f.name for f in fields(self.entry.config)}
        out = {k: v for k, v in (defaults or {}).items() if k in known}
        return out | dict(self.entry.fixed) | dict(self.settings)


def parse_method(text: str) -> Method:
    """``NAME`` or ``NAME:key=value,key=value`` checked against the learner's config class
    (each key a field, each value of its type and in its range); a
    :class:`~gdq_pddl.errors.ConfigError` naming the field, its type and its range."""
    if not isinstance(text, str):
        raise ConfigError(f"a method is a name (with :key=value settings), got {text!r}")
    name, sep, rest = text.partition(":")
    found = entry(name.strip())
    settings: dict[str, Any] = {}
    parts: list[str] = []
    if sep:
        specs = {f.name: f for f in fields(found.config)}
        for item in rest.split(","):
            key, eq, value = (x.strip() for x in item.partition("="))
            if not eq or not key or not value:
                raise ConfigError(f"method {text!r}: {item.strip()!r} is not key=value "
                                  f"(settings of {found.name}: {', '.join(specs)})")
            if key not in specs:
                raise ConfigError(f"method {text!r}: {found.name} has no setting {key!r} "
                                  f"(its settings: {', '.join(specs)})")
            if key in settings:
                raise ConfigError(f"method {text!r}: {key} is given twice")
            if key in found.fixed:
                raise ConfigError(f"method {text!r}: {found.name} is {key}="
                                  f"{found.fixed[key]}; another {key} is another method")
            settings[key] = _parse_value(text, found, key, value)
            parts.append(f"{key}={value}")
        _check(text, found, settings)
    canonical = found.name + (":" + ",".join(parts) if parts else "")
    return Method(canonical, found, settings)


def canonical(text: str) -> str:
    """The method as results name it (:attr:`Method.text`), checked (and refused where
    its learner needs an extra that is not installed: :func:`check_installed`)."""
    parsed = parse_method(text)
    check_installed(parsed.entry, text)
    return parsed.text


def _field_type(config: type, key: str) -> Any:
    return typing.get_type_hints(config)[key]


def type_text(config: type, key: str) -> str:
    """A field's type in words: ``a number``, ``a whole number``, ``true or false``,
    ``one of a, b``, ``... or none``."""
    return _describe(_field_type(config, key))


def _describe(tp: Any) -> str:
    args = typing.get_args(tp)
    if typing.get_origin(tp) in (types.UnionType, typing.Union):
        kinds = [_describe(a) for a in args if a is not type(None)]
        return " or ".join(kinds) + (" or none" if type(None) in args else "")
    if typing.get_origin(tp) is Literal:
        return "one of " + ", ".join(map(str, args))
    return {bool: "true or false", int: "a whole number", float: "a number"}.get(tp, str(tp))


def _convert(tp: Any, value: str) -> Any:
    """``value`` as a ``tp``; ValueError if it is not one."""
    args = typing.get_args(tp)
    if typing.get_origin(tp) in (types.UnionType, typing.Union):
        if type(None) in args and value.lower() == "none":
            return None
        for a in args:
            if a is not type(None):
                try:
                    return _convert(a, value)
                except ValueError:
                    pass
        raise ValueError(value)
    if typing.get_origin(tp) is Literal:
        for a in args:
            if str(a) == value:
                return a
        raise ValueError(value)
    if tp is bool:
        words = {"true": True, "false": False, "yes": True, "no": False, "1": True,
                 "0": False}
        if value.lower() not in words:
            raise ValueError(value)
        return words[value.lower()]
    if tp is int:
        return int(value)
    if tp is float:
        return float(value)
    raise ValueError(value)


def describe_field(config: type, key: str) -> str:
    """``key must be a <type> in <range>``: how errors name a setting."""
    span = field_range(config, key)
    return f"{key} must be {type_text(config, key)}{f' in {span}' if span else ''}"


def _parse_value(text: str, found: LearnerEntry, key: str, value: str) -> Any:
    try:
        return _convert(_field_type(found.config, key), value)
    except ValueError:
        raise ConfigError(f"method {text!r}: {describe_field(found.config, key)}, got "
                          f"{value!r}") from None


def _check(text: str, found: LearnerEntry, settings: Mapping[str, Any]) -> None:
    """Each setting alone in its config (so an error names its field), then all together."""
    for key, value in settings.items():
        try:
            found.config(**(dict(found.fixed) | {key: value}))
        except ConfigError:
            raise ConfigError(f"method {text!r}: {describe_field(found.config, key)}, got "
                              f"{value!r}") from None
    try:
        found.config(**(dict(found.fixed) | dict(settings)))
    except ConfigError as exc:
        raise ConfigError(f"method {text!r}: {exc}") from None


def make_learner(method: str, context: Any, defaults: Mapping[str, Any] | None = None,
                 **config: Any) -> Any:
    """A fresh learner of ``method`` for ``context``: ``make_learner("GDQ-code", ctx,
    alpha=0.2)``, ``make_learner("gdq:explore_all=0.5", ctx)``. The name in any case, with
    or without ``-`` and ``_``; ``config``: settings besides those of the method (one that
    contradicts them is refused); ``defaults``: settings the method may override (an
    experiment's alpha, gamma and epsilon)."""
    parsed = parse_method(method)
    check_installed(parsed.entry, method)
    given = {**parsed.entry.fixed, **parsed.settings}
    for key, value in config.items():
        if key in given and given[key] != value:
            raise ConfigError(f"method {method!r} sets {key}={given[key]!r}, and the "
                              f"overrides say {key}={value!r}")
    try:
        settings = parsed.entry.config(**(parsed.config_kwargs(defaults) | config))
    except TypeError as e:
        raise ConfigError(f"{method}: {e}".replace("__init__() ", "")) from None
    return parsed.entry.learner_class()(context, settings)


def learner_class(method: str) -> type:
    """The class of the learner of ``method`` (what it reads of a problem explored online:
    ``reads_knowledge``, ``estimate_weight``)."""
    return parse_method(method).entry.learner_class()


def _parsed(method: str) -> Method | None:
    """``method`` parsed (:func:`parse_method`), or None where no learner has it."""
    try:
        return parse_method(method)
    except ConfigError:
        return None


def colour(method: str) -> str:
    """The colour of ``method`` in every figure: its learner's for a bare name, a stable
    extra colour for a method with settings or a name no learner has."""
    parsed = _parsed(method)
    if parsed is not None and not parsed.settings:
        return parsed.entry.colour
    return _EXTRA[sum(map(ord, method)) % len(_EXTRA)]


def dashes(method: str) -> tuple[float, ...]:
    """The dash pattern of ``method``'s curves: its learner's (empty, solid, for a method
    with settings or a name no learner has)."""
    parsed = _parsed(method)
    return parsed.entry.dashes if parsed is not None and not parsed.settings else ()


def order(methods: typing.Iterable[str]) -> list[str]:
    """``methods`` in figure order: by learner (:func:`entries` order), a bare name before
    the same learner with settings; names no learner has after them, sorted."""
    rank = {e.name: i for i, e in enumerate(entries())}

    def where(m: str) -> tuple:
        parsed = _parsed(m)
        if parsed is None:
            return (len(rank), m)
        return (rank[parsed.entry.name], bool(parsed.settings), m)

    return sorted(set(methods), key=where)


def family(method: str) -> str | None:
    """The learner ``method`` is a variant of (``GDQ`` for ``GDQ-code:m=3``), or None for a
    name no learner has."""
    parsed = _parsed(method)
    return None if parsed is None else parsed.entry.base


def settings_table(found: LearnerEntry) -> list[tuple[str, str, str, str]]:
    """``(field, type and range, default, first line of its docs)`` of each setting of
    ``found`` (its fixed settings' defaults as its name sets them)."""
    defaults = found.config(**found.fixed)
    rows = []
    for f in fields(found.config):
        if f.name in found.fixed:
            continue
        span = field_range(found.config, f.name)
        doc = " ".join(field_doc(found.config, f.name).split(". ")[0].split())
        doc = doc if len(doc) <= 100 else doc[:97].rsplit(" ", 1)[0] + " ..."
        default = getattr(defaults, f.name)
        rows.append((f.name, type_text(found.config, f.name) + (f" in {span}" if span else ""),
                     "none" if default is None else str(default), doc))
    return rows
