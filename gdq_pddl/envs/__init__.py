"""Simulated worlds as Gymnasium environments, their true model and its exact solution.

:func:`register_envs` (called when :mod:`gdq_pddl` is imported) registers
``gdq_pddl/Office-v0``::

    import gymnasium, gdq_pddl
    env = gymnasium.make("gdq_pddl/Office-v0", task="C")
    env = gymnasium.make("gdq_pddl/Office-v0", start="p0", goal="p17")
    env = gymnasium.make("gdq_pddl/Office-v0", world="my_building.toml", task="A")

and ``gdq_pddl/PDDL-v0``, any PDDL problem under a dynamics file
(:mod:`gdq_pddl.envs.pddl_env`)::

    env = gymnasium.make("gdq_pddl/PDDL-v0", domain="keys", problem="keys-2")
    env = gymnasium.make("gdq_pddl/PDDL-v0", domain="d.pddl", problem="p.pddl",
                         dynamics="d.toml")
    env = gymnasium.make("gdq_pddl/PDDL-v0", domain="ppddl.pddl", problem="p.pddl",
                         determinisation="most-likely")  # what the planner knows

Both are one env class, :class:`~gdq_pddl.envs.pddl_env.PDDLEnv`, on an instance of the
one pipeline: a PDDL problem with its reality, or a world's task seen through the
office's observation map (:class:`~gdq_pddl.envs.office.OfficeInstance`); both step
the true model :func:`~gdq_pddl.envs.model.compile_true_model` builds.

No ``max_episode_steps`` is registered: the env counts its own steps and ends an episode
at the world's (or the dynamics file's) ``step_limit`` with the failure reward
``-r_max``, and its ``spec.max_episode_steps`` says that limit (a registered
``TimeLimit`` would duplicate it, with one number for every world file).
"""

from __future__ import annotations

import gymnasium

__all__ = ["ENV_IDS", "OFFICE_ID", "PDDL_ID", "office", "pddl_env", "register_envs"]

OFFICE_ID = "gdq_pddl/Office-v0"
"""The office's env id (:class:`~gdq_pddl.envs.office.OfficeEnv`)."""
PDDL_ID = "gdq_pddl/PDDL-v0"
"""Any PDDL problem's env id (:mod:`gdq_pddl.envs.pddl_env`)."""
ENV_IDS = {OFFICE_ID: "gdq_pddl.envs.office:OfficeEnv",
           PDDL_ID: "gdq_pddl.envs.pddl_env:PDDLEnv"}
"""Every env id this package registers, and its entry point."""


def register_envs() -> None:
    """Register the package's envs with Gymnasium (a second call does nothing)."""
    for env_id, entry_point in ENV_IDS.items():
        if env_id not in gymnasium.registry:
            gymnasium.register(id=env_id, entry_point=entry_point, max_episode_steps=None)
