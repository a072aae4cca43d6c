"""Simulated worlds as Gymnasium environments, their true model and its exact solution.

:func:`register_envs` (called when :mod:`gdq_pddl` is imported) registers
``gdq_pddl/Office-v0``::

    import gymnasium, gdq_pddl
    env = gymnasium.make("gdq_pddl/Office-v0", task="C")
    env = gymnasium.make("gdq_pddl/Office-v0", start="p0", goal="p17")
    env = gymnasium.make("gdq_pddl/Office-v0", world="my_building.toml", task="A")

No ``max_episode_steps`` is registered: the env counts its own steps and ends an episode
at the world's ``step_limit`` with the failure reward ``-r_max``; a ``TimeLimit`` wrapper
would duplicate that, and with a fixed number it would be wrong for a world file whose
step limit differs from the office's 20.
"""

from __future__ import annotations

OFFICE_ID = "gdq_pddl/Office-v0"


def register_envs() -> None:
    """Register the package's envs with Gymnasium (a second call does nothing)."""
    import gymnasium

    if OFFICE_ID in gymnasium.registry:
        return
    gymnasium.register(id=OFFICE_ID, entry_point="gdq_pddl.envs.office:OfficeEnv",
                       max_episode_steps=None)
