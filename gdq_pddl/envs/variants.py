"""Derived worlds: the same building (and knowledge) with different dynamics, as new
:class:`World` objects (for tests and experiments on inaccurate knowledge)."""

from __future__ import annotations

from dataclasses import replace

from gdq_pddl.errors import WorldError
from gdq_pddl.world_types import World


def deterministic_world(world: World) -> World:
    """``world`` where every action does what it says: doors always open and let the
    robot through (success 1, stuck 0) and ``goto``/``approach`` never slip."""
    doors = tuple(replace(d, success=1.0, stuck=0.0) for d in world.doors)
    return replace(world, name=f"{world.name}-deterministic", doors=doors,
                   navigation_success=1.0)


def with_door(world: World, name: str, success: float | None = None,
              stuck: float | None = None) -> World:
    """``world`` with door ``name``'s success and/or stuck probability replaced."""
    doors = {d.name: d for d in world.doors}
    if name not in doors:
        raise WorldError(world.source, f"doors.{name}",
                         f"unknown door (known: {', '.join(doors) or 'none'})")
    door = doors[name]
    success = door.success if success is None else float(success)
    stuck = door.stuck if stuck is None else float(stuck)
    if not (0.0 <= success <= 1.0 and 0.0 <= stuck <= 1.0 and success + stuck <= 1.0 + 1e-12):
        raise WorldError(world.source, f"doors.{name}",
                         f"need probabilities in [0, 1] with success + stuck <= 1, "
                         f"got {success} + {stuck}")
    new = replace(door, success=success, stuck=stuck)
    return replace(world, doors=tuple(new if d.name == name else d for d in world.doors))
