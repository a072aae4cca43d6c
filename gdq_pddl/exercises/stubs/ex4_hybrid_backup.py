"""Exercise 4: GDQ's hybrid backup (tutorial, section 5).

GDQ values a pair (s, a) by the knowledge's prior until it has tried it, then by a mix of
what it learned and the prior. The prior's backup of (s, a), with x where the knowledge
says the action leads (s itself where it says "no change", ``prior_next[s, a] == -1``):

    prior = R_max                          if x is a goal state
          = -prior_cost + gamma * V(x)     otherwise

The pair is *known* when it was tried more than m times (``visits[s, a] > m``); a pair
the knowledge says does nothing is known after its first trial (``visits[s, a] > 0``).
Unknown, its value is ``prior``. Known, after n = visits[s, a] trials, with ``learned``
the backup of the learned model (exercise 2's value) and w the prior's weight:

    Q(s, a) = (n * learned + w * prior) / (n + w)

Fill in ``hybrid_backup`` below, then check it:

    gdq-pddl exercises check 4 ex4_hybrid_backup.py
"""

import numpy as np


def hybrid_backup(s: int, a: int, v: np.ndarray, goal: np.ndarray, prior_next: np.ndarray,
                  visits: np.ndarray, learned: float, m: int, w: float, gamma: float,
                  r_max: float, prior_cost: float = 1.0) -> float:
    """Return GDQ's value of the pair (s, a).

    v: float[n_states], the current state values V.
    goal: bool[n_states], the goal states of the task.
    prior_next: int[n_states, n_actions], where the knowledge says each action leads
        (-1: it does nothing).
    visits: int[n_states, n_actions], the trials of each pair.
    learned: the learned model's backup of (s, a) (meaningful once it was tried).
    m: trials after which an applicable pair is known; w: the prior's weight.
    gamma: the discount factor; r_max: the goal reward; prior_cost: the prior's step cost.
    """
    raise NotImplementedError("exercise 4: write hybrid_backup")
