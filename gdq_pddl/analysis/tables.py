"""The area-visit table in the paper's layout (its Table "explore").

Rows are task x method, columns Area 1..k; a cell is ``mean (SE)`` over runs of the
visits to that area summed over a run's episodes. The task cell lists the paper's
irrelevant areas and the computed ones (areas the true optimal policy does not visit,
see :class:`~gdq_pddl.analysis.routes.TaskTruth`). In every column that is irrelevant
to the task by either definition, the fewest visits among all methods in the table are
bold (every method within rounding of the minimum, so ties are all bold).

Written as Markdown, LaTeX (booktabs) and CSV (plain numbers, one row per task x method).
"""

from __future__ import annotations

import csv
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from gdq_pddl.analysis.data import TASKS_EXPERIMENT
from gdq_pddl.analysis.stats import mean_se
from gdq_pddl.analysis.study import Study
from gdq_pddl.outputs import write_text, writing


@dataclass(frozen=True)
class AreaRow:
    """One task x method row."""

    task: str
    method: str
    runs: int
    mean: tuple[float, ...]
    se: tuple[float, ...]
    bold: tuple[bool, ...]


@dataclass(frozen=True)
class AreaTable:
    areas: tuple[int, ...]
    rows: tuple[AreaRow, ...]
    irrelevant_paper: dict[str, tuple[int, ...]]
    irrelevant_computed: dict[str, tuple[int, ...]]
    decimals: int = 1

    def tasks(self) -> list[str]:
        return list(dict.fromkeys(r.task for r in self.rows))


def run_area_totals(study: Study, method: str, task: str,
                    experiment: str = TASKS_EXPERIMENT) -> np.ndarray:
    """``[runs, n_areas]``: visits per area summed over each run's episodes of ``task``."""
    v = study.episodes.area_visits(experiment, method, task)
    if v.size == 0:
        return np.empty((0, len(study.episodes.areas)))
    return np.nansum(v, axis=1)


def area_table(study: Study, experiment: str = TASKS_EXPERIMENT, decimals: int = 1) -> AreaTable:
    """Compute the table (empty rows when ``experiment`` is missing)."""
    ep = study.episodes
    areas = ep.areas
    rows: list[AreaRow] = []
    paper: dict[str, tuple[int, ...]] = {}
    computed: dict[str, tuple[int, ...]] = {}
    if not study.has(experiment):
        return AreaTable(areas, (), paper, computed, decimals)
    for task in ep.tasks(experiment):
        truth = study.truth(experiment, task)
        paper[task], computed[task] = truth.irrelevant_areas_paper, truth.irrelevant_areas
        irrelevant = set(paper[task]) | set(computed[task])
        stats = {}
        for method in ep.methods(experiment):
            totals = run_area_totals(study, method, task, experiment)
            if totals.shape[0]:
                stats[method] = (totals.shape[0], *mean_se(totals, axis=0))
        if not stats:
            continue
        rounded = {m: np.round(s[1], decimals) for m, s in stats.items()}
        lowest = np.min(np.stack(list(rounded.values())), axis=0)
        for method, (n, mean, se) in stats.items():
            bold = tuple(a in irrelevant and rounded[method][i] <= lowest[i]
                         for i, a in enumerate(areas))
            rows.append(AreaRow(task, method, n, tuple(map(float, mean)),
                                tuple(map(float, se)), bold))
    return AreaTable(areas, tuple(rows), paper, computed, decimals)


def _sets(a: tuple[int, ...]) -> str:
    return ", ".join(map(str, a)) if a else "none"


def _cell(row: AreaRow, i: int, d: int) -> str:
    return f"{row.mean[i]:.{d}f} ({row.se[i]:.{d}f})"


def to_markdown(table: AreaTable) -> str:
    d = table.decimals
    head = ["Task", "Method", "runs", *[f"Area {a}" for a in table.areas]]
    lines = ["| " + " | ".join(head) + " |", "|" + "|".join(
        [":--", ":--", "--:"] + ["--:"] * len(table.areas)) + "|"]
    last = None
    for row in table.rows:
        if row.task != last:
            paper = _sets(table.irrelevant_paper[row.task])
            ours = _sets(table.irrelevant_computed[row.task])
            task_cell = f"**{row.task}** (irrelevant: paper {paper}; computed {ours})"
        else:
            task_cell = ""
        last = row.task
        cells = [f"**{_cell(row, i, d)}**" if b else _cell(row, i, d)
                 for i, b in enumerate(row.bold)]
        lines.append("| " + " | ".join([task_cell, row.method, str(row.runs), *cells]) + " |")
    return "\n".join(lines) + "\n"


def _tex(text: str) -> str:
    return text.replace("_", r"\_").replace("&", r"\&").replace("%", r"\%")


def to_latex(table: AreaTable) -> str:
    d = table.decimals
    k = len(table.areas)
    out = [r"\begin{tabular}{ll" + "r" * k + "}", r"\toprule",
           "Task & Method & " + " & ".join(f"Area {a}" for a in table.areas) + r" \\",
           r"\midrule"]
    tasks = table.tasks()
    for j, task in enumerate(tasks):
        rows = [r for r in table.rows if r.task == task]
        for i, row in enumerate(rows):
            if i == 0:
                label = f"Task {_tex(task)}"
            elif i == 1:
                label = f"paper: {_sets(table.irrelevant_paper[task])}"
            elif i == 2:
                label = f"ours: {_sets(table.irrelevant_computed[task])}"
            else:
                label = ""
            cells = []
            for a in range(k):
                text = f"{row.mean[a]:.{d}f}~({row.se[a]:.{d}f})"
                cells.append(rf"$\mathbf{{{text}}}$" if row.bold[a] else f"${text}$")
            out.append(f"{label} & \\textit{{{_tex(row.method)}}} & " + " & ".join(cells)
                       + r" \\")
        if j < len(tasks) - 1:
            out.append(r"\midrule")
    out += [r"\bottomrule", r"\end{tabular}"]
    return "\n".join(out) + "\n"


def write_csv(table: AreaTable, path: Path) -> None:
    with writing(path), path.open("w", newline="", encoding="utf-8") as f:
        w = csv.writer(f)
        w.writerow(["task", "method", "runs", "irrelevant_paper", "irrelevant_computed",
                    *[f"area_{a}_mean" for a in table.areas],
                    *[f"area_{a}_se" for a in table.areas],
                    *[f"area_{a}_bold" for a in table.areas]])
        for row in table.rows:
            w.writerow([row.task, row.method, row.runs,
                        " ".join(map(str, table.irrelevant_paper[row.task])),
                        " ".join(map(str, table.irrelevant_computed[row.task])),
                        *[f"{v:.6g}" for v in row.mean], *[f"{v:.6g}" for v in row.se],
                        *[int(b) for b in row.bold]])


def make_tables(out_dir: str | Path, study: Study | None = None,
                table_dir: str | Path | None = None) -> list[Path]:
    """Write ``area_visits.{md,tex,csv}`` into ``table_dir`` (default ``out_dir/tables``)."""
    study = study or Study.open(out_dir)
    target = Path(table_dir) if table_dir is not None else Path(out_dir) / "tables"
    table = area_table(study)
    if not table.rows:
        return []
    target.mkdir(parents=True, exist_ok=True)
    md, tex, csv_path = (target / f"area_visits.{e}" for e in ("md", "tex", "csv"))
    write_text(md, to_markdown(table))
    write_text(tex, to_latex(table))
    write_csv(table, csv_path)
    return [md, tex, csv_path]
