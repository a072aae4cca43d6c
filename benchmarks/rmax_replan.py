"""R-max's replanning before and after it skipped the states without a known pair.

    python benchmarks/rmax_replan.py                     # Task C, 2 runs x 100 episodes
    python benchmarks/rmax_replan.py --domain D.pddl --problem P.pddl --runs 2
    python benchmarks/rmax_replan.py --method R-max-shaping --episodes 300

R-max (``gdq_pddl.learners.rmax``) runs value iteration each time a pair becomes known.
``plan_known`` used to visit every state in every sweep; it now visits only the states
with a known pair, kept between plans (every state in a first sweep only after the tables
changed outside planning): a state without one does not change once visited. "before"
here is the every-state sweep, compiled from this file, in a learner that is R-max in all
else; "after" is the package's learner. Both
learn the same runs (env seeded ``run``, the learner's draws from ``run``), taking turns
run by run, so a loaded machine slows both alike; the script checks that each run's
returns, steps and final Q table are the same bytes, and prints the seconds of learning
(compiling excluded: a 2-episode warm-up of each first).
"""

from __future__ import annotations

import argparse
import time
from typing import Any

import numba
import numpy as np

from gdq_pddl.learners.learned_model import learned_value, record
from gdq_pddl.learners.rmax import RMax, RMaxShaping
from gdq_pddl.learners.tables import Model, Params, QTable


@numba.njit(cache=False)
def plan_every_state(table: QTable, model: Model, own: Any, p: Params, tolerance: float,
                     max_sweeps: int) -> int:
    """``plan_known`` as it was: Gauss-Seidel value iteration visiting every state in
    every sweep."""
    q, v, allowed, goal = table.q, table.v, table.allowed, table.goal
    n_states, n_actions = q.shape
    done = 0
    for _ in range(max_sweeps):
        done += 1
        change = 0.0
        for s in range(n_states):
            if goal[s]:
                continue
            best = -np.inf
            for a in range(n_actions):
                if not allowed[s, a]:
                    continue
                if model.visits[s, a] > p.m:
                    x = learned_value(model.slots, model.stuck, model.visits, model.cost_sum,
                                      model.cost_n, model.cost_all, goal, v, p, s, a)
                else:
                    x = own.unknown[s]
                change = max(change, abs(x - q[s, a]))
                q[s, a] = x
                best = max(best, x)
            v[s] = best
        if change <= tolerance:
            break
    own.sweeps[0] += done
    return done


@numba.njit(cache=False)
def observe_every_state(table: QTable, model: Model, plans: Any, prior: Any, queue: Any,
                        own: Any, p: Params, s: int, a: int, r: float, s2: int,
                        terminated: bool, truncated: bool, rng: np.random.Generator) -> bool:
    """R-max's ``observe`` with :func:`plan_every_state`."""
    if not record(model, table.goal, p, s, a, r, s2, terminated, truncated):
        return False
    if model.visits[s, a] == p.m + 1:
        plan_every_state(table, model, own, p, p.sweep_threshold, p.n_backups)
    return True


def every_state(cls: type[RMax]) -> type[RMax]:
    """``cls`` (R-max or R-max-shaping) planning with :func:`plan_every_state`."""

    class EveryState(cls):  # type: ignore[misc, valid-type]
        observe_rule = staticmethod(observe_every_state)
        loop_rules = None  # its own rules: the episode loop is a copy calling them

        def _init_task(self) -> None:
            t = self.tables
            self._revalue_rows(np.arange(len(self.q)))
            plan_every_state(t.table, t.model, t.own, self.params, self.config.tolerance,
                             self.config.max_sweeps)

    EveryState.__name__ = f"{cls.__name__}EveryState"
    return EveryState


def context_and_env(task: str, domain: str | None, problem: str | None):
    """The learners' context and an env: the office's ``task``, or a PDDL problem's."""
    if domain is None:
        import gymnasium

        import gdq_pddl  # noqa: F401  (registers the env)
        from gdq_pddl.learners import office_task_context
        env = gymnasium.make("gdq_pddl/Office-v0", task=task)
        return office_task_context(env.unwrapped.world, env.unwrapped.task), env
    from gdq_pddl.envs.pddl_env import PDDLEnv
    from gdq_pddl.experiments.protocol import Experiment, ProblemSpec
    from gdq_pddl.experiments.work import context_of, instance_of
    exp = Experiment("rmax-replan", ((problem, 1),), methods=("R-max",), world="pddl",
                     pddl=ProblemSpec(domain, problem))
    instance = instance_of(exp, problem, RMaxShaping)
    return context_of(exp, instance), PDDLEnv(instance=instance)


def main() -> None:
    from gdq_pddl.learners import make_learner, run_episodes
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--task", default="C")
    parser.add_argument("--domain", help="a PDDL domain file (with --problem)")
    parser.add_argument("--problem", help="a PDDL problem file")
    parser.add_argument("--method", nargs="+", default=["R-max", "R-max-shaping"])
    parser.add_argument("--runs", type=int, default=2)
    parser.add_argument("--episodes", type=int, default=100)
    args = parser.parse_args()
    ctx, env = context_and_env(args.task, args.domain, args.problem)
    where = args.problem or f"Task {args.task}"
    for method in args.method:
        after = make_learner(method, ctx)
        before_cls = every_state(type(after))
        seconds = {"before": [], "after": []}
        for run in [-1, *range(args.runs)]:  # -1: the warm-up (compiling)
            recs, qs = {}, {}
            for label in ("before", "after"):
                learner = before_cls(ctx, after.config) if label == "before" \
                    else make_learner(method, ctx)
                env.reset(seed=max(run, 0))
                t0 = time.perf_counter()
                recs[label] = run_episodes(learner, env, 2 if run < 0 else args.episodes,
                                           np.random.default_rng(max(run, 0)))
                if run >= 0:
                    seconds[label].append(time.perf_counter() - t0)
                qs[label] = learner.q.tobytes()
            same = (recs["before"].returns.tobytes() == recs["after"].returns.tobytes()
                    and recs["before"].steps.tobytes() == recs["after"].steps.tobytes()
                    and qs["before"] == qs["after"])
            if not same:
                raise SystemExit(f"{method} run {run}: before and after differ")
        b, a = sum(seconds["before"]), sum(seconds["after"])
        print(f"{where}, {method}, {args.runs} runs x {args.episodes} episodes: every state "
              f"{b:.2f} s, known states {a:.2f} s ({b / a:.1f} x); returns, steps and "
              f"final Q the same bytes", flush=True)


if __name__ == "__main__":
    main()
