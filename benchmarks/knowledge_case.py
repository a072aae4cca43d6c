"""``gdq-pddl knowledge`` on some of its cases only (its seeds, report and output folder).

    python benchmarks/knowledge_case.py wrong-probabilities -- --method GDQ R-max-shaping \
        --runs 10 --jobs 1 --out results/knowledge-wrong-probabilities

The words before ``--`` name cases of :data:`gdq_pddl.experiments.knowledge.CASES`; the
words after it are ``gdq-pddl knowledge``'s options. The command itself runs every case,
which is the wrong cost when one case is to be run with more runs.
"""

from __future__ import annotations

import sys
from functools import partial

from gdq_pddl import cli
from gdq_pddl.cli import experiments
from gdq_pddl.experiments.knowledge import CASES, knowledge_experiments


def main(argv: list[str]) -> int:
    split = argv.index("--") if "--" in argv else len(argv)
    names, options = argv[:split], argv[split + 1:]
    known = {c.name: c for c in CASES}
    unknown = [n for n in names if n not in known]
    if unknown or not names:
        print(f"knowledge_case.py: name cases from {', '.join(known)} (got {names})",
              file=sys.stderr)
        return 2
    cases = tuple(known[n] for n in names)
    experiments.knowledge_experiments = partial(knowledge_experiments, cases=cases)
    return cli.main(["knowledge", *options])


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
