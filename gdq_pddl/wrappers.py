"""The planner's knowledge for any Gymnasium agent: standard wrappers (docs/python.md).

Each wraps an env of this package (``gdq_pddl/Office-v0``, ``gdq_pddl/PDDL-v0``, an
:class:`~gdq_pddl.envs.online_env.OnlineEnv`), under ``gymnasium.make`` or in a vector
env (``gymnasium.make_vec(..., wrappers=[...])``), and reads the knowledge the learners'
context reads, through the env's instance (``env.unwrapped.instance``):

- ``instance.goal_distance(s)``: the fewest actions from learner state ``s`` to the goal
  if the knowledge is right (the context's ``plans.length[s]``; GDQ's prior model's
  distance; 0 at the goal, -1 where the knowledge reaches no goal);
- ``instance.plan_action(s)``: the first env action of a shortest plan from ``s`` (the
  lowest one of ``plans.first_actions[s]``, through ``context.action_of``; -1: none),
  which every env's ``info["plan_action"]`` carries beside ``action_mask``;
- ``instance.atom_names`` and ``env.unwrapped.facts()``: the true state's atoms.

On a problem explored online (:mod:`gdq_pddl.envs.online`) the distances and plans are
those of the estimates the learners read there (a reached state's one-step lookahead over
h_add); an online problem made without estimates (``estimate=None``) has none, and the
wrappers that read distances refuse it (:class:`~gdq_pddl.errors.ConfigError`).

:class:`KnowledgeShaping` adds the potential-based shaping term (Ng, Harada and Russell
1999) ``F_t = gamma * phi(s_{t+1}) - phi(s_t)`` to each reward, with

- ``potential="distance"``: ``phi(s) = -scale * d(s)``;
- ``potential="plan-step"`` (Grzes and Kudenko 2008): ``phi(s) = scale * w * step(s)``,
  ``step(s) = max(0, L - d(s))`` the step of a shortest plan from the episode's start
  that ``s`` stands at (states farther from the goal than the start: step 0),
  ``L = d(s_0)`` that plan's length and ``w = R_max / L`` (``R_max`` the env's
  ``r_max``; 1 if that is 0); 0 where ``L`` is 0;

where ``d(s)`` is the knowledge's goal distance, or the env's step limit where the
knowledge reaches no goal from ``s`` (a dead end or a state the knowledge cannot solve
from: no goal within an episode). ``phi`` is 0 at a state where the episode terminated
(the goal, or stuck): Ng et al.'s condition on absorbing states, so the optimal policy
is unchanged; a truncated episode's last state keeps its ``phi``. So for every episode of
``T`` steps, exactly (up to floating point)::

    sum_{t < T} gamma**t * F_t == gamma**T * phi(s_T) - phi(s_0)

(the discounted sum telescopes; the undiscounted sum of the ``F_t`` does not, unless
``gamma`` is 1). ``info`` says ``potential`` (``phi`` of the state reached; at reset,
``phi(s_0)``), ``shaping`` (``F_t``) and ``unshaped_reward`` (the env's reward), so the
unshaped return can always be recovered.
"""

from __future__ import annotations

import math
from typing import Any

import gymnasium as gym
import numpy as np
from gymnasium.spaces import Box, Dict, Discrete, MultiBinary

from gdq_pddl.envs.base import CompiledEnv
from gdq_pddl.envs.online import OnlineInstance
from gdq_pddl.errors import ConfigError

__all__ = ["POTENTIALS", "DistanceObservation", "FactObservation", "KnowledgeShaping",
           "knowledge_env"]

POTENTIALS = ("distance", "plan-step")
"""The potentials :class:`KnowledgeShaping` knows."""


def knowledge_env(env: gym.Env, who: str, distances: bool = False) -> CompiledEnv:
    """The env of this package under ``env``'s wrappers; :class:`ConfigError` naming
    ``who`` if there is none, or if ``distances`` are needed and it has none (a problem
    explored online without estimates)."""
    base = env.unwrapped
    if not isinstance(base, CompiledEnv):
        raise ConfigError(f"{who}: {type(base).__name__} is not an env of gdq_pddl "
                          "(gdq_pddl/Office-v0, gdq_pddl/PDDL-v0): it carries no planner "
                          "knowledge")
    instance = base.instance
    if distances and isinstance(instance, OnlineInstance) and not instance.estimates:
        raise ConfigError(f"{who}: {instance.source} is explored online without distance "
                          "estimates (estimate=None): there are no goal distances to read")
    return base


def _number(who: str, name: str, value: Any, low: float, high: float,
            low_open: bool = True) -> float:
    """``value`` as a float in ``(low, high]`` (``[low, high]`` if not ``low_open``)."""
    try:
        x = float(value)
    except (TypeError, ValueError):
        x = math.nan
    if not (math.isfinite(x) and (x > low if low_open else x >= low) and x <= high) or \
            isinstance(value, bool):
        raise ConfigError(f"{who}: {name}={value!r}: expected a number in "
                          f"{'(' if low_open else '['}{low:g}, {high:g}]")
    return x


