"""What every section of ``REPORT.md`` writes with: the options, the number formats, the
verdict bookkeeping (:class:`Verdicts`) and the line buffer (:class:`Writer`)."""

from __future__ import annotations

import math
from collections.abc import Callable, Sequence
from dataclasses import dataclass
from pathlib import Path

import jinja2
import numpy as np
import pandas as pd

from gdq_pddl.analysis.stats import HOLDS, Comparison, Milestone, compare, verdict, verdict_reason
from gdq_pddl.analysis.study import Study
from gdq_pddl.experiments.results import is_gdq
from gdq_pddl.learners import registry


@dataclass(frozen=True)
class ReportOptions:
    """Windows and thresholds of the report's statistics."""

    window: int = 50
    """Moving-average window (episodes) for milestones and curves."""
    early_window: int = 500
    """Hypothesis I also compares the mean return over the first this many episodes."""
    final_window: int = 250
    """Learning as a fraction of V*: mean return over the last this many episodes."""
    switch_window: int = 250
    """Hypothesis III: mean return over the first this many episodes after the switch."""
    route_window: int = 50
    route_share: float = 0.5
    """Task C convergence: from which episode at least this share of the last
    ``route_window`` episodes follow the best route successfully, to the end."""
    robot_window: int = 5
    robot_share: float = 0.6
    """Robot convergence: the same with a short window (30 trials)."""
    seed: int = 20240501


FIGURE_DIR, TABLE_DIR = "figures", "tables"


def number(x: float, digits: int = 2, sign: bool = False) -> str:
    """``x`` rounded to ``digits`` decimals (``sign``: always signed; NaN: ``n/a``)."""
    if x is None or math.isnan(x):
        return "n/a"
    return f"{x:+.{digits}f}" if sign else f"{x:.{digits}f}"


def fmt(x: float, digits: int = 3) -> str:
    return "n/a" if x is None or (isinstance(x, float) and math.isnan(x)) else f"{x:.{digits}g}"


def milestone_str(ms: Milestone) -> str:
    """A milestone on the mean curve, then in brackets the mean over the runs that reach
    it and how many do: ``55 (61.5; 4/5)``."""
    reached = [v for v in ms.per_run if not math.isnan(v)]
    mean = float(np.mean(reached)) if reached else math.nan
    return f"{fmt(ms.on_mean_curve, 5)} ({fmt(mean, 4)}; {len(reached)}/{len(ms.per_run)})"


def route_str(areas: Sequence[int]) -> str:
    return "->".join(map(str, areas)) if areas else "(none)"


def areas_str(areas: Sequence[int]) -> str:
    return ", ".join(map(str, areas)) or "none"


def pct(x: float) -> str:
    return "n/a" if math.isnan(x) else f"{x:.1%}"


VARIANT_NAMES = {e.name: e.label for e in registry.BUILT_IN if e.label}
"""How the verdict summary names the GDQ variants (the registry's labels)."""


def table_text(rows: Sequence[Sequence] | pd.DataFrame, columns: Sequence[str] = (),
               align: str = "") -> str:
    """Rows of cells (or a DataFrame) as a compact Markdown table, unpadded so that a line
    per row stays greppable (``| I | Task A | **holds** |``); ``align``: one ``l`` or
    ``r`` per column (default: every column left-aligned)."""
    frame = rows if isinstance(rows, pd.DataFrame) else pd.DataFrame(
        list(rows), columns=list(columns), dtype=object)
    return "\n".join(["| " + " | ".join(map(str, frame.columns)) + " |", "|" + "".join(
        "--:|" if a == "r" else "---|" for a in align or "l" * len(frame.columns)), *(
        "| " + " | ".join(map(str, row)) + " |" for row in frame.itertuples(index=False))])


TEMPLATES = jinja2.Environment(
    loader=jinja2.FileSystemLoader(Path(__file__).parent / "templates"), autoescape=False,
    trim_blocks=True, lstrip_blocks=True, keep_trailing_newline=True,
    undefined=jinja2.StrictUndefined)
"""The report prose: one Markdown template per report (``analysis/templates``)."""
TEMPLATES.filters["number"] = number


def render(template: str, **data) -> str:
    """The text of ``analysis/templates/<template>`` filled with ``data``."""
    return TEMPLATES.get_template(template).render(**data)


