"""gdq_pddl: Guided Dyna-Q, reinforcement learning guided by a PDDL planner."""

from __future__ import annotations

from typing import TYPE_CHECKING

from gdq_pddl import _jit_cache

if TYPE_CHECKING:
    from collections.abc import Callable

    import pandas

_jit_cache.refresh()  # before any compiled function loads its cache (see _jit_cache)

from gdq_pddl.envs import register_envs  # noqa: E402

__version__ = "0.1.0"

register_envs()  # gymnasium.make("gdq_pddl/Office-v0" or "gdq_pddl/PDDL-v0", ...) after import

__all__ = ["__version__", "load_results", "envs", "learners", "errors", "resources"]
"""The API: the envs (ids and docs), the learners, the errors raised on bad input, and
the shipped files by name. ``pdoc gdq_pddl -o docs/api`` writes its pages."""

load_results: Callable[..., pandas.DataFrame]
"""An output folder's episodes as a pandas DataFrame, one row per episode
(:func:`gdq_pddl.analysis.results.load_results`)."""


def __getattr__(name: str):
    """``load_results`` (:func:`gdq_pddl.analysis.results.load_results`: an output
    folder's episodes as a pandas DataFrame), imported on first use: start-up time, the
    analysis layer loads pandas and matplotlib, which an env user does not need."""
    if name == "load_results":
        from gdq_pddl.analysis.results import load_results  # start-up time: pandas

        return load_results
    raise AttributeError(f"module 'gdq_pddl' has no attribute {name!r}")
