"""Deep-RL agents of Stable-Baselines3 and sb3-contrib (``MaskablePPO``, ``PPO``, ``DQN``)
as learners of the registry, run by the same experiments as the tabular learners
(``gdq-pddl run --method MaskablePPO PPO DQN``; docs/learners.md, "Deep-RL agents").

Nothing here imports torch or Stable-Baselines3 until an agent is made: the package and
its commands work without the ``sb3`` extra, which lists these names as needing it
(:data:`SB3_MODULES`, :func:`gdq_pddl.learners.registry.missing`).

A :class:`DeepLearner` runs its own episodes (:meth:`DeepLearner.run_own_episodes`, which
:func:`~gdq_pddl.learners.episodes.run_episodes` calls): Stable-Baselines3's ``learn`` on
the env, with a callback that stops it when the experiment's number of episodes has
finished. Each finished training episode is one row of the records, as for a tabular
learner: its unshaped return (the env's rewards, recorded under any shaping), its steps,
whether it reached the goal and its area visits.
"""

from __future__ import annotations

import importlib
from collections.abc import Callable
from typing import Any

import gymnasium as gym
import numpy as np

from gdq_pddl.errors import ConfigError
from gdq_pddl.learners import registry
from gdq_pddl.learners.config import (
    DeepConfig,
    DQNConfig,
    PPOConfig,
)
from gdq_pddl.learners.context import TaskContext
from gdq_pddl.learners.episodes import EpisodeRecords

AGENTS: dict[str, str] = {"MaskablePPO": "sb3_contrib:MaskablePPO",
                          "PPO": "stable_baselines3:PPO", "DQN": "stable_baselines3:DQN"}
"""Each agent's class in its library."""


def _agent_class(name: str) -> type:
    module, _, attr = AGENTS[name].partition(":")
    return getattr(importlib.import_module(module), attr)


class _Recorder(gym.Wrapper):
    """Records each finished episode of the env under it (the unshaped rewards); sits
    right above the package's env, under the knowledge wrappers."""

    def __init__(self, env: gym.Env, n_areas: int) -> None:
        super().__init__(env)
        self.n_areas = n_areas
        self.rows: list[tuple[float, int, bool, np.ndarray]] = []
        self._start()

    def _start(self) -> None:
        self._return, self._steps = 0.0, 0
        self._areas = np.zeros(self.n_areas, dtype=np.int64)

    def reset(self, **kwargs: Any) -> tuple[Any, dict[str, Any]]:
        self._start()  # an episode cut short by a reset is not a row
        return self.env.reset(**kwargs)

    def step(self, action: Any) -> tuple[Any, float, bool, bool, dict[str, Any]]:
        obs, reward, terminated, truncated, info = self.env.step(action)
        self._return += float(reward)
        self._steps += 1
        area = int(info.get("area", 0))
        if area > 0:
            self._areas[area - 1] += 1
        if terminated or truncated:
            self.rows.append((self._return, self._steps,
                              bool(terminated and info.get("cause") == "goal"), self._areas))
            self._start()
        return obs, reward, terminated, truncated, info


def _wrappers() -> Any:
    """The knowledge wrappers' module, loaded by name when a setting needs it."""
    try:
        return importlib.import_module("gdq_pddl.wrappers")
    except ImportError:
        raise ConfigError("the shaping and obs settings need gdq_pddl.wrappers, which this "
                          "installation of gdq_pddl does not have") from None


