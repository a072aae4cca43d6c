"""The head of ``REPORT.md``: output folder, configuration, versions and the
method paragraph."""

from __future__ import annotations

from gdq_pddl.analysis.sections.writer import Writer
from gdq_pddl.analysis.stats import ALPHA


def write(w: Writer) -> None:
    cfg, ep = w.study.config, w.study.episodes
    w.add("# Experiment report", "",
          f"Output folder: `{w.out_dir}`; {len(ep)} episodes in `episodes.csv`; "
          f"experiments: {', '.join(ep.experiments) or 'none'}.", "")
    if cfg.experiments:
        w.add("| experiment | world | schedule (task x episodes) | methods | runs | seed |",
              "|---|---|---|---|--:|--:|")
        for e in cfg.experiments:
            sched = e.get("schedule") or []
            sched_txt = ", ".join(f"{t} x {n}" for t, n in sched
                                  if isinstance(sched, list)) or "?"
            w.add(f"| {e.get('name', '?')} | {e.get('world', cfg.world or 'office')} | "
                  f"{sched_txt} | {', '.join(e.get('methods') or cfg.methods) or '?'} "
                  f"| {e.get('runs', cfg.runs if cfg.runs is not None else '?')} | "
                  f"{e.get('seed', cfg.seed if cfg.seed is not None else '?')} |")
        w.add("")
    else:
        facts = [f"world `{cfg.world or 'office (built in)'}`"]
        if cfg.seed is not None:
            facts.append(f"seed {cfg.seed}")
        if cfg.runs is not None:
            facts.append(f"{cfg.runs} runs")
        if cfg.episodes is not None:
            facts.append(f"{cfg.episodes} episodes per run")
        if cfg.methods:
            facts.append("methods " + ", ".join(cfg.methods))
        w.add("Configuration: " + "; ".join(facts) + ".", "")
    if cfg.versions:
        w.add("Versions: " + ", ".join(f"{k} {v}" for k, v in cfg.versions.items()),
              "")
    w.add(
        "**Method.** The unit of analysis is the run. For each comparison every run "
        "contributes one number; each GDQ variant (`GDQ`, the library's: the action "
        "knowledge as an optimistic prior model; `GDQ-literal`, the paper's Algorithms "
        "1-3 read literally; `GDQ-code`, the authors' released code) is compared on its "
        "own with each "
        "baseline (every method but GDQ and its variants) by Welch's t-test "
        "(two-sided) and a percentile bootstrap "
        f"95% CI of the difference in means (10,000 resamples, seed {w.opts.seed}). "
        f"A difference counts when the CI excludes 0 and p < {ALPHA} (with fewer than 2 "
        "runs per method nothing counts). Verdict per case and variant: **holds** = "
        "the variant significantly better than every baseline; **does not hold** = "
        "significantly "
        "worse than at least one, or better than none; **mixed** = otherwise. "
        "Milestones use a trailing moving average over full windows of "
        f"{w.opts.window} episodes (defined from episode {w.opts.window} on).", "")
