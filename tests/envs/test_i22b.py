"""Progress on the true model's no-op fill (issue 22 item 4), the last step of its build."""

import numpy as np

from gdq_pddl.envs.model import with_noops


def test_no_op_fill_counts_its_arrays(bars):
    rows, prob = np.array([0, 2, 2]), np.array([1.0, 0.5, 0.5])  # pair 1 lists none
    fields = [np.array([4, 5, 6]), np.array([False, True, False])]
    new_ptr, out_prob, (nxt, stuck) = with_noops(rows, prob, fields, 3, 3)
    assert new_ptr.tolist() == [0, 1, 2, 4] and nxt.tolist() == [4, 0, 5, 6]  # state 1//3
    [bar] = [bar for bar in bars if bar.desc.startswith("true model")]
    assert bar.n == bar.total == 2 + 2  # where rows go, probabilities, then each field
