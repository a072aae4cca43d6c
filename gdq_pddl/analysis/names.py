"""The names an output folder uses: its experiments, and the order methods are listed in
(the GDQ variants first)."""

from __future__ import annotations

from collections.abc import Iterable

METHOD_ORDER = ("GDQ", "GDQ-literal", "GDQ-code", "DARLING", "DARLING-code", "Dyna-Q",
                "Q-learning")
"""The order methods are listed in every figure and table (unknown ones follow, sorted)."""

TASKS_EXPERIMENT = "tasks"
ROBOT_EXPERIMENT = "robot"
SWITCH_PREFIX = "switch-"


def order_methods(methods: Iterable[str]) -> list[str]:
    """``methods`` in :data:`METHOD_ORDER`, unknown names after them in sorted order."""
    found = set(methods)
    known = [m for m in METHOD_ORDER if m in found]
    return known + sorted(found - set(known))


def is_gdq(method: str) -> bool:
    """GDQ or one of its variants (``GDQ-literal``, ``GDQ-code``): not a baseline."""
    return method == "GDQ" or method.startswith("GDQ-")
