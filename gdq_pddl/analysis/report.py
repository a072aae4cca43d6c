"""``REPORT.md``: the paper's hypotheses tested on an experiment output folder.

Every verdict is computed from the data by :func:`gdq_pddl.analysis.stats.verdict` (GDQ
against each baseline, one number per run, Welch's t-test and a bootstrap CI); nothing
is hard-coded. Experiments missing from the folder (a ``--quick`` run without switches
or robot) are skipped with a note; experiments no paper section covers (``gdq-pddl run``)
get the *Methods compared* section (:mod:`.sections.methods`) instead of verdicts.

The sections are in :mod:`gdq_pddl.analysis.sections`; this module runs them in order
and puts the verdict summary after the method paragraph.
"""

from __future__ import annotations

from pathlib import Path

from gdq_pddl.analysis.figures import FigureOptions, make_figures
from gdq_pddl.analysis.sections import (
    ground_truth,
    header,
    hypothesis_1,
    hypothesis_2,
    hypothesis_3,
    methods,
    robot,
    route_c,
    variants,
    why_gdq_fails,
)
from gdq_pddl.analysis.sections.why_gdq_fails import OptInitValues, optinit_values
from gdq_pddl.analysis.sections.writer import ReportOptions, Writer
from gdq_pddl.analysis.study import Study
from gdq_pddl.analysis.tables import make_tables
from gdq_pddl.outputs import write_text

__all__ = ["OptInitValues", "ReportOptions", "make_all", "optinit_values", "write_report"]

SECTIONS = (header, methods, ground_truth, hypothesis_1, hypothesis_2, hypothesis_3, route_c,
            variants, why_gdq_fails, robot)
"""The report's sections in order (modules with ``write(w)``)."""
DEFAULT_OPTIONS = ReportOptions()


def render(w: Writer) -> str:
    """The written lines with the verdict summary: a one-line count under the title and
    the ``## Verdicts`` section after the method paragraph."""
    summary = w.verdicts.section(w.notes)
    # header is the first block up to the method paragraph; put the summary after it
    head_end = next(i for i, line in enumerate(w.lines)
                    if line.startswith("**Method.**")) + 2
    top = [f"**Summary.** {w.verdicts.counts()}", ""]
    return "\n".join(w.lines[:2] + top + w.lines[2:head_end] + summary
                     + w.lines[head_end:]) + "\n"


def write_report(out_dir: str | Path, opts: ReportOptions = DEFAULT_OPTIONS,
                 study: Study | None = None) -> Path:
    """Write ``REPORT.md`` in ``out_dir`` (embedding figures already in ``out_dir/figures``)."""
    out = Path(out_dir)
    study = study or Study.open(out)
    w = Writer(study, opts, out)
    for section in SECTIONS:
        section.write(w)
    path = out / "REPORT.md"
    write_text(path, render(w))
    return path


def make_all(out_dir: str | Path, opts: ReportOptions = DEFAULT_OPTIONS,
             figure_opts: FigureOptions | None = None) -> list[Path]:
    """Figures, tables and ``REPORT.md`` for one output folder; returns every written path."""
    out = Path(out_dir)
    study = Study.open(out)
    fopts = figure_opts or FigureOptions(window=opts.window)
    paths = make_figures(out, fopts, study)
    paths += make_tables(out, study)
    paths.append(write_report(out, opts, study))
    return paths
