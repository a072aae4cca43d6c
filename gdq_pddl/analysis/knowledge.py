"""Analysis of the wrong-knowledge experiments (``gdq-pddl knowledge``).

An output folder of :func:`gdq_pddl.experiments.knowledge.knowledge_experiments` holds,
per case, two experiments on the same *real* world: ``<case>--accurate`` (knowledge built
from the real world) and ``<case>--wrong`` (knowledge built from the case's knowledge
world). :func:`write_knowledge_report` measures, per case and method,

- **convergence**: per run, the first episode at which the trailing
  :data:`WINDOW`-episode mean return reaches ``V* - (1 - FRACTION) |V*|`` (85% of V*
  when V* > 0); a run that never reaches it never converged. A method's convergence
  episode is the median over runs (unconverged runs count as later than any episode, so
  the median is "never" when half the runs did not converge); the extra episodes are
  wrong-knowledge median minus accurate median. Why "reaches" and not "stays above until
  the end": with epsilon-greedy exploration a run's moving average keeps dipping (one
  stuck episode costs ~30), so "stays" measured mostly the date of the last dip; on the
  control case (identical knowledge, other seeds) it differed by 100-250 episodes between
  the two halves of the comparison, the first-passage time by 10-35. Why 85%: exploration
  (epsilon 0.1 over 95 actions, most of them useless) costs about 10% of V* even with
  the optimal greedy policy. Whether a method ends at the optimum is judged by its final
  greedy policy (next item), not by this threshold.
- **the final greedy policy**: walked along likeliest outcomes in the real world
  (:func:`~gdq_pddl.analysis.routes.walk_policy`), and whether its area route is the
  area route of the true optimal policy (value iteration on the real world); also its
  exact expected return in the real world (finite-horizon policy evaluation) over V*.
- **DARLING's allowed set** along the true optimal route: at each step, whether some
  optimal action (within 1e-9 of the best Q*) starts a plan within DARLING's tolerance
  from that learner state (``darling_plans.first_actions``; every action where the state
  has no plan). The same check for GDQ's plans: does an optimal action start a shortest
  plan (H of the paper variant) / a plan within 1.3x (H of the authors' code)?

Nothing in the report is typed in: every sentence is generated from these measurements.
"""

from __future__ import annotations

import json
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from gdq_pddl.analysis.routes import optimal_route, walk_policy
from gdq_pddl.envs.model import ModelArrays, compile_model, full_state
from gdq_pddl.envs.solve import expected_costs, solve_task
from gdq_pddl.world import Task, World

WINDOW = 100
"""Moving-average window (episodes) of the convergence criterion."""
CURVE_WINDOW = 50
"""Moving-average window (episodes) of the learning curves."""
FRACTION = 0.85
"""Convergence threshold: V* - (1 - FRACTION) |V*|."""
FINAL = 100
"""Episodes at the end over which the final mean return is reported."""
ACCURATE, WRONG = "accurate", "wrong"


def threshold(v_star: float, fraction: float = FRACTION) -> float:
    """The return level a converged learner's moving average stays at or above."""
    return v_star - (1.0 - fraction) * abs(v_star)


def moving_average(returns: np.ndarray, window: int = WINDOW) -> np.ndarray:
    """Trailing means over ``window`` episodes; entry i covers episodes i+1 .. i+window
    (1-based), so its episode number is ``i + window``. Works on [episodes] or
    [runs, episodes]."""
    x = np.asarray(returns, dtype=np.float64)
    w = min(window, x.shape[-1])
    c = np.cumsum(x, axis=-1)
    c = np.concatenate([np.zeros((*x.shape[:-1], 1)), c], axis=-1)
    return (c[..., w:] - c[..., :-w]) / w


