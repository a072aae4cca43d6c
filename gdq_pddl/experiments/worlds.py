"""What a world name of an :class:`~gdq_pddl.experiments.protocol.Experiment` means, in
the driver and in every worker alike.

A name is one of three things, told apart by its form alone, never by the files in the
working directory:

- ``office`` or ``office_robot``: a world shipped with the package;
- ``office:<variant>``: a world derived from the office in memory (:data:`WORLDS`, the
  cases of :mod:`gdq_pddl.experiments.knowledge`);
- anything else: the path of a world file. The command line records a ``--world`` file
  by its absolute path (:func:`world_name`), so ``--world office`` naming a file
  ``./office`` is that file in every process, and its hash is in ``config.json``.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import replace
from functools import cache
from pathlib import Path

from gdq_pddl.envs.variants import deterministic_world, with_door
from gdq_pddl.errors import GdqError
from gdq_pddl.world import World, builtin_world, load_world

BUILTIN = ("office", "office_robot")
"""The names of the worlds shipped with the package."""

DERIVED_PREFIX = "office:"
"""How the names of in-memory worlds derived from the office begin."""

PASSAGE = ("p8", "p17")
"""The corridor that exists in reality but not in the knowledge (case ``passage``)."""


def is_file_name(name: str) -> bool:
    """Whether the world name ``name`` is the path of a world file (not built in)."""
    return name not in BUILTIN and not name.startswith(DERIVED_PREFIX)


def world_name(path: Path | None) -> str:
    """The name an experiment records for the ``--world`` option ``path``: ``office`` for
    none, else the file's absolute path (which no built-in name can be mistaken for)."""
    return "office" if path is None else str(Path(path).absolute())


@cache
def load_world_named(name: str) -> World:
    """The world ``name`` means (see the module docstring), loaded once per process."""
    if name in BUILTIN:
        return builtin_world(name)
    if name.startswith(DERIVED_PREFIX):
        return derived_world(name)
    return load_world(Path(name))


def with_edge(world: World, a: str, b: str) -> World:
    """``world`` with an extra walkway ``a``-``b`` (both must be existing positions)."""
    for p in (a, b):
        world.position(p)  # raises WorldError for an unknown position
    if frozenset((a, b)) in {frozenset(e) for e in world.edges}:
        raise GdqError(f"{world.name} already has the edge {a}-{b}")
    return replace(world, edges=(*world.edges, (a, b)))


def _office() -> World:
    return builtin_world("office")


def _locked(door: str) -> Callable[[], World]:
    def build() -> World:
        return replace(with_door(_office(), door, success=0.0, stuck=0.0),
                       name=f"office-locked-{door}")
    return build


def _passage() -> World:
    return replace(with_edge(_office(), *PASSAGE), name="office-passage")


def _deterministic() -> World:
    return deterministic_world(_office())


WORLDS: dict[str, Callable[[], World]] = {
    "office:locked-d1": _locked("d1"),
    "office:locked-d3": _locked("d3"),
    "office:passage": _passage,
    "office:deterministic": _deterministic,
}
"""In-memory derived worlds by name (resolved by :func:`load_world_named`)."""


@cache
def derived_world(name: str) -> World:
    """The derived world ``name`` (a key of :data:`WORLDS`), built once per process."""
    try:
        return WORLDS[name]()
    except KeyError:
        raise GdqError(f"unknown derived world {name!r} (known: {', '.join(WORLDS)})") from None
