"""The dynamics file: reality for a PDDL domain (what its actions really do, and cost).

A PDDL domain says what an action does when it works; a dynamics file (TOML) says how
often it works, what happens when it does not, and what it costs. See
``docs/domains.md`` for the annotated format; in short::

    [dynamics]
    r_max = 20.0            # +r_max on reaching the goal, -r_max on failure
    step_limit = 30         # actions per episode

    [actions.move]          # one table per action schema (others: always succeed, cost 1)
    success = 0.95          # probability that the action has its PDDL effect
    stuck = 0.0             # probability that the trial fails (episode over, -r_max)
    failure = ["move"]      # the rest: "nothing" (default), "stuck", or a list of schemas:
                            # the effect of a uniformly random applicable ground action
                            # of those schemas happens instead (a slip)
    cost = 1.0              # or {dist = "uniform", low, high} / {dist = "normal", mean, sd}

    [actions.move.objects.door3]   # overrides for ground actions that name door3
    success = 0.6
    stuck = 0.2

An object override applies to every ground action of the schema that has the object
among its arguments; when several arguments have one, the leftmost wins. Keys it does
not give come from the schema's table. :func:`load_dynamics` checks everything against
the domain and problem and names the file and key of every error, as world files do.

A cost the file does not give is the one the domain states (``(increase (total-cost)
X)``), else 1. For a PPDDL domain the file is an *overlay* (``overlay=True``): the
domain gives the outcomes, so ``success``, ``stuck`` and ``failure`` are errors, and
the file gives only what PPDDL cannot say: ``r_max`` and ``step_limit`` (they replace
the domain's), costs (they replace the domain's; a distribution, say).
"""

from __future__ import annotations

import tomllib
from collections.abc import Mapping
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

from gdq_pddl.errors import WorldError
from gdq_pddl.inputs import read_text
from gdq_pddl.pddl.model import Domain, Problem
from gdq_pddl.world import CostDist, _Validator

FAILURES = ("nothing", "stuck")
"""Named failure modes; a list of schema names is the third one (a slip)."""


@dataclass(frozen=True)
class Outcomes:
    """What one ground action does: the probabilities of its outcomes and its cost."""

    success: float = 1.0
    stuck: float = 0.0
    failure: str | tuple[str, ...] = "nothing"
    """What the remaining ``1 - success - stuck`` does: ``"nothing"``, or the schemas
    whose applicable ground actions it picks one of at random (a slip). ``"stuck"``
    means ``stuck = 1 - success`` (nothing remains)."""
    cost: CostDist | None = None
    """None: not given; the cost the domain states, else 1."""


@dataclass(frozen=True)
class Dynamics:
    """A validated dynamics file. Build one with :func:`load_dynamics`."""

    source: str
    r_max: float = 20.0
    step_limit: int = 20
    actions: Mapping[str, Outcomes] = field(default_factory=dict)
    """Per schema; schemas not listed always succeed at cost 1."""
    objects: Mapping[str, Mapping[str, Outcomes]] = field(default_factory=dict)
    """Per schema, per object: overrides."""
    name: str = ""
    description: str = ""
    stated: frozenset[str] = frozenset()
    """The ``[dynamics]`` keys the file gives (the others are defaults)."""

    def outcomes(self, schema: str, args: tuple[str, ...]) -> Outcomes:
        """The outcomes of the ground action ``(schema *args)``."""
        per_object = self.objects.get(schema, {})
        for a in args:
            if a in per_object:
                return per_object[a]
        return self.actions.get(schema, Outcomes())


def split_action(name: str) -> tuple[str, tuple[str, ...]]:
    """``"(move a b)"`` -> ``("move", ("a", "b"))``."""
    parts = name.strip("()").split()
    return parts[0], tuple(parts[1:])


def load_dynamics(path: str | Path, domain: Domain, problem: Problem,
                  overlay: bool = False) -> Dynamics:
    """Read and validate a dynamics file (an overlay for a PPDDL domain: ``overlay``)
    against ``domain`` and ``problem``.

    Raises :class:`WorldError` naming the file and key of the first problem found.
    """
    text = read_text(path, lambda src, msg: WorldError(src, "", msg))
    return parse_dynamics(text, domain, problem, source=str(path), overlay=overlay)


def parse_dynamics(text: str, domain: Domain, problem: Problem,
                   source: str = "<string>", overlay: bool = False) -> Dynamics:
    """Validate the TOML ``text`` of a dynamics file; ``source`` names it in errors."""
    try:
        raw = tomllib.loads(text)
    except tomllib.TOMLDecodeError as exc:
        raise WorldError(source, "", f"not valid TOML: {exc}") from None
    return _DynamicsValidator(source, raw, domain, problem, overlay).dynamics()


