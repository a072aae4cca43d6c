"""Simulated worlds as Gymnasium environments, their true model and its exact solution.

:func:`register_envs` (called when :mod:`gdq_pddl` is imported) registers
``gdq_pddl/Office-v0`` (:mod:`gdq_pddl.envs.office`) and ``gdq_pddl/PDDL-v0``, any PDDL
problem under its reality (:mod:`gdq_pddl.envs.pddl_env`)::

    env = gymnasium.make("gdq_pddl/Office-v0", task="C")  # or start="p0", goal="p17", world=...
    env = gymnasium.make("gdq_pddl/PDDL-v0", domain="keys", problem="keys-2")
    env = gymnasium.make("gdq_pddl/PDDL-v0", domain="d.pddl", problem="p.pddl",
                         dynamics="d.toml", determinisation="most-likely")

Both are :class:`~gdq_pddl.envs.pddl_env.PDDLEnv` on an instance of the one pipeline,
stepping the true model of :func:`~gdq_pddl.envs.model.compile_true_model`. No
``max_episode_steps`` is registered: the env ends an episode at its own step limit.
"""

from __future__ import annotations

import gymnasium

__all__ = ["ENV_IDS", "OFFICE_ID", "PDDL_ID", "office", "pddl_env", "register_envs"]

OFFICE_ID = "gdq_pddl/Office-v0"
PDDL_ID = "gdq_pddl/PDDL-v0"
ENV_IDS = {OFFICE_ID: "gdq_pddl.envs.office:OfficeEnv",
           PDDL_ID: "gdq_pddl.envs.pddl_env:PDDLEnv"}
"""Every env id this package registers, and its entry point."""


def register_envs() -> None:
    """Register the package's envs with Gymnasium (a second call does nothing)."""
    for env_id, entry_point in ENV_IDS.items():
        if env_id not in gymnasium.registry:
            gymnasium.register(id=env_id, entry_point=entry_point, max_episode_steps=None)
