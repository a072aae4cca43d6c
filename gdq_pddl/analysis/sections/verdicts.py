"""The verdict bookkeeping of ``REPORT.md``: each GDQ variant's verdict per hypothesis
case (from :func:`gdq_pddl.analysis.stats.verdict`), the count of cases that hold and
the summary table."""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass, field

from gdq_pddl.analysis.data import order_methods
from gdq_pddl.analysis.stats import HOLDS, Comparison, verdict, verdict_reason

VARIANT_NAMES = {"GDQ": "GDQ, knowledge as a prior model", "GDQ-literal": "paper's GDQ read "
                 "literally", "GDQ-code": "authors'-code GDQ"}
"""How the verdict summary names the GDQ variants."""


@dataclass
class Case:
    """One hypothesis case: each GDQ variant's verdict and reason."""

    hypothesis: str
    case: str
    basis: str
    verdicts: dict[str, str] = field(default_factory=dict)
    reasons: dict[str, str] = field(default_factory=dict)


class Verdicts:
    """The cases in the order the sections met them, ``(hypothesis, case) -> Case``.

    ``gdq_runs`` says whether the data hold any GDQ run at all, so that a folder without
    cases (no tasks or switch experiment) is not summarised as having no GDQ runs;
    :attr:`elsewhere` names the sections that compare GDQ outside the hypotheses.
    """

    def __init__(self, gdq_runs: bool = True) -> None:
        self.cases: dict[tuple[str, str], Case] = {}
        self.gdq_runs = gdq_runs
        self.elsewhere: list[str] = []

    def record(self, hypothesis: str, case: str, basis: str, variant: str,
               comps: Sequence[Comparison]) -> tuple[str, str]:
        """Record ``variant``'s verdict on a case; returns the verdict and its reason."""
        v = verdict(comps)
        reason = verdict_reason(comps)
        entry = self.cases.setdefault((hypothesis, case), Case(hypothesis, case, basis))
        entry.verdicts[variant] = v
        entry.reasons[variant] = reason
        return v, reason

    def variants(self) -> list[str]:
        """The GDQ variants with a verdict, in method order."""
        found = {v for c in self.cases.values() for v in c.verdicts}
        return order_methods(found)

    def counts(self) -> str:
        """``GDQ, ... (`GDQ`): k of n cases hold; ...`` per variant, or why there is no
        verdict."""
        variants = self.variants()
        if not variants:
            if not self.gdq_runs:
                return "No verdicts (no GDQ runs in the data)."
            see = "".join(f"; see '{s}'" for s in self.elsewhere)
            return ("No paper-hypothesis verdicts: this folder has no tasks or switch "
                    f"experiment with GDQ runs{see}.")
        parts = []
        for v in variants:
            cases = [c for c in self.cases.values() if v in c.verdicts]
            held = sum(c.verdicts[v] == HOLDS for c in cases)
            parts.append(f"{VARIANT_NAMES.get(v, v)} (`{v}`): {held} of {len(cases)} cases hold")
        return "; ".join(parts) + "."

    def section(self, notes: Sequence[str]) -> list[str]:
        """The ``## Verdicts`` section: the table (when there are cases), the counts and
        the skipped parts."""
        summary = ["## Verdicts", ""]
        if self.cases:
            variants = self.variants()
            summary += ["| Hypothesis | Case | " + " | ".join(
                            f"{v} ({VARIANT_NAMES[v]})" if v in VARIANT_NAMES else v
                            for v in variants) + " | Basis |",
                        "|---|---|" + "---|" * len(variants) + "---|"]
            for c in self.cases.values():
                cells = [f"**{c.verdicts[v]}**" if v in c.verdicts else "–" for v in variants]
                reasons = "; ".join(f"{v} {c.reasons[v]}" for v in variants if v in c.reasons)
                summary.append(f"| {c.hypothesis} | {c.case} | " + " | ".join(cells)
                               + f" | {c.basis}: {reasons} |")
            summary.append("")
        summary += [self.counts(), ""]
        if notes:
            summary += ["Skipped parts:", "", *[f"- {n}" for n in notes], ""]
        return summary