class KnowledgeShaping(gym.Wrapper, gym.utils.RecordConstructorArgs):
    """Potential-based shaping from the knowledge's goal distance (module docstring):
    ``reward + gamma * phi(s') - phi(s)``; ``info`` has ``shaping``, ``potential`` and
    ``unshaped_reward``. ``gamma`` should be the agent's discount."""

    def __init__(self, env: gym.Env, gamma: float = 0.99, potential: str = "distance",
                 scale: float = 1.0) -> None:
        gym.utils.RecordConstructorArgs.__init__(self, gamma=gamma, potential=potential,
                                                 scale=scale)  # so env.spec remakes it
        super().__init__(env)
        self.gamma = _number("KnowledgeShaping", "gamma", gamma, 0.0, 1.0)
        """The discount of ``F = gamma * phi(s') - phi(s)``."""
        if potential not in POTENTIALS:
            raise ConfigError(f"KnowledgeShaping: potential={potential!r}: expected one of "
                              f"{', '.join(POTENTIALS)}")
        self.potential = potential
        """``"distance"`` or ``"plan-step"``."""
        self.scale = _number("KnowledgeShaping", "scale", scale, 0.0, 1e9)
        """What the potential is multiplied by."""
        knowledge_env(env, "KnowledgeShaping", distances=True)
        self._plan_length = 0
        self._phi = 0.0

    def distance(self, s: int) -> int:
        """``d(s)``: the knowledge's goal distance of learner state ``s``, or the env's step
        limit where the knowledge reaches no goal from ``s``."""
        base = self.env.unwrapped
        d = base.instance.goal_distance(s)
        return d if d >= 0 else int(base.model.step_limit)

    def potential_of(self, s: int) -> float:
        """``phi(s)`` of learner state ``s`` in the current episode (not at its end)."""
        d = self.distance(s)
        if self.potential == "distance":
            return -self.scale * d
        length = self._plan_length
        if length <= 0:
            return 0.0
        r_max = float(self.env.unwrapped.instance.r_max) or 1.0
        return self.scale * r_max / length * max(0, length - d)

    def reset(self, *, seed: int | None = None,
              options: dict[str, Any] | None = None) -> tuple[Any, dict[str, Any]]:
        """The env's reset; ``info["potential"]`` is ``phi(s_0)``."""
        obs, info = self.env.reset(seed=seed, options=options)
        s = self.env.unwrapped.learner_state()
        self._plan_length = self.distance(s)
        self._phi = self.potential_of(s)
        return obs, {**info, "potential": self._phi}

    def step(self, action: Any) -> tuple[Any, float, bool, bool, dict[str, Any]]:
        """The env's step, its reward shaped; ``info`` says ``shaping``, ``potential``
        (``phi`` of the state reached, 0 where the episode terminated) and
        ``unshaped_reward``."""
        obs, reward, terminated, truncated, info = self.env.step(action)
        phi = 0.0 if terminated else self.potential_of(self.env.unwrapped.learner_state())
        shaping = self.gamma * phi - self._phi
        self._phi = phi
        return obs, float(reward) + shaping, terminated, truncated, {
            **info, "shaping": shaping, "potential": phi, "unshaped_reward": float(reward)}


class FactObservation(gym.ObservationWrapper, gym.utils.RecordConstructorArgs):
    """The true state's atoms as a ``MultiBinary`` (``int8`` 0/1) over :attr:`atom_names`:
    a PDDL problem's fluent ground atoms (static ones left out); the office's ``(at p)``
    for every position and ``(open d)`` for every door. The office's are its full state
    (every door), more than its 31 learner states say."""

    def __init__(self, env: gym.Env) -> None:
        gym.utils.RecordConstructorArgs.__init__(self)
        super().__init__(env)
        base = knowledge_env(env, "FactObservation")
        self.atom_names: tuple[str, ...] = tuple(base.instance.atom_names)
        """The name of each entry of the observation, e.g. ``"(at c11)"``."""
        self.observation_space = MultiBinary(len(self.atom_names))

    def observation(self, observation: Any) -> np.ndarray:
        """The true state's atoms (the env's ``facts()``), whatever ``observation`` is."""
        return self.env.unwrapped.facts()


class DistanceObservation(gym.ObservationWrapper, gym.utils.RecordConstructorArgs):
    """The wrapped observation and the knowledge's goal distance, as a ``Dict``:
    ``"observation"`` (the wrapped env's), ``"distance"`` (``float32[1]``, the fewest
    actions to the goal if the knowledge is right; -1 where it reaches no goal; at most
    the number of states less one, unbounded on a problem explored online) and, with
    ``plan_action=True``, ``"plan_action"`` (``Discrete(n + 1)``: the first action of a
    shortest plan, or ``n``, one past the last action, where there is none). For a flat
    ``Box``, wrap it in ``gymnasium.wrappers.FlattenObservation`` (a ``Discrete`` entry
    becomes one-hot; not on a problem explored online, whose observations grow)."""

    def __init__(self, env: gym.Env, plan_action: bool = True) -> None:
        gym.utils.RecordConstructorArgs.__init__(self, plan_action=plan_action)
        super().__init__(env)
        base = knowledge_env(env, "DistanceObservation", distances=True)
        self.plan_action = bool(plan_action)
        """Whether the observation has ``"plan_action"``."""
        self._n = int(env.action_space.n)
        online = isinstance(base.instance, OnlineInstance)  # its states and estimates grow
        high = np.inf if online else float(max(base.instance.n_states - 1, 0))
        spaces: dict[str, gym.Space] = {
            "observation": env.observation_space,
            "distance": Box(-1.0, high, shape=(1,), dtype=np.float32)}
        if self.plan_action:
            spaces["plan_action"] = Discrete(self._n + 1)
        self.observation_space = Dict(spaces)

    def observation(self, observation: Any) -> dict[str, Any]:
        """``observation`` with the knowledge's distance (and plan action) of the state."""
        base = self.env.unwrapped
        s = base.learner_state()
        out = {"observation": observation,
               "distance": np.array([base.instance.goal_distance(s)], dtype=np.float32)}
        if self.plan_action:
            a = base.instance.plan_action(s)
            out["plan_action"] = np.int64(a if a >= 0 else self._n)
        return out
