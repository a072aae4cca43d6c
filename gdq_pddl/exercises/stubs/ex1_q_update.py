"""Exercise 1: the Q-learning update (tutorial, section 2).

After one real step, Q-learning moves Q(s, a) a step of size alpha towards its target:

    target  = r                                if the episode ended with this step
            = r + gamma * max_b Q(s2, b)       otherwise
    Q(s, a) <- Q(s, a) + alpha * (target - Q(s, a))

Fill in ``q_update`` below, then check it:

    gdq-pddl exercises check 1 ex1_q_update.py
"""

import numpy as np


def q_update(q: np.ndarray, s: int, a: int, r: float, s2: int, done: bool, alpha: float,
             gamma: float) -> float:
    """Return the new value of Q(s, a) after the real step (s, a, r, s2).

    q: the Q table, float[n_states, n_actions] (read it; the grader ignores changes).
    s, a: the state and the action taken; r: the reward the step paid.
    s2: the state the step led to.
    done: True when the episode ended with this step (the goal, stuck, or out of steps):
        then there is no next state to bootstrap from.
    alpha: the step size; gamma: the discount factor.
    """
    raise NotImplementedError("exercise 1: write q_update")
