"""gdq_pddl: Guided Dyna-Q, reinforcement learning guided by a PDDL planner."""

from gdq_pddl import _jit_cache

_jit_cache.refresh()  # before any compiled function loads its cache (see _jit_cache)

from gdq_pddl.envs import register_envs  # noqa: E402

__version__ = "0.1.0"

register_envs()  # gymnasium.make("gdq_pddl/Office-v0" or "gdq_pddl/PDDL-v0", ...) after import
