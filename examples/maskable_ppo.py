"""Deep RL on the planner's knowledge: sb3-contrib's MaskablePPO beside GDQ on Task C.

What it shows: ``gdq_pddl/Office-v0`` needs no wrapper for MaskablePPO: the env answers
``action_masks()`` with the actions the robot's PDDL knowledge says can do something
(the same mask GDQ's ``info["action_mask"]`` carries). Both methods learn on Task C with
the same seeds; every ``--eval-every`` environment steps (GDQ: at the end of the episode
that gets there), each one's greedy policy runs
``--eval-episodes`` episodes on an evaluation env (the same seed for both), and the
script prints the environment steps each needed to reach ``--target`` greedy success,
and its success at the end. Needs ``pip install 'gdq_pddl[sb3]'`` (sb3-contrib, torch;
docs/python.md says how to get the CPU-only torch).

``--knowledge`` gives MaskablePPO more of the knowledge through the wrappers of
:mod:`gdq_pddl.wrappers` (docs/python.md): ``shaping`` (potential-based shaping from the
goal distance, PPO's gamma), ``facts`` (the true state's atoms as a ``MultiBinary``
instead of a state index) or ``distance`` (the goal distance and the plan's first
action beside the state: a ``Dict``, so ``MultiInputPolicy``).

    python examples/maskable_ppo.py --steps 30000 --seeds 0 1 2
    python examples/maskable_ppo.py --steps 30000 --knowledge shaping

The measured comparison (MaskablePPO, PPO and DQN, each plain, shaped and seeing the
facts, against GDQ and Q-shaping on Task C and PDDL problems; IQM over 5 seeds with 95%
intervals) is one command, ``python benchmarks/deep_rl.py``, and its table and figure
are in docs/results/deep-rl.md.
"""

from __future__ import annotations

import argparse
import sys
from collections.abc import Callable
from typing import Any

import gymnasium
import numpy as np

import gdq_pddl  # noqa: F401  (registers the envs)
from gdq_pddl.learners import GDQ, office_task_context, run_episodes
from gdq_pddl.wrappers import DistanceObservation, FactObservation, KnowledgeShaping

ENV_ID, TASK = "gdq_pddl/Office-v0", "C"
Policy = Callable[[Any, np.ndarray], int]  # (observation, mask) -> action
KNOWLEDGE: dict[str, Callable[[gymnasium.Env], gymnasium.Env]] = {
    "none": lambda env: env,  # the mask alone (the env's action_masks())
    "shaping": lambda env: KnowledgeShaping(env, gamma=0.99, potential="distance"),
    "facts": FactObservation,
    "distance": DistanceObservation}
"""What MaskablePPO's env is wrapped in, by ``--knowledge``."""


def make_env(knowledge: str = "none") -> gymnasium.Env:
    """Task C's env, in the wrapper ``knowledge`` names (:data:`KNOWLEDGE`)."""
    return KNOWLEDGE[knowledge](gymnasium.make(ENV_ID, task=TASK))


def greedy_success(policy: Policy, episodes: int, seed: int, knowledge: str = "none") -> float:
    """The share of ``episodes`` evaluation episodes in which ``policy`` reaches the goal
    (its observations as ``knowledge``'s wrapper gives them)."""
    env = make_env(knowledge)
    obs, _ = env.reset(seed=seed)
    masks, wins = env.get_wrapper_attr("action_masks"), 0
    for _ in range(episodes):
        done = False
        while not done:
            obs, _, terminated, truncated, info = env.step(policy(obs, masks()))
            done = terminated or truncated
        wins += info["cause"] == "goal"
        obs, _ = env.reset()
    return wins / episodes