OUTCOME_KEYS = ("success", "stuck", "failure")
"""What a dynamics file says about outcomes, and an overlay may not (the domain does)."""


class _DynamicsValidator(_Validator):
    """The world file's checks (types, probabilities, costs) plus the domain's names."""

    def __init__(self, source: str, raw: dict[str, Any], domain: Domain,
                 problem: Problem, overlay: bool = False) -> None:
        super().__init__(source, raw)
        self.schemas = {a.name: a for a in domain.actions}
        self.objects = problem.objects
        self.overlay = overlay
        self.domain_source = domain.source

    def dynamics(self) -> Dynamics:
        for key in self.raw:
            if key not in ("dynamics", "actions"):
                raise self.fail(key, "unknown table (expected [dynamics] and [actions.*])")
        d = self.get(self.raw, "dynamics", "dynamics", dict, {})
        for key in d:
            if key not in ("r_max", "step_limit", "name", "description"):
                raise self.fail(f"dynamics.{key}", "unknown key (expected r_max, step_limit, "
                                "name, description)")
        r_max = self.positive(d, "r_max", "dynamics.r_max", 20.0)
        limit = self.count(d, "step_limit", "dynamics.step_limit", 20)
        actions, objects = {}, {}
        for schema, table in self.get(self.raw, "actions", "actions", dict, {}).items():
            key = f"actions.{schema}"
            if schema not in self.schemas:
                raise self.fail(key, f"unknown action schema (the domain has: "
                                f"{', '.join(self.schemas)})")
            if not isinstance(table, dict):
                raise self.fail(key, f"expected a table, got {table!r}")
            base = self.outcomes(table, key, Outcomes())
            actions[schema] = base
            per = {}
            for obj, sub in self.get(table, "objects", f"{key}.objects", dict, {}).items():
                okey = f"{key}.objects.{obj}"
                if obj not in self.objects:
                    raise self.fail(okey, f"unknown object (the problem has: "
                                    f"{', '.join(sorted(self.objects))})")
                if not isinstance(sub, dict):
                    raise self.fail(okey, f"expected a table, got {sub!r}")
                if "objects" in sub:
                    raise self.fail(f"{okey}.objects", "object overrides do not nest")
                per[obj] = self.outcomes(sub, okey, base)
            objects[schema] = per
        return Dynamics(self.source, r_max, limit, actions, objects,
                        self.get(d, "name", "dynamics.name", str, ""),
                        self.get(d, "description", "dynamics.description", str, ""),
                        frozenset(d))

    def outcomes(self, table: Mapping[str, Any], key: str, base: Outcomes) -> Outcomes:
        for k in table:
            if k not in ("success", "stuck", "failure", "cost", "objects"):
                raise self.fail(f"{key}.{k}", "unknown key (expected success, stuck, failure, "
                                "cost, objects)")
            if self.overlay and k in OUTCOME_KEYS:
                raise self.fail(f"{key}.{k}", f"{self.domain_source} is a PPDDL domain: its "
                                "probabilistic effects give the outcomes (a failed trial: "
                                "an outcome that makes (stuck) true), so an overlay gives "
                                "only cost, r_max and step_limit")
        success = self.probability(table, "success", f"{key}.success") \
            if "success" in table else base.success
        failure = self.failure(table, key) if "failure" in table else base.failure
        if failure == "stuck":
            if "stuck" in table:
                raise self.fail(f"{key}.stuck", 'give stuck or failure = "stuck", not both '
                                '(failure = "stuck" means stuck = 1 - success)')
            stuck = 1.0 - success
        else:
            stuck = self.probability(table, "stuck", f"{key}.stuck") \
                if "stuck" in table else base.stuck
        if success + stuck > 1.0 + 1e-12:
            raise self.fail(key, f"success + stuck must be <= 1, got {success} + {stuck}")
        cost = self.cost(table["cost"], f"{key}.cost") if "cost" in table else base.cost
        return Outcomes(success, stuck, failure, cost)

    def failure(self, table: Mapping[str, Any], key: str) -> str | tuple[str, ...]:
        value = table["failure"]
        if isinstance(value, str):
            if value not in FAILURES:
                raise self.fail(f"{key}.failure", f'expected "nothing", "stuck" or a list of '
                                f"action schemas, got {value!r}")
            return value
        if not isinstance(value, list) or not value:
            raise self.fail(f"{key}.failure", f'expected "nothing", "stuck" or a non-empty '
                            f"list of action schemas, got {value!r}")
        for s in value:
            if not isinstance(s, str) or s not in self.schemas:
                raise self.fail(f"{key}.failure", f"unknown action schema {s!r} (the domain "
                                f"has: {', '.join(self.schemas)})")
        return tuple(value)