def convergence_episode(returns: np.ndarray, level: float, window: int = WINDOW) -> int | None:
    """First episode (1-based) at which the trailing ``window``-episode mean return is
    >= ``level``; None if it never is."""
    ma = moving_average(returns, window)
    hits = np.flatnonzero(ma >= level)
    return None if hits.size == 0 else int(hits[0]) + min(window, len(returns))


def median_episode(episodes: list[int | None]) -> float:
    """Median over runs with unconverged runs as +inf (inf: most runs never converged)."""
    if not episodes:
        return float("nan")
    return float(np.median([np.inf if e is None else e for e in episodes]))


def policy_value(world: World, task: Task, policy: dict[int, int] | np.ndarray,
                 model: ModelArrays | None = None) -> float:
    """Exact expected undiscounted return from the start of a stationary learner policy
    (learner state -> action) in ``world``, by backward induction over the step limit
    (the same outcome rewards as :func:`gdq_pddl.envs.solve.solve`)."""
    model = compile_model(world) if model is None else model
    n_actions, limit, r = model.n_actions, model.step_limit, model.r_max
    n_full = model.obs_of.shape[0]
    if isinstance(policy, dict):
        pi = np.zeros(int(model.obs_of.max()) + 1, dtype=np.int64)
        for s, a in policy.items():
            pi[s] = a
    else:
        pi = np.asarray(policy, dtype=np.int64)
    act = pi[model.obs_of]
    pairs = np.arange(n_full) * n_actions + act
    lo, hi = model.ptr[pairs], model.ptr[pairs + 1]
    owner = np.repeat(np.arange(n_full), hi - lo)
    k = np.concatenate([np.arange(a, b) for a, b in zip(lo, hi, strict=True)])
    prob, nxt, stuck = model.prob[k], model.next[k], model.stuck[k]
    goal_pos = world.index[task.goal]
    at_goal = model.pos_of[nxt] == goal_pos
    ending = stuck | at_goal
    end_reward = np.where(stuck, -r, np.where(at_goal, r, -r))
    cost = expected_costs(model)[act[owner]]
    goal_states = model.pos_of == goal_pos
    v = np.zeros(n_full)
    for t in range(limit - 1, -1, -1):
        value = end_reward if t == limit - 1 else np.where(ending, end_reward, -cost + v[nxt])
        v = np.where(goal_states, 0.0, np.bincount(owner, prob * value, minlength=n_full))
    return float(v[full_state(world, task.start)])


@dataclass(frozen=True)
class RouteStep:
    """One step of the true optimal route and what the knowledge allows there."""

    state: str
    optimal: tuple[str, ...]
    """Optimal actions (ties within 1e-9) at this step."""
    darling_allowed: bool
    in_shortest_plans: bool
    in_tolerant_plans: bool


def route_check(real: World, knowledge: World, task: Task,
                darling_tolerance: float = 0.3) -> list[RouteStep]:
    """Along the likeliest route of the true optimal policy in ``real``: are the optimal
    actions in DARLING's allowed set / in GDQ's plans, with knowledge from ``knowledge``?"""
    from gdq_pddl.learners.context import office_task_context
    from gdq_pddl.spaces import LearnerSpaces

    ctx = office_task_context(knowledge, task, darling_tolerance=darling_tolerance)
    allowed = np.array(ctx.darling_plans.first_actions, dtype=np.bool_, copy=True)
    allowed[~allowed.any(axis=1)] = True  # DARLING: every action where there is no plan
    shortest = ctx.plans.first_actions
    tolerant = ctx.darling_plans.first_actions
    model = compile_model(real)
    solution, fs = solve_task(real, task, model)
    spaces = LearnerSpaces(real)
    out: list[RouteStep] = []
    for t in range(model.step_limit):
        obs = int(model.obs_of[fs])
        q = solution.Q[t, fs]
        best = np.flatnonzero(q >= q.max() - 1e-9)
        out.append(RouteStep(
            state=spaces.state_name(obs),
            optimal=tuple(spaces.action_name(int(a)) for a in best),
            darling_allowed=bool(allowed[obs, best].any()),
            in_shortest_plans=bool(shortest[obs, best].any()),
            in_tolerant_plans=bool(tolerant[obs, best].any())))
        i = fs * model.n_actions + int(solution.policy[t, fs])
        lo, hi = model.ptr[i], model.ptr[i + 1]
        k = lo + int(np.argmax(model.prob[lo:hi]))
        if model.stuck[k]:
            break
        fs = int(model.next[k])
        if model.pos_of[fs] == solution.goal_pos:
            break
    return out