class DeepLearner:
    """A Stable-Baselines3 / sb3-contrib agent as a learner of the registry; subclasses
    name the agent (:attr:`agent`). Made for a task context like every learner; its
    network is built on the first env it runs in."""

    agent: str = ""
    """The agent's name in :data:`AGENTS`."""
    config_type: type[DeepConfig] = DeepConfig
    reads_knowledge: bool = False
    """Whether it reads the planner's knowledge (not on a problem explored online, which
    deep agents do not run on)."""
    estimate_weight: float = 1.0

    def __init__(self, context: TaskContext, config: DeepConfig | None = None) -> None:
        registry.check_installed(registry.entry(self.agent), self.agent)
        self.context = context
        self.config = config if config is not None else self.config_type()
        if not isinstance(self.config, self.config_type):
            raise ConfigError(f"{self.agent} takes a {self.config_type.__name__}, got "
                              f"{type(self.config).__name__}")
        self.model: Any = None
        self._states = 0

    @property
    def nbytes(self) -> int:
        """The bytes of the network's parameters (0 before it is built)."""
        if self.model is None:
            return 0
        return sum(p.numel() * p.element_size() for p in self.model.policy.parameters())

    def start_task(self, context: TaskContext) -> None:
        """Switch to the task ``context``, keeping the network (the next env must have the
        same observation and action spaces)."""
        self.context = context

    def _wrap(self, env: gym.Env) -> tuple[_Recorder, gym.Env]:
        recorder = _Recorder(env, int(env.unwrapped.model.area_of_pos.max()))
        wrapped: gym.Env = recorder
        cfg = self.config
        if cfg.shaping != "none":
            wrapped = _wrappers().KnowledgeShaping(wrapped, gamma=cfg.gamma,
                                                   potential=cfg.shaping, scale=cfg.scale)
        if cfg.obs == "facts":
            wrapped = _wrappers().FactObservation(wrapped)
        elif cfg.obs == "distance":
            wrapped = _wrappers().DistanceObservation(wrapped)
        return recorder, wrapped

    def _build(self, vec: Any, seed: int) -> None:
        import torch  # optional (the sb3 extra), slow to import
        from stable_baselines3.common.utils import set_random_seed  # optional (sb3 extra)

        torch.set_num_threads(1)  # small networks; --jobs runs one process per core
        set_random_seed(seed)  # before the network is built: its initial weights
        policy = "MultiInputPolicy" if isinstance(vec.observation_space, gym.spaces.Dict) \
            else "MlpPolicy"
        hidden = [self.config.hidden, self.config.hidden]
        self.model = _agent_class(self.agent)(
            policy, vec, device="cpu", verbose=0, seed=None,
            policy_kwargs={"net_arch": hidden}, **self.config.agent_kwargs())
        self.model.action_space.seed(seed)  # DQN's random actions
        if isinstance(self.config, DQNConfig):
            self.model.exploration_schedule = _Epsilon(self.model, self.config)

    def wrap(self, env: gym.Env) -> gym.Env:
        """``env`` in the knowledge wrappers of the settings (``shaping``, ``obs``): what
        the agent sees, for an evaluation env (:meth:`greedy_actions`)."""
        return self._wrap(env)[1]

    def _start(self, env: gym.Env, rng: np.random.Generator) -> tuple[_Recorder, Any, bool]:
        """The recorder and vector env of ``env``, the network built on the first one
        (its seed drawn from ``rng``); whether it was built now."""
        from stable_baselines3.common.vec_env import DummyVecEnv  # optional (sb3 extra)

        recorder, wrapped = self._wrap(env)
        vec = DummyVecEnv([lambda: wrapped])
        first = self.model is None
        if first:
            self._build(vec, int(rng.integers(2**31 - 1)))
        else:
            if vec.observation_space != self.model.observation_space or \
                    vec.action_space != self.model.action_space:
                raise ConfigError(f"{self.agent}: the next task's env has other observation "
                                  "or action spaces than the network was built for")
            self.model.set_env(vec)
        self._states = int(getattr(env.observation_space, "n", 0))
        self._masks = env.unwrapped.mask_table
        return recorder, vec, first

    def train_steps(self, env: gym.Env, steps: int, rng: np.random.Generator,
                    every: int = 0, checkpoint: Callable[[int], None] | None = None
                    ) -> EpisodeRecords:
        """Train on ``env`` (seeded by ``env.reset(seed=...)`` before) for ``steps`` env
        steps (PPO: rounded up to whole rollouts of ``n_steps``), calling
        ``checkpoint(steps_done)`` after every ``every`` steps (0: never); the records of
        the training episodes that finished. What benchmarks/deep_rl.py measures with."""
        recorder, _, first = self._start(env, rng)
        if every and checkpoint is not None:
            checkpoint(int(self.model.num_timesteps))
        self.model.learn(total_timesteps=steps, reset_num_timesteps=first,
                         callback=_every(every, checkpoint), progress_bar=False)
        return _records(recorder, len(recorder.rows))

    def greedy_actions(self, obs: Any, masks: np.ndarray | None = None) -> np.ndarray:
        """The network's greedy actions for a batch of observations ``obs`` (as
        :meth:`wrap` gives them), drawn among ``masks`` (bool[batch, actions]) by
        MaskablePPO; the others ignore ``masks``."""
        if self.agent == "MaskablePPO" and masks is not None:
            return self.model.predict(obs, deterministic=True, action_masks=masks)[0]
        return self.model.predict(obs, deterministic=True)[0]

    def run_own_episodes(self, env: gym.Env, n_episodes: int,
                         rng: np.random.Generator) -> EpisodeRecords:
        """Train on ``env`` (seeded by ``env.reset(seed=...)`` before) until
        ``n_episodes`` episodes have finished; the agent's seed is drawn from ``rng``."""
        recorder, vec, first = self._start(env, rng)
        budget = self.config.steps if self.config.steps is not None else \
            n_episodes * int(env.unwrapped.model.step_limit)
        if n_episodes and budget:
            self.model.learn(total_timesteps=budget, callback=_stopper(recorder, n_episodes),
                             reset_num_timesteps=first, progress_bar=False)
        if len(recorder.rows) < n_episodes:  # the step budget is spent: no more learning
            obs = self.model._last_obs if self.model._last_obs is not None else vec.reset()
            while len(recorder.rows) < n_episodes:
                masks = np.stack(vec.env_method("action_masks")) \
                    if self.agent == "MaskablePPO" else None
                obs, *_ = vec.step(self.greedy_actions(obs, masks))
        return _records(recorder, n_episodes)

    def greedy_policy(self) -> np.ndarray:
        """int64[n_states]: the network's greedy action of each learner state (masked for
        MaskablePPO), where it sees the state's index (``obs=state``); empty otherwise
        (its policy is not a function of the index alone, and policies.csv gets no rows)."""
        if self.model is None or self.config.obs != "state" or not self._states:
            return np.zeros(0, dtype=np.int64)
        masks = self._masks[:self._states].astype(bool) if self.agent == "MaskablePPO" else None
        return np.asarray(self.greedy_actions(np.arange(self._states), masks), dtype=np.int64)


