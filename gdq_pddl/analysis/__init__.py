"""From an experiment output folder to figures, tables and ``REPORT.md``.

``make_all(out_dir)`` writes everything; the parts are :mod:`.figures`, :mod:`.tables`,
:mod:`.stats` and :mod:`.report`, reading the folder through :mod:`.data` and
:class:`~gdq_pddl.analysis.study.Study`.
"""

from __future__ import annotations

from gdq_pddl.analysis.data import Episodes, load_episodes
from gdq_pddl.analysis.report import make_all, write_report
from gdq_pddl.analysis.study import Study

__all__ = ["Episodes", "Study", "load_episodes", "make_all", "write_report"]
