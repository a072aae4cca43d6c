"""From an experiment output folder to figures, tables and ``REPORT.md``.

:func:`load_results` reads ``episodes.csv`` into a pandas DataFrame (one row per
episode); :class:`Study` is the folder read lazily; :func:`make_report` writes whatever
report the folder's data calls for (:func:`make_all` for an episodes folder).
"""

from __future__ import annotations

from gdq_pddl.analysis.report import make_all, make_report, report_text, write_report
from gdq_pddl.analysis.study import Study
from gdq_pddl.experiments.results import load_results

__all__ = ["Study", "load_results", "make_all", "make_report", "report_text", "write_report"]
