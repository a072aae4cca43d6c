"""gdq_pddl: Guided Dyna-Q, reinforcement learning guided by a PDDL planner."""

from __future__ import annotations

import importlib
from typing import TYPE_CHECKING

from gdq_pddl import _jit_cache

if TYPE_CHECKING:
    from collections.abc import Callable

    import pandas

    from gdq_pddl.learners import episodes, saving

_jit_cache.refresh()  # before any compiled function loads its cache (see _jit_cache)

from gdq_pddl.envs import register_envs  # noqa: E402

__version__ = "0.1.0"

register_envs()  # gymnasium.make("gdq_pddl/Office-v0" or "gdq_pddl/PDDL-v0", ...) after import

_LAZY = {"load_results": "gdq_pddl.experiments.results",
         **dict.fromkeys(("GreedyPolicy", "evaluate_policy", "load_generators", "load_learner",
                          "save_learner"), "gdq_pddl.learners")}
__all__ = ["__version__", *_LAZY, "envs", "learners", "wrappers", "errors", "resources"]
"""The API: the envs (ids and docs), the learners (with save, load and evaluate), the
wrappers that give any Gymnasium agent the knowledge, the errors raised on bad input,
and the shipped files by name. The documentation site renders them
(docs/reference/api.md: ``pip install '.[docs]' && mkdocs serve``)."""

load_results: Callable[..., pandas.DataFrame]
"""An output folder's episodes as a pandas DataFrame, one row per episode
(:func:`gdq_pddl.experiments.results.load_results`)."""
save_learner: Callable[..., None]
"""Save a learner's tables, config, generators and its task's identity to a ``.npz`` file
at the path given, no pickle (:func:`gdq_pddl.learners.saving.save_learner`)."""
load_learner: Callable[..., saving.TabularLearner]
"""A learner saved by ``save_learner``, ready to continue bit-identically on the task it was
saved for (another is refused naming what differs;
:func:`gdq_pddl.learners.saving.load_learner`)."""
load_generators: Callable[..., dict]
"""The random generators saved beside a learner
(:func:`gdq_pddl.learners.saving.load_generators`)."""
GreedyPolicy: type[saving.GreedyPolicy]
"""A learner's greedy policy, state -> action, savable
(:class:`gdq_pddl.learners.saving.GreedyPolicy`)."""
evaluate_policy: Callable[..., episodes.EpisodeRecords]
"""Mean return and success of a policy over episodes of an env, through its wrappers
(:func:`gdq_pddl.learners.episodes.evaluate_policy`)."""


def __getattr__(name: str):
    """The names of :data:`_LAZY`, imported on first use (start-up time)."""
    if name in _LAZY:
        return getattr(importlib.import_module(_LAZY[name]), name)
    raise AttributeError(f"module 'gdq_pddl' has no attribute {name!r}")
