"""Save a learner, or its greedy policy, to one ``.npz`` file and load it back (no pickle).

A file holds a JSON ``header`` (format and version, sizes; a learner's class, config,
params and generator states) and the arrays, a learner's keyed ``group.field`` of its
:class:`~gdq_pddl.learners.tables.Tables` (layout: ``docs/learners.md``). A loaded learner
continues bit-identically (with the generators saved beside it). Loading refuses, with a
:class:`~gdq_pddl.errors.ResultsError` naming the file, a file of another format or
format version, a damaged one, or one of another task size.
"""

from __future__ import annotations

import json
import zipfile
from dataclasses import asdict, dataclass
from importlib.metadata import PackageNotFoundError, version
from pathlib import Path
from typing import IO, Any

import numpy as np

from gdq_pddl.errors import ConfigError, ResultsError
from gdq_pddl.learners import guards, registry
from gdq_pddl.learners.context import TaskContext
from gdq_pddl.learners.tables import Params, Tables
from gdq_pddl.learners.tabular import TabularLearner

FORMAT_VERSION = 1
"""The version of the file layout (``docs/learners.md``); another is refused on load."""


def _classes() -> dict[str, type]:
    """Every registered learner class by its class name (imported now)."""
    return {cls.__name__: cls for e in registry.entries() for cls in [e.learner_class()]}


_BIT_GENERATORS = ("PCG64", "PCG64DXSM", "Philox", "SFC64", "MT19937")

File = str | Path | IO[bytes]
"""A path, or a binary file object (``io.BytesIO``...)."""


def _name(file: File) -> str:
    return str(file) if isinstance(file, str | Path) else str(getattr(file, "name", "<file>"))


def _versions() -> dict[str, str]:
    try:
        package = version("gdq_pddl")
    except PackageNotFoundError:  # run from a checkout without installing
        package = "unknown"
    return {"gdq_pddl": package, "numpy": np.__version__}


def _write(file: File, kind: str, n_states: int, n_actions: int, arrays: dict[str, Any],
           **header: Any) -> None:
    header = {"format": f"gdq_pddl {kind}", "format_version": FORMAT_VERSION,
              "versions": _versions(), "n_states": n_states, "n_actions": n_actions, **header}
    text = json.dumps(header, default=lambda x: x.tolist())  # a generator state's arrays
    np.savez_compressed(file, header=np.array(text), **arrays)


def _read(file: File, kind: str) -> tuple[dict[str, Any], dict[str, np.ndarray]]:
    """The header and the arrays of a file of ``kind``; ResultsError naming it if not."""
    name = _name(file)
    try:
        with np.load(file, allow_pickle=False) as z:
            arrays = {k: z[k] for k in z.files}
        header = json.loads(str(arrays.pop("header")))
    except FileNotFoundError:
        raise ResultsError(f"{name}: no such file") from None
    except (OSError, ValueError, KeyError, EOFError, zipfile.BadZipFile) as exc:
        raise ResultsError(f"{name}: not a gdq_pddl {kind} file ({exc})") from None
    if not isinstance(header, dict) or header.get("format") != f"gdq_pddl {kind}":
        raise ResultsError(f"{name}: not a gdq_pddl {kind} file (its format is "
                           f"{header.get('format') if isinstance(header, dict) else None!r})")
    if header.get("format_version") != FORMAT_VERSION:
        raise ResultsError(f"{name}: file format version {header.get('format_version')!r}; "
                           f"this gdq_pddl reads version {FORMAT_VERSION}")
    return header, arrays


def save_learner(file: File, learner: TabularLearner, **generators: np.random.Generator
                 ) -> None:
    """Write ``learner`` (every array, its config and params) to ``file`` (module doc),
    with the state of each named generator, e.g. ``save_learner("gdq.npz", learner,
    rng=rng, env=env.unwrapped.np_random)`` (:func:`load_generators` gives them back)."""
    if type(learner) not in _classes().values():
        raise ConfigError(f"save_learner saves a learner of make_learner ({', '.join(_classes())}"
                          f"), got {type(learner).__name__}")
    for key, rng in generators.items():
        guards.check_generator(rng, f"generator {key!r}")
    arrays: dict[str, np.ndarray] = {}
    aliases: dict[str, str] = {}
    first: dict[int, str] = {}
    for group, arrs in zip(Tables._fields, learner.tables, strict=True):
        for field, x in zip(arrs._fields, arrs, strict=True):
            key = f"{group}.{field}"
            if id(x) in first:
                aliases[key] = first[id(x)]
            else:
                first[id(x)], arrays[key] = key, x
    _write(file, "learner", *learner.tables.table.q.shape, arrays,
           **{"class": type(learner).__name__}, config=asdict(learner.config),
           params=learner.params._asdict(), aliases=aliases,
           generators={k: g.bit_generator.state for k, g in generators.items()})


