"""Exercise 2: Dyna-Q's planning step (tutorial, section 3).

After each real step Dyna-Q makes N *simulated* updates: it draws a pair (s, a) it has
tried and sets Q(s, a) to its expected value under the model it learned from its
experience. The model counts, for each pair, how often it led to each state s2
(``counts[s, a, s2]``) and how often the robot got stuck (``stuck[s, a]``: -R_max, and the
episode is over); ``cost[s, a]`` is the pair's mean step cost. With n = the pair's trials
(the sum of its counts plus its stuck trials):

    Q(s, a) <- ( sum over s2 of counts[s, a, s2] * value(s2)  +  stuck[s, a] * (-R_max) ) / n

    value(s2) = R_max                               if s2 is a goal state
              = -cost[s, a] + gamma * max_b Q(s2, b)  otherwise

The pairs are backed up one after the other: a later backup reads the values the
earlier ones wrote.

Fill in ``dyna_planning`` below, then check it:

    gdq-pddl exercises check 2 ex2_dyna_planning.py
"""

import numpy as np


def dyna_planning(q: np.ndarray, counts: np.ndarray, stuck: np.ndarray, cost: np.ndarray,
                  goal: np.ndarray, pairs: list[tuple[int, int]], gamma: float,
                  r_max: float) -> np.ndarray:
    """Return the Q table after the backups of ``pairs``, in order.

    q: the Q table, float[n_states, n_actions] (return a new table or this one, changed).
    counts: int[n_states, n_actions, n_states], the transitions the model recorded.
    stuck: int[n_states, n_actions], the trials that got stuck.
    cost: float[n_states, n_actions], each pair's mean step cost (a positive number).
    goal: bool[n_states], the goal states of the task.
    pairs: the (s, a) pairs to back up, in order (each tried at least once).
    gamma: the discount factor; r_max: the goal reward (and the stuck penalty).
    """
    raise NotImplementedError("exercise 2: write dyna_planning")