@dataclass
class MethodResult:
    """One method in one experiment (accurate or wrong knowledge) of a case."""

    runs: int
    episodes: int
    convergence: list[int | None]
    final_return: float
    """Mean return over the last :data:`FINAL` episodes and all runs."""
    on_route: int
    """Runs whose final greedy policy follows the optimal area route to the goal."""
    policy_values: list[float]
    routes: list[tuple[int, ...]]
    curve: np.ndarray
    """Mean over runs of the trailing moving average (episode numbers CURVE_WINDOW..n)."""

    @property
    def converged(self) -> int:
        return sum(e is not None for e in self.convergence)

    @property
    def median(self) -> float:
        return median_episode(self.convergence)


@dataclass
class CaseResult:
    name: str
    description: str
    real: str
    knowledge: str
    task: Task
    v_star: float
    optimal_positions: tuple[str, ...]
    optimal_areas: tuple[int, ...]
    methods: list[str]
    results: dict[str, dict[str, MethodResult]]
    """``{ACCURATE|WRONG: {method: MethodResult}}``."""
    checks: dict[str, list[RouteStep]]
    """``{ACCURATE|WRONG: route check}``."""


def _experiments(out: Path) -> dict[str, dict]:
    cfg = json.loads((out / "config.json").read_text(encoding="utf-8"))
    return {e["name"]: e for e in cfg.get("experiments", [])}


def analyse(out: str | Path) -> list[CaseResult]:
    """Measure every case of an output folder of ``gdq-pddl knowledge``."""
    from gdq_pddl.analysis.data import load_episodes, load_policies
    from gdq_pddl.experiments.knowledge import CASES, knowledge_world
    from gdq_pddl.experiments.work import load_world_named, resolve_task

    out = Path(out)
    exps = _experiments(out)
    episodes = load_episodes(out / "episodes.csv")
    policies = load_policies(out)
    grouped = policies.grouped() if policies is not None else {}
    described = {c.name: c.description for c in CASES}
    names = sorted({n.rsplit("--", 1)[0] for n in exps if n.endswith(("--accurate", "--wrong"))},
                   key=lambda n: (list(described).index(n) if n in described else 99, n))
    cases = []
    for name in names:
        acc, wrong = exps.get(f"{name}--{ACCURATE}"), exps.get(f"{name}--{WRONG}")
        if acc is None or wrong is None:
            continue
        real = load_world_named(wrong["world"])
        kworld = knowledge_world(real, wrong.get("knowledge"))
        task = resolve_task(real, wrong["schedule"][0][0])
        route = optimal_route(real, task)
        model = compile_model(real)
        solution, s0 = solve_task(real, task, model)
        v_star = float(solution.V[0, s0])
        level = threshold(v_star)
        results: dict[str, dict[str, MethodResult]] = {}
        methods = [m for m in wrong["methods"] if m in acc["methods"]]
        for kind, exp in ((ACCURATE, acc), (WRONG, wrong)):
            results[kind] = {}
            for m in methods:
                returns = episodes.matrix("return", exp["name"], m)
                if returns.size == 0:
                    continue
                pols = [grouped.get((exp["name"], m, task.name, r)) for r in range(len(returns))]
                walks = [walk_policy(real, p, task.start, task.goal) for p in pols if p]
                results[kind][m] = MethodResult(
                    runs=len(returns), episodes=returns.shape[1],
                    convergence=[convergence_episode(row, level) for row in returns],
                    final_return=float(np.mean(returns[:, -FINAL:])),
                    on_route=sum(w.reached_goal and w.areas(real) == route.areas(real)
                                 for w in walks),
                    policy_values=[policy_value(real, task, p, model) for p in pols if p],
                    routes=[w.areas(real) if w.reached_goal else () for w in walks],
                    curve=moving_average(returns, CURVE_WINDOW).mean(axis=0))
        checks = {ACCURATE: route_check(real, real, task),
                  WRONG: route_check(real, kworld, task)}
        cases.append(CaseResult(
            name=name, description=described.get(name, ""), real=wrong["world"],
            knowledge=str(wrong.get("knowledge") or wrong["world"]), task=task, v_star=v_star,
            optimal_positions=route.positions, optimal_areas=route.areas(real),
            methods=methods, results=results, checks=checks))
    return cases


