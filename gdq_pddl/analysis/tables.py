"""The area-visit table in the paper's layout (its Table "explore"): a row per task and
method, a ``mean (SE)`` cell per area of the visits summed over a run; bold, in the
areas irrelevant by either definition, the fewest visits after rounding. Markdown,
LaTeX (booktabs) and CSV (every digit) by the DataFrame's own writers.
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

import pandas as pd

from gdq_pddl.analysis.study import Study
from gdq_pddl.analysis.writer import TABLE_DIR, areas_str
from gdq_pddl.experiments.results import TASKS_EXPERIMENT
from gdq_pddl.outputs import write_text


@dataclass(frozen=True)
class AreaTable:
    """``frame``: index (task, method); columns ``runs``, ``area_<a>_mean``,
    ``area_<a>_se`` and ``area_<a>_bold`` per area ``a`` (the CSV's columns)."""

    frame: pd.DataFrame
    areas: tuple[int, ...]
    irrelevant_paper: dict[str, tuple[int, ...]]
    irrelevant_computed: dict[str, tuple[int, ...]]


DECIMALS = 1


def area_table(study: Study) -> AreaTable:
    """Compute the table of the tasks experiment (no rows when it is missing or has no
    areas)."""
    areas, cols, experiment = study.areas, study.area_columns, TASKS_EXPERIMENT
    if not study.has(experiment) or not study.has_areas(experiment):
        return AreaTable(pd.DataFrame(), areas, {}, {})
    tasks, methods = study.tasks(experiment), study.methods(experiment)
    per_run = study.rows(experiment).groupby(["task", "method", "run"], observed=True)[
        cols].sum()
    by = per_run.groupby(level=["task", "method"], observed=True)
    mean, se = by.mean(), by.sem().fillna(0.0)
    mean.columns = se.columns = [f"area_{a}" for a in areas]
    order = [(t, m) for t in tasks for m in methods if (t, m) in mean.index]
    frame = pd.concat([by.size().rename("runs"), mean.add_suffix("_mean"),
                       se.add_suffix("_se")], axis=1).loc[order]
    lowest = mean.round(DECIMALS).groupby(level="task", observed=True).transform("min")
    truths = {task: study.truth(experiment, task) for task in tasks}
    paper = {task: truth.irrelevant_areas_paper for task, truth in truths.items()}
    computed = {task: truth.irrelevant_areas for task, truth in truths.items()}
    for a in areas:
        irrelevant = pd.Series([a in set(paper[t]) | set(computed[t]) for t, _ in order],
                               index=frame.index)
        col = f"area_{a}"
        frame[f"{col}_bold"] = irrelevant & (mean[col].round(DECIMALS) <= lowest[col]).loc[order]
    return AreaTable(frame, areas, paper, computed)


def _cells(table: AreaTable, bold: str, sep: str = " ") -> pd.DataFrame:
    """The table as text: ``mean (se)`` cells, ``bold`` a format with one ``{}``."""
    d, f = DECIMALS, table.frame
    out = pd.DataFrame({"runs": f["runs"]})
    for a in table.areas:
        text = [f"{m:.{d}f}{sep}({s:.{d}f})" for m, s in zip(f[f"area_{a}_mean"], f[f"area_{a}_se"],
                                                              strict=True)]
        out[f"Area {a}"] = [bold.format(t) if b else t for t, b in zip(text, f[f"area_{a}_bold"],
                                                                       strict=True)]
    return out


def area_markdown(table: AreaTable) -> str:
    """The table as Markdown (the task cell names both sets of irrelevant areas)."""
    if table.frame.empty:
        return "_No area visits in the data._\n"
    cells = _cells(table, "**{}**").reset_index()
    first = ~cells["task"].duplicated()
    cells["task"] = [f"**{t}** (irrelevant: paper {areas_str(table.irrelevant_paper[t])}; "
                     f"computed {areas_str(table.irrelevant_computed[t])})" if f else ""
                     for t, f in zip(cells["task"], first, strict=True)]
    cells = cells.rename(columns={"task": "Task", "method": "Method"})
    return cells.to_markdown(index=False, colalign=("left", "left", *["right"] * (
        len(cells.columns) - 2))) + "\n"


def area_latex(table: AreaTable) -> str:
    """The table as LaTeX (booktabs; bold cells in ``\\mathbf``)."""
    cells = _cells(table, r"$\mathbf{{{}}}$", "~").drop(columns="runs").reset_index()
    for c in cells.columns[2:]:
        cells[c] = [t if t.startswith("$") else f"${t}$" for t in cells[c]]
    cells["task"] = cells["task"].astype(str).where(~cells["task"].duplicated(), "")
    return cells.rename(columns={"task": "Task", "method": "Method"}).to_latex(
        index=False, escape=False, column_format="ll" + "r" * len(table.areas))


def make_tables(out_dir: str | Path, study: Study | None = None) -> list[Path]:
    """Write ``area_visits.{md,tex,csv}`` into ``out_dir/tables``."""
    study = study or Study.open(out_dir)
    target = Path(out_dir) / TABLE_DIR
    table = area_table(study)
    if table.frame.empty:
        return []
    target.mkdir(parents=True, exist_ok=True)
    md, tex, csv_path = (target / f"area_visits.{e}" for e in ("md", "tex", "csv"))
    write_text(md, area_markdown(table))
    write_text(tex, area_latex(table))
    frame = table.frame.copy()
    tasks = frame.index.get_level_values("task")
    frame.insert(1, "irrelevant_paper", [" ".join(map(str, table.irrelevant_paper[t]))
                                         for t in tasks])
    frame.insert(2, "irrelevant_computed", [" ".join(map(str, table.irrelevant_computed[t]))
                                            for t in tasks])
    write_text(csv_path, frame.astype({c: int for c in frame if c.endswith("_bold")})
               .to_csv(float_format="%.6g", lineterminator="\n"))
    return [md, tex, csv_path]
