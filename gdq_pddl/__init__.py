"""gdq_pddl: Guided Dyna-Q, reinforcement learning guided by a PDDL planner."""

from gdq_pddl.envs import register_envs

__version__ = "0.1.0"

register_envs()  # gymnasium.make("gdq_pddl/Office-v0" or "gdq_pddl/PDDL-v0", ...) after import
