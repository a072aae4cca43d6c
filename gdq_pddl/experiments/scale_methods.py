"""The methods of ``gdq-pddl scale`` by name (read by the CLI without loading learners)."""

from __future__ import annotations

METHODS: dict[str, tuple[str, dict]] = {
    "GDQ": ("gdq", {}),
    "GDQ-literal": ("gdq", {"variant": "literal"}),
    "GDQ-code": ("gdq", {"variant": "code", "plan_tolerance": 0.3}),
    "DARLING": ("darling", {"tolerance": 0.3}),
    "Dyna-Q": ("dynaq", {}),
    "Q-learning": ("qlearning", {}),
}
"""Name -> (``make_learner`` name, its keyword arguments)."""

DEFAULT_METHODS = tuple(m for m in METHODS if m != "GDQ-literal")
"""Every method but GDQ-literal, which never learns (``docs/decisions.md``)."""