def learn_gdq(seed: int, steps: int, every: int, evaluate: Callable[[Policy], float]):
    """GDQ's greedy success after about every ``every`` steps: ``[(steps, success)]``."""
    env = gymnasium.make(ENV_ID, task=TASK)
    office = env.unwrapped
    learner = GDQ(office_task_context(office.world, office.task))
    env.reset(seed=seed)
    rng, done, curve = np.random.default_rng(seed), 0, []
    while done < steps:
        done += int(run_episodes(learner, env, 1, rng).steps.sum())
        if done >= every * (len(curve) + 1) or done >= steps:
            greedy = learner.greedy_policy()
            curve.append((done, evaluate(lambda obs, mask, q=greedy: int(q[obs]))))
    return curve


def learn_ppo(seed: int, steps: int, every: int, evaluate: Callable[[Policy], float],
              knowledge: str = "none"):
    """MaskablePPO's (default settings) greedy success every ``every`` steps, its env
    wrapped as ``knowledge`` says."""
    import torch  # optional dependency (the [sb3] extra)
    from sb3_contrib import MaskablePPO  # optional dependency (the [sb3] extra)

    torch.set_num_threads(1)  # small networks: one core is enough, and fairer to others
    policy = "MultiInputPolicy" if knowledge == "distance" else "MlpPolicy"
    model = MaskablePPO(policy, make_env(knowledge), seed=seed, device="cpu")
    curve: list[tuple[int, float]] = []

    def greedy(obs: Any, mask: np.ndarray) -> int:
        return int(model.predict(obs, action_masks=mask, deterministic=True)[0])

    def check(*_) -> bool:  # called after every step of the rollouts
        if model.num_timesteps % every == 0:
            curve.append((model.num_timesteps, evaluate(greedy)))
        return True

    model.learn(steps, callback=check)  # whole rollouts of 2048 steps: may run past steps
    if not curve or curve[-1][0] != model.num_timesteps:
        curve.append((model.num_timesteps, evaluate(greedy)))
    return curve


def main(steps: int, eval_every: int, eval_episodes: int, target: float,
         seeds: list[int], knowledge: str = "none") -> dict[str, list[tuple[int | None, float]]]:
    try:
        import sb3_contrib  # noqa: F401  optional dependency (the [sb3] extra)
    except ImportError:
        sys.exit("this example needs sb3-contrib and torch: pip install 'gdq_pddl[sb3]'")
    ppo = "MaskablePPO" if knowledge == "none" else f"MaskablePPO+{knowledge}"
    out: dict[str, list[tuple[int | None, float]]] = {"GDQ": [], ppo: []}
    print(f"Task C; greedy success over {eval_episodes} episodes every {eval_every} steps; "
          f"steps to {target:.0%}")
    for seed in seeds:
        for name in ("GDQ", ppo):
            seen = "none" if name == "GDQ" else knowledge  # what the policy observes

            def evaluate(policy: Policy, seed: int = seed, seen: str = seen) -> float:
                return greedy_success(policy, eval_episodes, 10_000 + seed, seen)

            curve = (learn_gdq(seed, steps, eval_every, evaluate) if name == "GDQ" else
                     learn_ppo(seed, steps, eval_every, evaluate, knowledge))
            reached = next((n for n, success in curve if success >= target), None)
            out[name].append((reached, curve[-1][1]))
            print(f"seed {seed} {name:<12} steps to {target:.0%}: "
                  f"{reached if reached is not None else f'not in {curve[-1][0]}':>8}   "
                  f"final success {curve[-1][1]:.0%} after {curve[-1][0]} steps", flush=True)
    return out


if __name__ == "__main__":
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--steps", type=int, default=30_000)
    parser.add_argument("--eval-every", type=int, default=500)
    parser.add_argument("--eval-episodes", type=int, default=100)
    parser.add_argument("--target", type=float, default=0.9)
    parser.add_argument("--seeds", type=int, nargs="+", default=[0])
    parser.add_argument("--knowledge", choices=list(KNOWLEDGE), default="none",
                        help="what MaskablePPO's env is wrapped in (default: the mask only)")
    main(**vars(parser.parse_args()))
