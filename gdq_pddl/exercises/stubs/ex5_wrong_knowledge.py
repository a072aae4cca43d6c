"""Exercise 5: wrong knowledge (tutorial, section 6).

The knowledge says a door opens when the robot asks for help beside it; in reality it is
jammed: every request leaves the robot stuck (-R_max, the episode is over). GDQ first
values ``opendoor`` there by the prior, ``prior_value``. By the learned model a failed
trial is worth ``trial_value`` (-R_max for a stuck one). The best other action in that
state (the way round, through another door) is worth ``alternative``. After n failed
trials, by exercise 4's rule, the door's value is

    prior_value                                    while n <= m (the pair is not known)
    (n * trial_value + w * prior_value) / (n + w)  once n > m

How many failed trials does it take before the door's value is below the alternative,
so that the greedy action turns away from it? Hold the three values fixed (in the
learner the values of other states move a little as it learns).

Fill in ``trials_to_turn_away`` below, then check it:

    gdq-pddl exercises check 5 ex5_wrong_knowledge.py
"""


def trials_to_turn_away(prior_value: float, trial_value: float, alternative: float,
                        w: float, m: int) -> int | None:
    """Return the smallest number of failed trials after which the door's value is
    strictly below ``alternative``: 0 if ``prior_value`` already is, None if no number of
    trials gets it there.

    prior_value: what the knowledge says trying the door is worth.
    trial_value: what one failed trial is worth, by the learned model.
    alternative: the value of the best other action.
    w: the prior's weight (pseudo-observations); m: trials before the pair is known.
    """
    raise NotImplementedError("exercise 5: write trials_to_turn_away")
