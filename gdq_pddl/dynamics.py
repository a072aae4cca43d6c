"""The dynamics file (TOML, ``docs/domains.md``): reality for a PDDL domain, per action
schema and optionally per object, how often it works (``success``), gets stuck
(``stuck``), what the rest does (``failure``) and what it costs. For a PPDDL domain the
file is an *overlay*: only ``r_max``, ``step_limit`` and costs.
"""

from __future__ import annotations

import difflib
import math
import tomllib
from collections.abc import Iterable, Mapping
from dataclasses import dataclass, field
from typing import Any

from gdq_pddl.errors import WorldError
from gdq_pddl.limits import MAX_NUMBER
from gdq_pddl.pddl.model import Atom, Domain, Problem

COST_KINDS = {"const": 0, "uniform": 1, "normal": 2}
"""Numeric codes of cost distributions, as the compiled simulator reads them."""

COST_KEYS: dict[str, tuple[str, ...]] = {
    "uniform": ("dist", "low", "high"),
    "normal": ("dist", "mean", "sd"),
}
"""The keys of a cost table, by distribution."""


@dataclass(frozen=True)
class CostDist:
    """The cost of one action: a constant, ``uniform(a, b)`` or ``normal(a, b)`` clipped at 0."""

    kind: str = "const"
    a: float = 1.0
    b: float = 0.0


def read_toml(text: str, source: str) -> dict[str, Any]:
    """The tables of a TOML text; :class:`WorldError` naming ``source`` if it is not TOML."""
    try:
        return tomllib.loads(text)
    except tomllib.TOMLDecodeError as exc:
        raise WorldError(source, "", f"not valid TOML: {exc}") from None


class Checks:
    """The checks world and dynamics files share (strict keys, typed and finite values,
    probabilities, costs); each error names the file and the key at fault."""

    def __init__(self, source: str, raw: dict[str, Any]) -> None:
        self.source, self.raw = source, raw

    def fail(self, key: str, message: str) -> WorldError:
        return WorldError(self.source, key, message)

    def known_keys(self, table: Mapping[str, Any], path: str, allowed: Iterable[str],
                   what: str = "key") -> None:
        """Refuse a key of ``table`` not in ``allowed`` (a misspelling would be ignored)."""
        allowed = tuple(allowed)
        for key in table:
            if key not in allowed:
                close = difflib.get_close_matches(key, allowed, n=1)
                hint = f"did you mean {close[0]!r}? " if close else ""
                where = f"{path}.{key}" if path else key
                raise self.fail(where, f"unknown {what} ({hint}expected one of: "
                                f"{', '.join(allowed)})")

    def get(self, table: Mapping[str, Any], key: str, path: str, kind: type | tuple,
            default: Any = ...) -> Any:
        if key not in table:
            if default is ...:
                raise self.fail(path, "missing")
            return default
        value = table[key]
        if kind is float and isinstance(value, int) and not isinstance(value, bool):
            value = float(value)
        if not isinstance(value, kind) or isinstance(value, bool) and kind is not bool:
            names = (kind,) if isinstance(kind, type) else kind
            name = " or ".join(k.__name__ for k in names)
            raise self.fail(path, f"expected {name}, got {value!r}")
        if isinstance(value, (int, float)) and not isinstance(value, bool):
            self.finite(value, path)
        return value

    def finite(self, value: float, path: str) -> None:
        """Refuse NaN, infinities and numbers past :data:`MAX_NUMBER`."""
        if not math.isfinite(value) or abs(value) > MAX_NUMBER:
            raise self.fail(path, f"expected a finite number of at most {MAX_NUMBER:g} in "
                            f"size, got {value!r}")

    def positive(self, table: Mapping[str, Any], key: str, path: str, default: float) -> float:
        value = self.get(table, key, path, float, default)
        if value <= 0:
            raise self.fail(path, f"must be > 0, got {value}")
        return value

    def count(self, table: Mapping[str, Any], key: str, path: str, default: int) -> int:
        value = self.get(table, key, path, int, default)
        if value < 1:
            raise self.fail(path, f"must be >= 1, got {value}")
        return value

    def probability(self, table: Mapping[str, Any], key: str, path: str) -> float:
        value = self.get(table, key, path, float)
        if not 0.0 <= value <= 1.0:
            raise self.fail(path, f"a probability must be in [0, 1], got {value}")
        return value

    def cost(self, value: Any, path: str) -> CostDist:
        if isinstance(value, (int, float)) and not isinstance(value, bool):
            self.finite(value, path)
            if value < 0:
                raise self.fail(path, f"a cost must be >= 0, got {value}")
            return CostDist("const", float(value))
        if not isinstance(value, dict):
            raise self.fail(path, f"expected a number or a table with 'dist', got {value!r}")
        dist = value.get("dist")
        if dist not in ("uniform", "normal"):
            raise self.fail(f"{path}.dist", f"expected 'uniform' or 'normal', got {dist!r}")
        self.known_keys(value, path, COST_KEYS[dist])
        if dist == "uniform":
            low = self.get(value, "low", f"{path}.low", float)
            high = self.get(value, "high", f"{path}.high", float)
            if not 0 <= low <= high:
                raise self.fail(path, f"need 0 <= low <= high, got low={low} high={high}")
            return CostDist("uniform", low, high)
        mean = self.get(value, "mean", f"{path}.mean", float)
        sd = self.get(value, "sd", f"{path}.sd", float)
        if sd < 0 or mean < 0:
            raise self.fail(path, f"need mean >= 0 and sd >= 0, got {mean}, {sd}")
        return CostDist("normal", mean, sd)