class Verdicts:
    """Each GDQ variant's verdict per hypothesis case, in the order the sections met them;
    ``gdq_runs``: whether the data hold a GDQ run at all (else: no verdicts, and why)."""

    COLUMNS = ["hypothesis", "case", "basis", "variant", "verdict", "reason"]

    def __init__(self, gdq_runs: bool = True) -> None:
        self.rows: list[tuple[str, ...]] = []
        self.gdq_runs = gdq_runs

    @property
    def frame(self) -> pd.DataFrame:
        return pd.DataFrame(self.rows, columns=self.COLUMNS)

    def counts(self) -> str:
        """``GDQ, ... (`GDQ`): k of n cases hold; ...`` per variant, or why there is no
        verdict."""
        if not self.rows:
            return "No verdicts (no GDQ runs in the data)." if not self.gdq_runs else \
                "No paper-hypothesis verdicts: no tasks or switch experiment with GDQ runs."
        held = (self.frame["verdict"] == HOLDS).groupby(self.frame["variant"]).agg(
            ["sum", "size"])
        return "; ".join(f"{VARIANT_NAMES.get(v, v)} (`{v}`): {int(h['sum'])} of "
                         f"{int(h['size'])} cases hold" for v, h in held.loc[
                             registry.order(held.index)].iterrows()) + "."

    def section(self, notes: Sequence[str]) -> list[str]:
        """``## Verdicts``: a row per case, a column per variant, then the counts and the
        skipped parts."""
        summary = ["## Verdicts", ""]
        if self.rows:
            f, variants = self.frame, registry.order(self.frame["variant"].unique())
            table = f.pivot_table(index=["hypothesis", "case"], columns="variant",
                                  values="verdict", aggfunc="first", sort=False).reindex(
                columns=variants).map(lambda v: "–" if pd.isna(v) else f"**{v}**")
            table.columns = [f"{v} ({VARIANT_NAMES[v]})" if v in VARIANT_NAMES else v
                             for v in variants]
            why = f.assign(why=f["variant"] + " " + f["reason"]).groupby(
                ["hypothesis", "case"], sort=False).agg(basis=("basis", "first"),
                                                        why=("why", "; ".join))
            table["Basis"] = why["basis"] + ": " + why["why"]
            summary += [table_text(table.reset_index().rename(columns={
                "hypothesis": "Hypothesis", "case": "Case"})), ""]
        summary += [self.counts(), ""]
        if notes:
            summary += ["Skipped parts:", "", *[f"- {n}" for n in notes], ""]
        return summary


class Writer:
    """Accumulates Markdown lines, the hypothesis verdicts and the skipped parts."""

    def __init__(self, study: Study, opts: ReportOptions, out_dir: Path) -> None:
        self.study, self.opts, self.out_dir = study, opts, out_dir
        self.lines: list[str] = []
        self.verdicts = Verdicts(any(is_gdq(m) for m in study.methods()))
        self.notes: list[str] = []

    def add(self, *lines: str) -> None:
        self.lines.extend(lines)

    def figure(self, stem: str, caption: str) -> None:
        path = self.out_dir / FIGURE_DIR / f"{stem}.png"
        if path.exists():
            self.add(f"![{caption}]({FIGURE_DIR}/{stem}.png)", "")

    def table(self, rows: Sequence[Sequence], columns: Sequence[str], align: str = "") -> None:
        """``rows`` of cells as a Markdown table (:func:`table_text`), then a blank line;
        ``align`` defaults to the first column left, the others right."""
        self.add(table_text(rows, columns, align or "l" + "r" * (len(columns) - 1)), "")

    def test(self, hypothesis: str, case: str, basis: str, variant: str, experiment: str,
             stat: Callable[[str], np.ndarray], higher_is_better: bool = True,
             unit: str = "", note: str = "") -> list[Comparison]:
        """``variant`` against each baseline of ``experiment`` with data, on per-run
        ``stat(method)`` (an empty array: no runs): its verdict recorded, its bullet, a
        ``note`` line and the comparisons written."""
        a = stat(variant)
        comps = [compare(a, b, variant, m, higher_is_better, seed=self.opts.seed)
                 for m in self.study.baselines(experiment) if (b := stat(m)).size]
        v, reason = verdict(comps), verdict_reason(comps)
        self.verdicts.rows.append((hypothesis, case, basis, variant, v, reason))
        label = case if variant == registry.REFERENCE else f"{case}, {variant}"
        self.add(f"- **{label}: {v}**: {variant} {reason} ({basis})", *[f"  {note}"][:bool(note)])
        self.comparisons(comps, unit)
        return comps

    def comparisons(self, comps: Sequence[Comparison], unit: str = "") -> None:
        for c in comps:
            self.add(f"  - {c.describe(unit)}")
        self.add("")

    def variants(self, experiment: str) -> list[str]:
        """GDQ and its variants present in ``experiment`` (GDQ first)."""
        return [m for m in self.study.methods(experiment) if is_gdq(m)]

    def section(self, title: str, available: bool, what: str, why: str) -> bool:
        """Write the heading ``## title``; when the section's data is not ``available``,
        note ``what`` as skipped because ``why`` and return False (the section ends)."""
        self.add(f"## {title}", "")
        if not available:
            self.notes.append(f"{what}: skipped, {why}.")
            self.add(f"_Skipped: {why}._", "")
        return available
