"""gdq_pddl: Guided Dyna-Q, reinforcement learning guided by a PDDL planner."""

__version__ = "0.1.0"