def load_learner(file: File, context: TaskContext) -> TabularLearner:
    """The learner saved in ``file`` (:func:`save_learner`), for ``context``, the task it
    goes on learning (of the saved size; its tables are the saved ones, so it continues
    as the saved learner would; :meth:`~gdq_pddl.learners.tabular.TabularLearner.start_task`
    switches it to another task)."""
    name = _name(file)
    header, arrays = _read(file, "learner")
    guards.check_context(context)
    saved, size = (header.get("n_states"), header.get("n_actions")), \
        (context.n_states, context.n_actions)
    if saved != size:
        raise ResultsError(f"{name}: saved for {saved[0]} states x {saved[1]} actions, the "
                           f"task context has {size[0]} x {size[1]}")
    try:
        cls = _classes()[header["class"]]
        learner = cls(context, cls.config_type(**header["config"]))
        params = Params(**header["params"])
        loaded = {**arrays, **{k: arrays[v] for k, v in header["aliases"].items()}}
        # a file saved before the prior knew the file's rewards has no prior.reward: the
        # context's (empty on the goal scale, where nothing else changed)
        loaded.setdefault("prior.reward", learner.tables.prior.reward)
        # and one saved before the prior kept chances of dead ends has no prior.dead: the
        # context's (empty where the knowledge has no dead end)
        loaded.setdefault("prior.dead", learner.tables.prior.dead)
        # and one saved before learners had their own group has none: a learner's fresh
        # own arrays (empty for the learners of that time)
        for field, x in zip(learner.tables.own._fields, learner.tables.own, strict=True):
            loaded.setdefault(f"own.{field}", x)
        tables = Tables(*(type(group)(*(loaded[f"{g}.{field}"] for field in group._fields))
                          for g, group in zip(Tables._fields, learner.tables, strict=True)))
        guards.check_tables(tables, params)
        if params.kind != learner.kind:
            raise ConfigError(f"params.kind is {params.kind}, a {cls.__name__} with this "
                              f"config is kind {learner.kind}")
    except (KeyError, TypeError, AttributeError, ConfigError) as exc:
        raise ResultsError(f"{name}: damaged learner file ({type(exc).__name__}: {exc})"
                           ) from None
    learner.tables, learner.params, learner._model = tables, params, tables.model
    learner.q = tables.table.q
    return learner


def load_generators(file: File) -> dict[str, np.random.Generator]:
    """The generators saved with the learner in ``file``, by name, in their saved state."""
    header, _ = _read(file, "learner")
    out = {}
    for key, state in header.get("generators", {}).items():
        kind = state.get("bit_generator") if isinstance(state, dict) else None
        if kind not in _BIT_GENERATORS:
            raise ResultsError(f"{_name(file)}: generator {key!r} has an unknown bit "
                               f"generator {kind!r} (known: {', '.join(_BIT_GENERATORS)})")
        bits = getattr(np.random, kind)()
        try:
            bits.state = state
        except (TypeError, ValueError, KeyError) as exc:
            raise ResultsError(f"{_name(file)}: generator {key!r}: {exc}") from None
        out[key] = np.random.Generator(bits)
    return out


@dataclass(frozen=True, eq=False)
class GreedyPolicy:
    """A learner's greedy policy, frozen: ``actions[s]`` is the action in learner state
    ``s``. It acts like a learner that learns nothing (``act``, ``observe``), so
    :func:`~gdq_pddl.learners.episodes.evaluate_policy` runs it in any env of the task."""

    actions: np.ndarray
    """int64[n_states]: the action per learner state."""
    n_actions: int
    """The task's number of actions."""

    def __post_init__(self) -> None:
        a = self.actions
        if not isinstance(a, np.ndarray) or a.ndim != 1 or len(a) == 0 or \
                a.dtype != np.int64 or a.min() < 0 or a.max() >= self.n_actions:
            raise ConfigError(f"GreedyPolicy.actions must be a non-empty int64 array of "
                              f"actions in [0, {self.n_actions})")

    @classmethod
    def of(cls, learner: TabularLearner) -> GreedyPolicy:
        """``learner``'s greedy policy now."""
        return cls(np.asarray(learner.greedy_policy(), dtype=np.int64),
                   learner.context.n_env_actions)

    def act(self, state: int, rng: np.random.Generator | None = None) -> int:
        """The policy's action in ``state`` (``rng`` unused)."""
        return int(self.actions[guards.check_state("state", state, len(self.actions))])

    def observe(self, *step: object) -> None:
        """Learns nothing."""

    def save(self, file: File) -> None:
        """Write the policy to ``file`` (module doc)."""
        _write(file, "policy", len(self.actions), self.n_actions, {"actions": self.actions})

    @classmethod
    def load(cls, file: File) -> GreedyPolicy:
        """The policy saved in ``file`` (:meth:`save`)."""
        header, arrays = _read(file, "policy")
        try:
            return cls(arrays["actions"], int(header["n_actions"]))
        except (KeyError, TypeError, ValueError) as exc:
            raise ResultsError(f"{_name(file)}: damaged policy file ({exc})") from None
