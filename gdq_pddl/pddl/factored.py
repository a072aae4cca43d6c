"""Independent effects: side by side, multiplied out, or kept as their parts.

Each binding of a ``forall`` of a probabilistic effect is an independent draw, so a ground
action's outcomes are the product of its draws (:func:`times`): IPPC-2008 sysadmin-slp's
``reboot`` has ``2 x 4^(n-1)`` on ``n`` computers. Where every outcome of the schema has
the same choices (its own outcomes *times* independent draws, not a mixture of products)
and its listing, equal effects merged, would pass :data:`FACTORED_ABOVE` (4096) outcomes,
the action is kept :class:`Factored` (:func:`factor`): its own outcomes and one part per
draw, never multiplied out; otherwise listed, as before factoring. The listing's size is
read without listing where the parts are :func:`separable` (``docs/decisions.md``).

Reality draws one outcome of each part (:func:`sample_parts`), as the competition's
simulator samples each binding, and applies them side by side (:func:`combine`). The
knowledge's determinisation is **each part's outcomes taken one at a time**
(:func:`factored_kept`): every part at its most likely outcome, then each other outcome
of one part with every other part at its most likely, ``1 + sum(|part| - 1)`` outcomes.
Its delete relaxation is the product's (each outcome of each part adds its facts in some
listed outcome), so h_max, h_add and h_FF are what the listed product would give; its
first outcome is the product's most likely, what ``most-likely`` keeps. It leaves out the
combinations where two or more parts leave their most likely outcome at once (why, and
what that costs: ``docs/decisions.md``); a replanning learner meets them as they happen.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, replace

from gdq_pddl.pddl.parser import MAX_OUTCOMES

FACTORED_ABOVE = MAX_OUTCOMES
"""A ground action whose listing would have more outcomes than this is kept as its parts
(:class:`Factored`), never listed; at most this many, it is listed as it always was."""

Ground = tuple[frozenset[str], frozenset[str], tuple[tuple, ...], float, tuple, bool]
"""A ground outcome's effect as fact sets: adds, deletes, conditional effects ``(must hold,
must not hold, adds, deletes)``, the reward it always earns, its conditional rewards
``(alternatives, amount)`` and whether it is a failed trial; equal ones are one outcome."""
NOTHING: Ground = (frozenset(), frozenset(), (), 0.0, (), False)  # sets and earns nothing
Dist = list[tuple[float, Ground]]


def both(x: Ground, y: Ground) -> Ground:
    """Two effects side by side (a failed trial has no other effect)."""
    if x[5] or y[5]:
        return (frozenset(), frozenset(), (), x[3] + y[3], x[4] + y[4], True)
    return (x[0] | y[0], x[1] | y[1], tuple(dict.fromkeys(x[2] + y[2])), x[3] + y[3],
            x[4] + y[4], False)


def times(dist: Dist, draw: Dist) -> Dist:
    """``dist`` and the independent ``draw`` side by side: their product, equal effects
    merged (in the order ``dist``'s outcomes, then ``draw``'s, list them)."""
    return merged([(p * q, both(x, y)) for p, x in dist for q, y in draw])


def merged(dist: Dist) -> Dist:
    """``dist`` with equal effects one outcome (first appearance first)."""
    out: dict[Ground, float] = {}
    for p, g in dist:
        out[g] = out.get(g, 0.0) + p
    return [(p, g) for g, p in out.items()]


@dataclass(frozen=True)
class Factored:
    """A ground action's effect as independent parts whose product it is: ``parts[0]``
    the action's own outcomes (its top-level distribution, without its choices), then one
    part per binding of each of its choices (:class:`~gdq_pddl.pddl.model.Choice`), each
    a distribution ``(probability, effect)`` summing to 1, equal effects merged; parts
    with one outcome are folded into ``parts[0]``. Reality draws one outcome from every
    part, independently, and applies them side by side."""

    parts: tuple[tuple[tuple[float, Ground], ...], ...]


def factor(own: Dist, draws: list[Dist]) -> Factored | None:
    """The action of schema outcomes ``own`` (one ``(probability, effect)`` each, its
    choices aside) times the independent ``draws`` (each merged) kept :class:`Factored`,
    where listing it would pass :data:`FACTORED_ABOVE` outcomes; None where it is listed
    (the module docstring). The listing's size is read exactly but cheaply: at most the
    product of the sizes; exactly that where the parts are :func:`separable`; else the
    listing made schema outcome by schema outcome, draw by draw, and stopped where it
    passes (where the listing was refused before factoring)."""
    cap = FACTORED_ABOVE
    if len(own) * math.prod(len(d) for d in draws) <= cap:
        return None
    if not separable([own, *draws]):
        total = 0
        for first in own:
            out = [first]
            for draw in draws:
                out = times(out, draw)
                if len(out) > cap:
                    break
            total += len(out)
            if total > cap:
                break
        else:
            return None
    parts = [merged(own)]
    for draw in draws:
        if len(draw) == 1:  # for sure: beside the action's own outcomes
            parts[0] = times(parts[0], draw)
        else:
            parts.append(draw)
    return Factored(tuple(tuple(part) for part in parts))


def separable(parts: list[Dist]) -> bool:
    """Whether side by side, one outcome of each of ``parts`` (distributions, equal
    effects merged), no two combinations give the same effect, so that the merged product
    is as large as the plain one: no failed trial, no fact and no conditional effect that
    two parts set, and every part but one earning nothing whatever its outcome (the one
    part's amounts then are the sums)."""
    facts: set[str] = set()
    conds: set[tuple] = set()
    earning = 0
    for part in parts:
        mine = set().union(*(g[0] | g[1] for _, g in part))
        its = {c for _, g in part for c in g[2]}
        if any(g[5] for _, g in part) or mine & facts or its & conds:
            return False
        facts |= mine
        conds |= its
        earning += any(g[3] != 0.0 or g[4] != () for _, g in part)
    return earning <= 1


def factored_kept(factored: Factored, determinisation: str, name: str
                  ) -> tuple[Dist, tuple[int, ...], tuple[str, ...]]:
    """What a :class:`Factored` ground action lists (never its parts' product): the
    outcome of every part's most likely outcome together, first, then each outcome of one
    part with every other part at its most likely (*one part at a time*: 1 plus the sum of
    the parts' other outcomes, equal effects once, each with the probability of the
    first combination that gives it); the ones the planner's ``determinisation`` keeps
    (all-outcomes: every one that does something; most-likely: the first), and their
    planner schema names (``name``, or ``name_f<i>`` where several are kept)."""
    parts = factored.parts
    best = [max(range(len(part)), key=lambda i, part=part: (part[i][0], -i)) for part in parts]

    def join(a: tuple[float, Ground], b: tuple[float, Ground]) -> tuple[float, Ground]:
        return a[0] * b[0], both(a[1], b[1])

    prefix = [(1.0, NOTHING)]
    for part, i in zip(parts, best, strict=True):
        prefix.append(join(prefix[-1], part[i]))
    suffix = [(1.0, NOTHING)] * (len(parts) + 1)
    for j in range(len(parts) - 1, -1, -1):
        suffix[j] = join(parts[j][best[j]], suffix[j + 1])
    listed: dict[Ground, float] = {prefix[-1][1]: prefix[-1][0]}
    for j, part in enumerate(parts):
        for i, outcome in enumerate(part):
            if i != best[j] and outcome[0] > 0:
                p, g = join(join(prefix[j], outcome), suffix[j + 1])
                listed.setdefault(g, p)
    outcomes = [(p, g) for g, p in listed.items()]

    def useful(i: int) -> bool:
        p, g = outcomes[i]
        return p > 0 and not g[5] and bool(g[0] or g[1] or g[2])

    if determinisation == "all-outcomes":
        known = tuple(i for i in range(len(outcomes)) if useful(i))
    else:
        known = (0,) if useful(0) else ()
    names = (name,) if len(known) == 1 else tuple(f"{name}_f{i}" for i in known)
    return outcomes, known, names


def combine(outcomes):
    """The ground outcomes ``outcomes`` (:class:`~gdq_pddl.pddl.grounding.GroundOutcome`,
    one of each part of a factored ground action) side by side, as one of that type: adds,
    deletes and conditional effects together (adds win), rewards summed, probabilities
    multiplied; a failed trial if one is (then nothing else happens, as :func:`both`)."""
    add = dele = 0
    p, reward, stuck = 1.0, 0.0, False
    conditional: list[tuple[int, int, int, int]] = []
    rewards: list = []
    for o in outcomes:
        p *= o.probability
        add, dele = add | o.add, dele | o.dele
        stuck |= o.stuck
        conditional += o.conditional
        reward += o.reward
        rewards += o.rewards
    if stuck:
        add = dele = 0
        conditional = []
    return replace(outcomes[0], probability=p, add=add, dele=dele & ~add, stuck=stuck,
                   conditional=tuple(dict.fromkeys(conditional)), reward=reward,
                   rewards=tuple(rewards))


def sample_parts(parts, rng) -> tuple:
    """One outcome of each of ``parts`` (a factored ground action's), drawn independently
    from ``rng`` (a numpy Generator): one uniform a part, the first outcome whose
    cumulative probability passes it (as :func:`~gdq_pddl.envs.step.draw_outcome` draws)."""
    out = []
    for part, x in zip(parts, rng.random(len(parts)).tolist(), strict=True):
        acc = 0.0
        for o in part:
            acc += o.probability
            if x < acc:
                break
        out.append(o)
    return tuple(out)


def gain_terms(parts) -> tuple:
    """What :func:`best_gain` reads of a factored ground action's ``parts``, once: the
    most the parts whose gains do not depend on the state earn (without failed trials,
    and of all), whether each has an outcome that does not fail, and the other parts."""
    same = [part for part in parts if not any(o.rewards for o in part)]
    live = [[o.reward for o in part if not o.stuck] for part in same]
    return (all(live), sum(max(g) for g in live if g),
            sum(max(o.reward for o in part) for part in same),
            [part for part in parts if any(o.rewards for o in part)])


def best_gain(terms: tuple, state: int) -> float:
    """The most an outcome of a factored ground action (:func:`gain_terms` of its parts)
    earns in ``state`` that does not fail the trial (where one can: every part has such
    an outcome; else of all): each part's most, added up, as the gains of parts add up."""
    all_live, live_sum, any_sum, varying = terms
    live = [[o.gain(state) for o in part if not o.stuck] for part in varying]
    if all_live and all(live):
        return float(live_sum + sum(max(g) for g in live))
    return float(any_sum + sum(max(o.gain(state) for o in part) for part in varying))
