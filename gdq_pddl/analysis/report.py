"""``REPORT.md`` of an output folder, with its figures and tables: what the folder holds
decides which (:func:`make_report`). Every verdict is computed from the data.
"""

from __future__ import annotations

from pathlib import Path

from gdq_pddl.analysis import generic, sections
from gdq_pddl.analysis.figures import FigureOptions, make_figures
from gdq_pddl.analysis.knowledge import make_knowledge_report
from gdq_pddl.analysis.pairs import make_pairs_report
from gdq_pddl.analysis.study import Study
from gdq_pddl.analysis.tables import make_tables
from gdq_pddl.analysis.writer import ReportOptions, Writer
from gdq_pddl.errors import ResultsError
from gdq_pddl.experiments.pairs import PAIRS_EXPERIMENT
from gdq_pddl.experiments.protocol import PAPER_SIZE, QUICK_SIZE
from gdq_pddl.experiments.results import load_config, unfinished
from gdq_pddl.outputs import write_text

SECTIONS = (generic.write_header, generic.write_methods, sections.write_ground_truth,
            sections.write_hypothesis_1, sections.write_hypothesis_2,
            sections.write_hypothesis_3, sections.write_route_c, sections.write_variants,
            sections.write_why_gdq_fails, sections.write_robot)
"""The paper report's sections in order."""
DEFAULT_OPTIONS = ReportOptions()


def report_text(out_dir: str | Path, opts: ReportOptions = DEFAULT_OPTIONS,
                study: Study | None = None) -> str:
    """The Markdown of ``REPORT.md`` (embedding figures already in ``out_dir/figures``)."""
    out = Path(out_dir)
    study = study or Study.open(out)
    w = Writer(study, opts, out)
    if len(study.uncovered) == len(study.experiments):  # no paper experiment
        w.add("# Run report", "", *generic.setup_lines(study), "")
        generic.write_methods(w, full=False)
        return "\n".join(w.lines)
    for section in SECTIONS:
        section(w)
    # a one-line count under the title, the verdicts after the method paragraph
    head_end = next(i for i, line in enumerate(w.lines) if line.startswith("**Method.**")) + 2
    top = [*first_look_lines(study), f"**Summary.** {w.verdicts.counts()}", ""]
    return "\n".join(w.lines[:2] + top + w.lines[2:head_end] + w.verdicts.section(w.notes)
                     + w.lines[head_end:]) + "\n"


def first_look_lines(study: Study) -> list[str]:
    """A warning for the first lines of a report whose paper experiments ran fewer runs
    than the paper's protocol (``reproduce --quick``): what that means for the verdicts.
    None for the full protocol."""
    runs = [e.get("runs") for e in study.config.experiments
            if e.get("name") not in study.uncovered and isinstance(e.get("runs"), int)]
    full_episodes, full_runs = PAPER_SIZE
    if not runs or max(runs) >= full_runs:
        return []
    episodes = max((n for e in study.config.experiments if e.get("name") not in
                    study.uncovered for _, n in (e.get("schedule") or []) if isinstance(n, int)),
                   default=0)
    quick = " (`gdq-pddl reproduce --quick`)" if (episodes, max(runs)) == QUICK_SIZE else ""
    return [f"**A first look: {max(runs)} runs**, of {episodes} episodes a task{quick}, "
            f"where the paper's protocol has {full_runs} runs of {full_episodes}. With so "
            "few runs the tests have little power: a difference the full protocol finds "
            "significant often is not here, so a case reads \"mixed\" or \"does not "
            "hold\" where the full run says it holds, and fewer cases hold below. A failed "
            "case here is not a failed reproduction; `gdq-pddl reproduce` runs the paper's "
            "protocol.", ""]


def write_report(out_dir: str | Path, opts: ReportOptions = DEFAULT_OPTIONS,
                 study: Study | None = None) -> Path:
    """Write ``REPORT.md`` in ``out_dir``; returns its path."""
    path = Path(out_dir) / "REPORT.md"
    write_text(path, report_text(out_dir, opts, study))
    return path


def make_all(out_dir: str | Path, opts: ReportOptions = DEFAULT_OPTIONS) -> list[Path]:
    """Figures, tables and ``REPORT.md`` of an episodes folder; returns every written path."""
    out = Path(out_dir)
    study = Study.open(out)
    paths = make_figures(out, FigureOptions(window=opts.window), study)
    paths += make_tables(out, study)
    paths.append(write_report(out, opts, study))
    return paths


def make_report(out_dir: str | Path, command: str | None = None) -> list[Path]:
    """The report the folder's data calls for: a pairs folder's (:mod:`.pairs`), the
    wrong-knowledge cases' (:mod:`.knowledge`; ``command`` names what made them), else
    :func:`make_all` (the paper's hypotheses tested on its experiments, *Methods compared*
    on any other); returns every written path, ``REPORT.md`` last."""
    out = Path(out_dir)
    config = load_config(out)
    if config.experiments and all(e.get("name") == PAIRS_EXPERIMENT
                                  for e in config.experiments):
        return make_pairs_report(out)
    if not (out / "episodes.csv").is_file():
        stopped = unfinished(out)
        if stopped is not None:
            raise stopped
        raise ResultsError(f"{out} has no episodes.csv: is it an output folder of gdq-pddl "
                           "run, switch, robot, reproduce, knowledge or pairs?")
    if any(e.get("knowledge") for e in config.experiments):
        return make_knowledge_report(out, command or "gdq-pddl knowledge (see config.json)")
    return make_all(out)