# --- figures ----------------------------------------------------------------------------

def _colour(method: str) -> str:
    try:
        from gdq_pddl.analysis.figures import method_colour

        return method_colour(method)
    except Exception:  # pragma: no cover - a figure colour is never worth failing over
        return "#333333"


def write_figures(cases: list[CaseResult], out: Path) -> list[Path]:
    """Learning curves per case (wrong solid, accurate dashed, V* and the convergence
    threshold) and a bar chart of convergence episodes per method and case."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    paths: list[Path] = []
    if not cases:
        return paths
    n = len(cases)
    cols = min(2, n)
    rows = -(-n // cols)
    fig, axes = plt.subplots(rows, cols, figsize=(6.2 * cols, 4.0 * rows), squeeze=False,
                             layout="constrained")
    for ax, case in zip(axes.ravel(), cases, strict=False):
        for m in case.methods:
            for kind, style in ((WRONG, "-"), (ACCURATE, "--")):
                r = case.results[kind].get(m)
                if r is None:
                    continue
                x = np.arange(len(r.curve)) + min(CURVE_WINDOW, r.episodes)
                ax.plot(x, r.curve, style, color=_colour(m), lw=1.2 if kind == WRONG else 0.9,
                        label=f"{m} ({kind})")
        ax.axhline(case.v_star, color="black", lw=1, ls=":", label="V* (real world)")
        ax.axhline(threshold(case.v_star), color="grey", lw=0.8, ls="-.",
                   label="convergence threshold")
        lo = min(case.v_star, threshold(case.v_star))
        ax.set_ylim(max(-40.0, lo - 25.0), max(case.v_star, 0.0) + 4.0)
        ax.set_title(f"{case.name}: task {case.task.name} ({case.task.start}->{case.task.goal})",
                     fontsize=10)
        ax.set_xlabel("episode")
        ax.set_ylabel(f"return, {CURVE_WINDOW}-episode mean over runs")
    for ax in axes.ravel()[n:]:
        ax.set_visible(False)
    handles, labels = axes.ravel()[0].get_legend_handles_labels()
    fig.legend(handles, labels, loc="outside lower center", ncol=4, fontsize=8)
    for ext in ("png", "pdf"):
        fig.savefig(out / f"knowledge_curves.{ext}", dpi=120)
        paths.append(out / f"knowledge_curves.{ext}")
    plt.close(fig)

    methods = list(dict.fromkeys(m for c in cases for m in c.methods))
    fig, axes = plt.subplots(1, n, figsize=(max(3.2 * n, 6), 3.8), squeeze=False,
                             layout="constrained")
    for ax, case in zip(axes.ravel(), cases, strict=True):
        episodes = max((r.episodes for k in case.results.values() for r in k.values()),
                       default=1)
        x = np.arange(len(methods))
        for j, (kind, hatch) in enumerate(((ACCURATE, "//"), (WRONG, ""))):
            for i, m in enumerate(methods):
                r = case.results[kind].get(m)
                if r is None:
                    continue
                med = r.median
                never = not np.isfinite(med)
                ax.bar(x[i] + (j - 0.5) * 0.38, episodes if never else med, width=0.38,
                       color="white" if never else _colour(m), edgecolor=_colour(m),
                       hatch="xx" if never else hatch, lw=1)
        ax.set_xticks(x, methods, rotation=45, ha="right", fontsize=8)
        ax.set_title(case.name, fontsize=10)
        ax.set_ylim(0, episodes * 1.05)
    axes.ravel()[0].set_ylabel("convergence episode (median of runs)")
    fig.suptitle("left bar of each pair (hatched //): accurate knowledge; right: wrong "
                 "knowledge; crossed white bar: never converged", fontsize=8)
    for ext in ("png", "pdf"):
        fig.savefig(out / f"knowledge_convergence.{ext}", dpi=120)
        paths.append(out / f"knowledge_convergence.{ext}")
    plt.close(fig)
    return paths


# --- report -----------------------------------------------------------------------------

def _ep(value: float) -> str:
    if np.isnan(value):
        return "n/a"
    return "never" if not np.isfinite(value) else f"{value:.0f}"


def _extra(acc: MethodResult | None, wrong: MethodResult | None) -> str:
    if acc is None or wrong is None:
        return "n/a"
    a, w = acc.median, wrong.median
    if np.isfinite(a) and np.isfinite(w):
        return f"{w - a:+.0f}"
    if np.isfinite(a):
        return "never converges"
    if np.isfinite(w):
        return "converges only with wrong knowledge"
    return "neither converges"


def _frac(values: list[float], v_star: float) -> str:
    if not values:
        return "n/a"
    m = float(np.mean(values))
    return f"{m / v_star:.2f}" if v_star > 0 else f"{m:.2f}"


def _route_summary(r: MethodResult) -> str:
    counts: dict[tuple[int, ...], int] = {}
    for route in r.routes:
        counts[route] = counts.get(route, 0) + 1
    parts = [f"{'-'.join(map(str, k)) if k else 'no goal'} x{v}"
             for k, v in sorted(counts.items(), key=lambda kv: -kv[1])]
    return ", ".join(parts) or "n/a"


def _check_summary(steps: list[RouteStep], attr: str) -> str:
    missing = [f"{s.state} ({' / '.join(s.optimal)})" for s in steps if not getattr(s, attr)]
    if not missing:
        return "yes, at every step"
    return "no, not at " + "; ".join(missing)


def _findings(case: CaseResult) -> list[str]:
    out = []
    for m in case.methods:
        a, w = case.results[ACCURATE].get(m), case.results[WRONG].get(m)
        if a is None or w is None:
            continue
        out.append(
            f"**{m}**: greedy policy on the optimal route in {w.on_route}/{w.runs} runs with "
            f"wrong knowledge, {a.on_route}/{a.runs} with accurate; converged in "
            f"{w.converged}/{w.runs} vs {a.converged}/{a.runs} runs (median episode "
            f"{_ep(w.median)} vs {_ep(a.median)}: {_extra(a, w)}).")
    steps = case.checks[WRONG]
    excluded = [s for s in steps if not s.darling_allowed]
    if excluded:
        out.append("DARLING's allowed set (wrong knowledge) excludes every optimal action at "
                   + ", ".join(s.state for s in excluded) + ".")
    else:
        out.append("DARLING's allowed set (wrong knowledge) contains an optimal action at "
                   "every step of the optimal route.")
    return out


def write_report(cases: list[CaseResult], out: Path, command: str = "gdq-pddl knowledge"
                 ) -> Path:
    """``REPORT.md``: per case the measurements described in the module docstring."""
    lines = [
        "# Knowledge that disagrees with the world",
        "",
        f"Command: `{command}`. The env simulates the *real* world; the learners' knowledge "
        "(PDDL problem, plans) is built from the *knowledge* world. Each case is run twice on "
        "the same real world: with wrong knowledge, and with accurate knowledge (built from "
        "the real world) as the reference. V* and the optimal route come from value "
        "iteration on the real world.",
        "",
        "Definitions (measured, see `gdq_pddl/analysis/knowledge.py`):",
        "",
        f"- *converged at episode e*: e is the first episode at which the trailing {WINDOW}"
        f"-episode mean return of a run reaches V* - {1 - FRACTION:.2f} |V*| (first passage; "
        "'stays above until the end' measured mostly the last exploration dip). The median "
        "is over runs, unconverged runs counting as 'never'; *extra* = median with wrong "
        "knowledge - median with accurate knowledge. The control case's extra episodes "
        "show the noise of this comparison.",
        "- *on route*: the final greedy policy, walked along likeliest outcomes in the real "
        "world, reaches the goal along the optimal policy's area route.",
        "- *policy value*: the exact expected return of the final greedy policy in the real "
        "world, as a fraction of V* (the raw value when V* <= 0).",
        f"- *final return*: mean return of the last {FINAL} episodes over all runs.",
        "",
        "Figures: `knowledge_curves.png` (learning curves; solid: wrong knowledge, dashed: "
        "accurate), `knowledge_convergence.png` (convergence episodes).",
        "",
    ]
    for case in cases:
        lines += [
            f"## {case.name}",
            "",
            case.description + "." if case.description else "",
            "",
            f"- real world `{case.real}`, knowledge world `{case.knowledge}`, task "
            f"{case.task.name} ({case.task.start} -> {case.task.goal})",
            f"- V* = {case.v_star:.3f}; convergence threshold {threshold(case.v_star):.3f}",
            f"- optimal route: {' '.join(case.optimal_positions)} (areas "
            f"{'-'.join(map(str, case.optimal_areas))})",
            "",
            "| method | on route (wrong / accurate) | converged runs | median convergence "
            "episode | extra episodes | policy value | final return | greedy routes (wrong) |",
            "|---|---|---|---|---|---|---|---|",
        ]
        for m in case.methods:
            a, w = case.results[ACCURATE].get(m), case.results[WRONG].get(m)
            if a is None or w is None:
                continue
            lines.append(
                f"| {m} | {w.on_route}/{w.runs} / {a.on_route}/{a.runs} | "
                f"{w.converged} / {a.converged} | {_ep(w.median)} / {_ep(a.median)} | "
                f"{_extra(a, w)} | {_frac(w.policy_values, case.v_star)} / "
                f"{_frac(a.policy_values, case.v_star)} | {w.final_return:.2f} / "
                f"{a.final_return:.2f} | {_route_summary(w)} |")
        lines += ["", "(pairs are wrong knowledge / accurate knowledge)", "",
                  "Does the knowledge contain the true optimum? Along the optimal route:", "",
                  "| knowledge | DARLING allows an optimal action | an optimal action starts a "
                  "shortest plan (GDQ) | ... a plan within 1.3x (GDQ-code) |",
                  "|---|---|---|---|"]
        for kind in (WRONG, ACCURATE):
            steps = case.checks[kind]
            lines.append(f"| {kind} | {_check_summary(steps, 'darling_allowed')} | "
                         f"{_check_summary(steps, 'in_shortest_plans')} | "
                         f"{_check_summary(steps, 'in_tolerant_plans')} |")
        lines += ["", "Findings:", ""] + [f"- {f}" for f in _findings(case)] + [""]
    path = out / "REPORT.md"
    path.write_text("\n".join(lines), encoding="utf-8")
    return path


def make_knowledge_report(out: str | Path, command: str = "gdq-pddl knowledge") -> list[Path]:
    """Analyse ``out`` and write its figures and ``REPORT.md``; returns the paths."""
    out = Path(out)
    cases = analyse(out)
    paths = write_figures(cases, out)
    paths.append(write_report(cases, out, command))
    return paths