FAILURES = ("nothing", "stuck")
"""Named failure modes; a list of schema names is the third one (a slip)."""


@dataclass(frozen=True)
class Outcomes:
    """What one ground action does: the probabilities of its outcomes and its cost."""

    success: float = 1.0
    stuck: float = 0.0
    failure: str | tuple[str, ...] = "nothing"
    """What the remaining ``1 - success - stuck`` does: ``"nothing"``, or a slip to a
    random applicable action of these schemas (``"stuck"``: ``stuck = 1 - success``)."""
    cost: CostDist | None = None  # None: the cost the domain states, else 1


@dataclass(frozen=True)
class Dynamics:
    """A validated dynamics file (:func:`parse_dynamics`, or ``World.dynamics``)."""

    source: str
    r_max: float = 20.0
    step_limit: int = 20
    actions: Mapping[str, Outcomes] = field(default_factory=dict)  # others: cost 1, no failure
    objects: Mapping[str, Mapping[str, Outcomes]] = field(default_factory=dict)  # overrides
    name: str = ""
    description: str = ""
    stated: frozenset[str] = frozenset()  # the [dynamics] keys the file gives

    def outcomes(self, schema: str, args: tuple[str, ...]) -> Outcomes:
        """The outcomes of the ground action ``(schema *args)``."""
        per_object = self.objects.get(schema, {})
        for a in args:
            if a in per_object:
                return per_object[a]
        return self.actions.get(schema, Outcomes())


def split_action(name: str) -> tuple[str, tuple[str, ...]]:
    """``"(move a b)"`` -> ``("move", ("a", "b"))``."""
    atom = Atom.parse(name)
    return atom.predicate, atom.args


def parse_dynamics(text: str, domain: Domain, problem: Problem,
                   source: str = "<string>", overlay: bool = False) -> Dynamics:
    """Validate the TOML ``text`` of a dynamics file; ``source`` names it in errors."""
    return _DynamicsValidator(source, read_toml(text, source), domain, problem,
                              overlay).dynamics()


OUTCOME_KEYS = ("success", "stuck", "failure")
"""What a dynamics file says about outcomes, and an overlay may not (the domain does)."""


class _DynamicsValidator(Checks):
    """The world file's checks (types, probabilities, costs) plus the domain's names."""

    def __init__(self, source: str, raw: dict[str, Any], domain: Domain,
                 problem: Problem, overlay: bool = False) -> None:
        super().__init__(source, raw)
        self.schemas = {a.name: a for a in domain.actions}
        self.objects = problem.objects
        self.overlay = overlay
        self.domain_source = domain.source

    def dynamics(self) -> Dynamics:
        self.known_keys(self.raw, "", ("dynamics", "actions"), "table")
        d = self.get(self.raw, "dynamics", "dynamics", dict, {})
        self.known_keys(d, "dynamics", ("r_max", "step_limit", "name", "description"))
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
        self.known_keys(table, key, (*OUTCOME_KEYS, "cost", "objects"))
        for k in OUTCOME_KEYS if self.overlay else ():
            if k in table:
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
