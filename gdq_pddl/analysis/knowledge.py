"""Analysis of the wrong-knowledge experiments (``gdq-pddl knowledge``).

An output folder of :func:`gdq_pddl.experiments.knowledge.knowledge_experiments` holds,
per case, two experiments on the same *real* world: ``<case>--accurate`` (knowledge built
from the real world) and ``<case>--wrong`` (knowledge built from the case's knowledge
world). :func:`make_knowledge_report` measures, per case and method,

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
  has no plan). The same check for GDQ's prior (is an optimal action one the knowledge
  says can do something?) and plans: does an optimal action start a shortest plan (H of
  GDQ-literal) / a plan within 1.3x (H of GDQ-code)?

Nothing in the report is typed in: every sentence is generated from these measurements.

The measurements are in :mod:`.knowledge_measures`, the cases read from the folder in
:mod:`.knowledge_cases`, the figures in :mod:`.knowledge_figures` and the Markdown in
:mod:`.knowledge_markdown`; this module runs them.
"""

from __future__ import annotations

from pathlib import Path

from gdq_pddl.analysis.knowledge_cases import CaseResult, MethodResult, analyse
from gdq_pddl.analysis.knowledge_figures import write_figures
from gdq_pddl.analysis.knowledge_markdown import write_report
from gdq_pddl.analysis.knowledge_measures import (
    ACCURATE,
    CURVE_WINDOW,
    FINAL,
    FRACTION,
    WINDOW,
    WRONG,
    RouteStep,
    convergence_episode,
    median_episode,
    moving_average,
    policy_value,
    route_check,
    threshold,
)

__all__ = [
    "ACCURATE", "CURVE_WINDOW", "FINAL", "FRACTION", "WINDOW", "WRONG", "CaseResult",
    "MethodResult", "RouteStep", "analyse", "convergence_episode", "make_knowledge_report",
    "median_episode", "moving_average", "policy_value", "route_check", "threshold",
    "write_figures", "write_report",
]


def make_knowledge_report(out: str | Path, command: str = "gdq-pddl knowledge") -> list[Path]:
    """Analyse ``out`` and write its figures and ``REPORT.md``; returns the paths."""
    out = Path(out)
    cases = analyse(out)
    paths = write_figures(cases, out)
    paths.append(write_report(cases, out, command))
    return paths
