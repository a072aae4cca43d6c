"""The methods of ``gdq-pddl scale`` by name, and the learner each one is (what the CLI
reads when it starts, without loading the learners; :mod:`gdq_pddl.experiments.scale`
runs them)."""

from __future__ import annotations

METHODS: dict[str, tuple[str, dict]] = {
    "GDQ": ("gdq", {}),
    "GDQ-literal": ("gdq", {"variant": "literal"}),
    "GDQ-code": ("gdq", {"variant": "code", "plan_tolerance": 0.3}),
    "DARLING": ("darling", {"tolerance": 0.3}),
    "Dyna-Q": ("dynaq", {}),
    "Q-learning": ("qlearning", {}),
}
"""Name -> (``make_learner`` name, its keyword arguments); GDQ-code and DARLING with
door-route plans within 1.3 x the shortest (see :mod:`gdq_pddl.experiments.scale`)."""

DEFAULT_METHODS = tuple(m for m in METHODS if m != "GDQ-literal")
"""What ``gdq-pddl scale`` runs unless ``--method`` says otherwise: every method but
GDQ-literal, which never learns (``docs/decisions.md``)."""