class _Epsilon:
    """DQN's epsilon by steps done (``exploration_steps``), not by share of the budget."""

    def __init__(self, model: Any, config: DQNConfig) -> None:
        self.model, self.config = model, config

    def __call__(self, progress_remaining: float) -> float:
        c = self.config
        done = min(1.0, self.model.num_timesteps / c.exploration_steps) \
            if c.exploration_steps else 1.0
        return c.exploration_initial_eps + done * (c.exploration_final_eps -
                                                   c.exploration_initial_eps)


def _records(recorder: _Recorder, n_episodes: int) -> EpisodeRecords:
    """The first ``n_episodes`` rows of ``recorder`` as records."""
    rows = recorder.rows[:n_episodes]
    areas = np.zeros((n_episodes, recorder.n_areas), dtype=np.int64)
    for i, row in enumerate(rows):
        areas[i] = row[3]
    return EpisodeRecords(np.array([r[0] for r in rows], dtype=np.float64),
                          np.array([r[1] for r in rows], dtype=np.int64),
                          np.array([r[2] for r in rows], dtype=np.bool_), areas)


def _every(every: int, checkpoint: Callable[[int], None] | None) -> Any:
    """A callback that calls ``checkpoint(steps done)`` after every ``every`` steps, at
    the start of the next rollout or the end of training: after the update that ends the
    step's rollout (PPO's ``n_steps``, DQN's ``train_freq``), so the last checkpoint sees
    the trained network."""
    from stable_baselines3.common.callbacks import BaseCallback  # optional (sb3 extra)

    class Every(BaseCallback):
        pending: int | None = None

        def _on_step(self) -> bool:
            if every and checkpoint is not None and self.num_timesteps % every == 0:
                self.pending = self.num_timesteps
            return True

        def _flush(self) -> None:
            if self.pending is not None and checkpoint is not None:
                checkpoint(self.pending)
            self.pending = None

        def _on_rollout_start(self) -> None:
            self._flush()

        def _on_training_end(self) -> None:
            self._flush()

    return Every()


def _stopper(recorder: _Recorder, n_episodes: int) -> Any:
    """A callback that stops ``learn`` when ``recorder`` has ``n_episodes`` rows."""
    from stable_baselines3.common.callbacks import BaseCallback  # optional (sb3 extra)

    class Stop(BaseCallback):
        def _on_step(self) -> bool:
            return len(recorder.rows) < n_episodes

    return Stop()


class MaskablePPO(DeepLearner):
    """sb3-contrib's MaskablePPO: PPO that draws only the env's allowed actions."""

    agent = "MaskablePPO"
    config_type = PPOConfig


class PPO(DeepLearner):
    """Stable-Baselines3's PPO (every action open to it)."""

    agent = "PPO"
    config_type = PPOConfig


class DQN(DeepLearner):
    """Stable-Baselines3's DQN (every action open to it)."""

    agent = "DQN"
    config_type = DQNConfig
