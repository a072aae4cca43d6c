"""Figure and REPORT.md of the scale experiment (:mod:`gdq_pddl.experiments.scale`)."""

from __future__ import annotations

from pathlib import Path

import numpy as np

from gdq_pddl.experiments.scale import FRACTION, TOLERANCE, WINDOW, SizeResult


def _median_conv(result: SizeResult, name: str) -> tuple[float | None, int]:
    """Median episodes to convergence over the converged runs, and how many converged."""
    done = [c for c in result.converged(name) if c is not None]
    return (float(np.median(done)) if done else None), len(done)


def figure(results: list[SizeResult], episodes: int, out: Path) -> list[Path]:
    """Episodes to convergence and env steps/s against size, per method (PNG + PDF)."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, (ax, bx) = plt.subplots(1, 2, figsize=(10, 4))
    names = list(dict.fromkeys(n for r in results for n in r.returns))
    for i, name in enumerate(names):
        xs, ys, open_x = [], [], []
        sx, sy = [], []
        for r in results:
            if name not in r.returns:
                continue
            med, _ = _median_conv(r, name)
            xs.append(r.positions)  # NaN breaks the line where a size did not converge
            ys.append(med if med is not None else np.nan)
            if med is None:
                open_x.append(r.positions)
            sx.append(r.positions)
            sy.append(r.steps_per_s[name])
        color = f"C{i}"
        ax.plot(xs, ys, "o-", color=color, label=name)
        ax.plot(open_x, [episodes * (1.02 + 0.02 * i)] * len(open_x), "o", color=color,
                fillstyle="none")
        bx.plot(sx, sy, "o-", color=color, label=name)
    ax.axhline(episodes, color="grey", lw=0.5, ls="--")
    ax.set(xscale="log", xlabel="positions", ylabel="episodes to convergence",
           title=f"open markers: not converged in {episodes} episodes")
    bx.set(xscale="log", yscale="log", xlabel="positions", ylabel="env steps / s (one core)")
    ax.legend(fontsize=8)
    fig.tight_layout()
    paths = [out / "scale.png", out / "scale.pdf"]
    for p in paths:
        fig.savefig(p)
    plt.close(fig)
    return paths


def report(results: list[SizeResult], runs: int, episodes: int, seed: int, out: Path) -> Path:
    """REPORT.md: the definitions, one table per size, and what was skipped."""
    lines = [
        "# Learning against building size", "",
        f"Generated buildings (`gdq-pddl building --positions N --seed {seed}`), task A, "
        f"{runs} run(s) x {episodes} episodes per method, compact model "
        "(`gdq_pddl.envs.compact`).", "",
        f"**Episodes to convergence**: the first episode at which the trailing {WINDOW}-"
        f"episode moving average of the return reaches R_fail + {FRACTION} (V_ref - R_fail); "
        "V_ref is the reference value (`gdq_pddl.envs.solve_compact`, a lower "
        "bound on V*), R_fail = -r_max - (step_limit - 1) the return of a timeout. "
        "Median over the runs that converged (count in brackets). Discount "
        f"gamma = 1 - 1/step_limit; DARLING and GDQ-code use door-route plans within "
        f"{1 + TOLERANCE:g} x the shortest (`gdq_pddl.abstraction.routes`); see "
        "`gdq_pddl/experiments/scale.py` for why.", "",
        "![episodes to convergence and steps/s](scale.png)", "",
    ]
    for r in results:
        lines += [f"## {r.positions} positions", "",
                  f"{r.doors} doors, {r.n_states} learner states x {r.n_actions} actions, "
                  f"shortest plan L = {r.plan_length}, step_limit = {r.step_limit}, "
                  f"r_max = {r.r_max:g}, V_ref = {r.v_ref:.1f}, R_fail = {r.r_fail:g}, "
                  f"threshold = {r.threshold:.1f}; plan tables for every state "
                  f"built in {r.context_s:.1f} s.", "",
                  "| method | episodes to convergence | mean return, last 100 | "
                  "success rate, last 100 | env steps/s |", "|---|---|---|---|---|"]
        for name in r.returns:
            med, n = _median_conv(r, name)
            conv = f"{med:.0f} ({n}/{runs})" if med is not None else f"> {episodes} (0/{runs})"
            last = r.returns[name][:, -100:]
            succ = r.success[name][:, -100:]
            lines.append(f"| {name} | {conv} | {last.mean():.1f} | {succ.mean():.2f} | "
                         f"{r.steps_per_s[name]:,.0f} |")
        for name, why in r.skipped.items():
            lines.append(f"| {name} | not run: {why} | | | |")
        lines.append("")
    path = out / "REPORT.md"
    path.write_text("\n".join(lines), encoding="utf-8")
    return path
