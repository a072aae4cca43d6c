"""Exercise 3: values from the planner's knowledge, OptInit (tutorial, section 5).

GDQ reads the knowledge (the PDDL domain, mapped to the learner's states and actions) as
a model: ``next_state[s, a]`` is where the knowledge says action a leads from s, or -1
where it says the action does nothing ("no change": the robot stays in s). It is read
optimistically: every action does what the knowledge says at a cost of ``step_cost``, and
reaching a goal state pays R_max and ends the episode. OptInit is value iteration on this
model, before the robot takes a single step:

    Q(s, a) = R_max                                if a leads to a goal state
            = -step_cost + gamma * V(where a leads)  otherwise  (s itself for -1)
    V(s)    = max of Q(s, a) over the actions the knowledge says apply in s
              (over every action where none applies); V = 0 and Q = 0 in a goal state

Repeat until V stops changing (by at most 1e-9 or so): the grader compares to 1e-6.

Fill in ``optinit`` below, then check it:

    gdq-pddl exercises check 3 ex3_optinit.py
"""

import numpy as np


def optinit(next_state: np.ndarray, goal: np.ndarray, gamma: float, r_max: float,
            step_cost: float = 1.0) -> np.ndarray:
    """Return the OptInit Q table, float[n_states, n_actions].

    next_state: int[n_states, n_actions], where the knowledge says each action leads
        (-1: it does nothing).
    goal: bool[n_states], the goal states of the task.
    gamma: the discount factor; r_max: the goal reward; step_cost: the cost of a step.
    """
    raise NotImplementedError("exercise 3: write optinit")
