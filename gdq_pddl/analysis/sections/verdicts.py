"""The verdict bookkeeping of ``REPORT.md``: each GDQ variant's verdict per hypothesis
case (from :func:`gdq_pddl.analysis.stats.verdict`), the count of cases that hold and
the summary table."""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass, field

from gdq_pddl.analysis.data import order_methods
from gdq_pddl.analysis.stats import HOLDS, Comparison, verdict, verdict_reason

VARIANT_NAMES = {"GDQ": "paper GDQ", "GDQ-code": "authors'-code GDQ"}
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
    """The cases in the order the sections met them, ``(hypothesis, case) -> Case``."""

    def __init__(self) -> None:
        self.cases: dict[tuple[str, str], Case] = {}

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
        """``paper GDQ: k of n cases hold; authors'-code GDQ: j of m cases hold``."""
        variants = self.variants()
        if not variants:
            return "No verdicts (no GDQ runs in the data)."
        parts = []
        for v in variants:
            cases = [c for c in self.cases.values() if v in c.verdicts]
            held = sum(c.verdicts[v] == HOLDS for c in cases)
            parts.append(f"{VARIANT_NAMES.get(v, v)} (`{v}`): {held} of {len(cases)} cases hold")
        return "; ".join(parts) + "."

    def section(self, notes: Sequence[str]) -> list[str]:
        """The ``## Verdicts`` section: the table, the counts and the skipped parts."""
        variants = self.variants() or ["GDQ"]
        summary = ["## Verdicts", "",
                   "| Hypothesis | Case | " + " | ".join(
                       f"{v} ({VARIANT_NAMES[v]})" if v in VARIANT_NAMES else v
                       for v in variants) + " | Basis |",
                   "|---|---|" + "---|" * len(variants) + "---|"]
        for c in self.cases.values():
            cells = [f"**{c.verdicts[v]}**" if v in c.verdicts else "–" for v in variants]
            reasons = "; ".join(f"{v} {c.reasons[v]}" for v in variants if v in c.reasons)
            summary.append(f"| {c.hypothesis} | {c.case} | " + " | ".join(cells)
                           + f" | {c.basis}: {reasons} |")
        if not self.cases:
            summary.append("| – | – | " + "no data | " * len(variants) + "– |")
        summary += ["", self.counts(), ""]
        if notes:
            summary += ["Skipped parts:", "", *[f"- {n}" for n in notes], ""]
        return summary
