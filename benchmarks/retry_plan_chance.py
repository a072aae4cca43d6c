"""The chance that a fixed plan reaches the goal within a step limit, and what it pays on
average, when each of its actions is tried until its outcome happens (a try that fails
changes nothing but costs its cost): the sum of geometric numbers of tries, computed
exactly step by step.

    python benchmarks/retry_plan_chance.py P:C [P:C ...] --limit 40 60 235 [--reward R]

Each ``P:C`` is one action of the plan, in order: the probability that a try works
(``1/25``, ``0.5``, ``1``) and the cost of one try. It prints, for each limit, the goal's
probability within it, the expected cost paid before the goal or the limit, and their
difference from the goal reward ``R``. IPPC-2008 zenotravel p04's plan (fly to the
passengers, board both, fly to each one's city, debark; ``docs/results/online.md``):

    python benchmarks/retry_plan_chance.py 1:0 1/25:10 1:0 1/2:0 1:0 1/2:0 1:0 1/25:10 \\
        1:0 1/4:0 1:0 1/25:10 1:0 1/4:0 --limit 40 235 --reward 10000
"""

from __future__ import annotations

import argparse
from fractions import Fraction


def chance_and_cost(stages: list[tuple[float, float]], limit: int) -> tuple[float, float]:
    """``(P(every stage done within limit steps), expected cost paid within the limit)``."""
    done_at = {0: 1.0}  # steps used -> probability that the stages so far are done then
    cost = 0.0
    for p, c in stages:
        nxt: dict[int, float] = {}
        for t, q in done_at.items():
            left = q
            for k in range(1, limit - t + 1):  # the k-th try of this stage
                cost += left * c
                nxt[t + k] = nxt.get(t + k, 0.0) + left * p
                left *= 1 - p
        done_at = nxt
    return sum(done_at.values()), cost


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("stages", nargs="+", help="P:C per action of the plan, in order")
    parser.add_argument("--limit", type=int, nargs="+", required=True)
    parser.add_argument("--reward", type=float, default=0.0)
    args = parser.parse_args(argv)
    stages = []
    for text in args.stages:
        p, _, c = text.partition(":")
        stages.append((float(Fraction(p)), float(c or 0)))
    if any(not 0 < p <= 1 for p, _ in stages):
        parser.error("each P must be in (0, 1]")
    expected = sum(1 / p for p, _ in stages)
    print(f"{len(stages)} actions; {expected:.1f} tries expected, "
          f"{sum(c / p for p, c in stages):.1f} paid on average with no limit")
    for limit in args.limit:
        chance, cost = chance_and_cost(stages, limit)
        print(f"limit {limit}: goal {chance:.3f}, cost {cost:.1f}, "
              f"goal reward x chance - cost {args.reward * chance - cost:.1f}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
