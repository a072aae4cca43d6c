"""Save a learner, or its greedy policy, to one ``.npz`` file and load it back (no pickle).

A file holds a JSON ``header`` (format and version, sizes, the ``identity`` of the task it
belongs to; a learner's class, config, params and generator states) and the arrays, a
learner's keyed ``group.field`` of its :class:`~gdq_pddl.learners.tables.Tables` (layout:
``docs/learners.md``). A file is written at exactly the path given (no ``.npz`` is added).
A loaded learner continues bit-identically (with the generators saved beside it).

Loading refuses, with a :class:`~gdq_pddl.errors.ResultsError` naming the file, a file of
another format or format version, a damaged one, one of another task (its identity,
:mod:`~gdq_pddl.envs.identity`: the problem's files by hash, and for a problem explored
online the states its rows number) or of another task size, and a learner file holding
what :func:`save_learner` never writes (params other than its config and task give,
non-finite values).
"""

from __future__ import annotations

import json
import zipfile
from collections.abc import Mapping
from dataclasses import asdict, dataclass
from importlib.metadata import PackageNotFoundError, version
from pathlib import Path
from typing import IO, Any

import numpy as np

from gdq_pddl.envs.identity import NUMBERING_KEYS, describe, first_difference, shown
from gdq_pddl.errors import ConfigError, OutputError, ResultsError
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
    if isinstance(file, str | Path):  # numpy would add ".npz" to a name without it
        try:
            with open(file, "wb") as fh:
                np.savez_compressed(fh, header=np.array(text), **arrays)
        except OSError as exc:  # a missing folder, a folder given as the file, a full disk
            raise OutputError(f"{file}: cannot write the {kind} file here "
                              f"({exc.strerror or exc})") from None
    else:
        np.savez_compressed(file, header=np.array(text), **arrays)


def identity_of(context: object, rows: int | None = None) -> dict[str, str] | None:
    """The identity of the task ``context`` (or an instance) is of, now (None: not known);
    ``rows``: of a problem explored online, its first ``rows`` rows only."""
    say = getattr(context, "identity", None)
    if not callable(say):
        return None
    return dict(say() if rows is None else say(rows=rows))


def _rows(identity: Mapping[str, str] | None) -> int | None:
    """The rows numbered in an identity's ``states`` (a problem explored online)."""
    text = (identity or {}).get("states", "")
    head = text.split(" ", 1)[0]
    return int(head) if head.isdigit() else None


def _saved_identity(name: str, header: Mapping[str, Any]) -> dict[str, str] | None:
    """The ``identity`` a header records (None: a file saved before identities were)."""
    saved = header.get("identity")
    if saved is not None and not (isinstance(saved, dict) and all(
            isinstance(k, str) and isinstance(v, str) for k, v in saved.items())):
        raise ResultsError(f"{name}: damaged file (header key identity: {saved!r}, expected "
                           "an object of strings)")
    return saved


def check_identity(name: str, what: str, saved: Mapping[str, str] | None,
                   now: Mapping[str, str] | None, against: str,
                   keys: tuple[str, ...] | None = None) -> None:
    """Refuse the file ``name`` (a ``what``) saved for ``saved`` where ``against`` (the
    task context, the env) is ``now``: a :class:`ResultsError` naming the first key that
    differs (of ``keys``; None: every key) and both values. Nothing is compared where
    ``now`` is None; ``saved`` None (a file saved before identities were recorded) is
    refused only against a problem explored online, whose rows cannot be checked."""
    if now is None:
        return
    if saved is None:
        if "states" in now:
            raise ResultsError(f"{name}: this {what} records no identity (saved by an older "
                               f"gdq_pddl), so it cannot be checked against {against}, a "
                               "problem explored online, whose rows number the states its "
                               "own episodes reached")
        return
    diff = first_difference(saved, now, keys)
    if diff is None:
        return
    key, was, is_ = diff[0], shown(diff[1]), shown(diff[2])
    if key in ("states", "explored"):
        raise ResultsError(f"{name}: this {what} belongs to another instance explored online "
                           f"({key}: {was}; {against}: {is_}): its rows number the states "
                           "the run that saved it reached, in their order, and another "
                           "instance numbers its own; use it only with the instance it was "
                           "saved from (docs/learners.md)")
    raise ResultsError(f"{name}: this {what} was saved for {describe(saved)}, {against} is "
                       f"{describe(now)}: its {key} is {was} in the file, {is_} in {against}")


def _read(file: File, kind: str) -> tuple[dict[str, Any], dict[str, np.ndarray]]:
    """The header and the arrays of a file of ``kind``; ResultsError naming it if not."""
    name = _name(file)
    try:
        with np.load(file, allow_pickle=False) as z:
            arrays = {k: z[k] for k in z.files}
        header = json.loads(str(arrays.pop("header")))
    except FileNotFoundError:
        hint = f" ({name}.npz exists: an older gdq_pddl added .npz to the name it was " \
            "given; give that name)" if isinstance(file, str | Path) and \
            Path(f"{file}.npz").exists() else ""
        raise ResultsError(f"{name}: no such file{hint}") from None
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
    """Write ``learner`` (every array, its config and params, the identity of its task) to
    ``file`` (module doc; a path is written as given, no ``.npz`` added), with the state
    of each named generator, e.g. ``save_learner("gdq.npz", learner, rng=rng,
    env=env.unwrapped.np_random)`` (:func:`load_generators` gives them back)."""
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
           generators={k: g.bit_generator.state for k, g in generators.items()},
           identity=identity_of(learner.context))


def load_learner(file: File, context: TaskContext) -> TabularLearner:
    """The learner saved in ``file`` (:func:`save_learner`; the path as given), for
    ``context``, the task it was saved on (its identity and size: the same problem files,
    and for a problem explored online the same instance; its tables are the saved ones,
    so it continues as the saved learner would;
    :meth:`~gdq_pddl.learners.tabular.TabularLearner.start_task` switches it to another
    task). Raises :class:`~gdq_pddl.errors.ResultsError` naming the file and what differs."""
    name = _name(file)
    header, arrays = _read(file, "learner")
    guards.check_context(context)
    check_identity(name, "learner", _saved_identity(name, header), identity_of(context),
                   "the task context")
    saved, size = (header.get("n_states"), header.get("n_actions")), \
        (context.n_states, context.n_actions)
    if saved != size:
        raise ResultsError(f"{name}: saved for {saved[0]} states x {saved[1]} actions, the "
                           f"task context has {size[0]} x {size[1]}")
    try:
        cls = _classes()[header["class"]]
        config = header["config"]
        if not isinstance(config, dict):
            raise TypeError(f"config is {config!r}, not an object")
    except (KeyError, TypeError) as exc:
        raise ResultsError(f"{name}: damaged learner file ({type(exc).__name__}: {exc})"
                           ) from None
    try:
        config = cls.config_type(**config)
    except ConfigError as exc:
        raise ResultsError(f"{name}: header key config: {exc}") from None
    except TypeError as exc:
        raise ResultsError(f"{name}: damaged learner file (config: {exc})") from None
    try:
        learner = cls(context, config)
        params = Params(**header["params"])
        loaded = {**arrays, **{k: arrays[v] for k, v in header["aliases"].items()}}
        tables = Tables(*(type(group)(*(loaded[f"{g}.{field}"] for field in group._fields))
                          for g, group in zip(Tables._fields, learner.tables, strict=True)))
        guards.check_tables(tables, params)
        if params.kind != learner.kind:
            raise ConfigError(f"params.kind is {params.kind}, a {cls.__name__} with this "
                              f"config is kind {learner.kind}")
    except (KeyError, TypeError, AttributeError, ConfigError) as exc:
        raise ResultsError(f"{name}: damaged learner file ({type(exc).__name__}: {exc})"
                           ) from None
    _check_params(name, params, learner.params)
    _check_finite(name, tables)
    learner.tables, learner.params, learner._model = tables, params, tables.model
    learner.q = tables.table.q
    return learner


_PARAM_RANGES = {"alpha": "(0, 1]", "gamma": "[0, 1)", "epsilon": "[0, 1]"}
"""The valid ranges of the params a config gives
(:class:`~gdq_pddl.learners.config.LearnerConfig`)."""


def _check_params(name: str, saved: Params, built: Params) -> None:
    """Refuse saved params other than those the config and the task give (all of a
    learner's params are: :meth:`~gdq_pddl.learners.tabular.TabularLearner._build`)."""
    for key, want in built._asdict().items():
        got = getattr(saved, key)
        if got != want:
            where = f", in {_PARAM_RANGES[key]}" if key in _PARAM_RANGES else ""
            raise ResultsError(f"{name}: header key params.{key} is {got!r}; save_learner "
                               f"writes what the config and the task give: {want!r}{where}")


def _check_finite(name: str, tables: Tables) -> None:
    """Refuse a float array holding NaN or an infinity (no learner writes one)."""
    for group, arrs in zip(Tables._fields, tables, strict=True):
        for field, x in zip(arrs._fields, arrs, strict=True):
            if x.dtype.kind == "f" and x.size and not np.isfinite(x).all():
                where = np.unravel_index(int(np.flatnonzero(~np.isfinite(x))[0]), x.shape)
                raise ResultsError(f"{name}: array {group}.{field} holds {x[where]!r} at "
                                   f"{tuple(int(i) for i in where)}; save_learner writes only "
                                   "finite values")


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
    identity: Mapping[str, str] | None = None
    """The identity of the task it was taken from (:mod:`~gdq_pddl.envs.identity`;
    None: not known); :func:`~gdq_pddl.learners.episodes.evaluate_policy` runs it only in
    an env whose states are numbered alike (:data:`~gdq_pddl.envs.identity.NUMBERING_KEYS`)."""

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
                   learner.context.n_env_actions, identity_of(learner.context))

    def act(self, state: int, rng: np.random.Generator | None = None) -> int:
        """The policy's action in ``state`` (``rng`` unused)."""
        return int(self.actions[guards.check_state("state", state, len(self.actions))])

    def observe(self, *step: object) -> None:
        """Learns nothing."""

    def check_env(self, env: object, name: str = "the policy") -> None:
        """Refuse (:class:`~gdq_pddl.errors.ResultsError` naming ``name``) an env whose
        instance numbers its states otherwise than the task the policy was taken from (a
        problem explored online: the policy's rows must be the first of the env's, which
        may have found more states since)."""
        instance = getattr(getattr(env, "unwrapped", env), "instance", None)
        saved = None if self.identity is None else dict(self.identity)
        now = identity_of(instance)
        n, have = _rows(saved), _rows(now)
        if n is not None and have is not None and n < have:  # the env found more since
            now = identity_of(instance, rows=n)
        check_identity(name, "policy", saved, now, "the env", NUMBERING_KEYS)

    def save(self, file: File) -> None:
        """Write the policy and its task's identity to ``file`` (module doc; a path is
        written as given)."""
        _write(file, "policy", len(self.actions), self.n_actions, {"actions": self.actions},
               identity=None if self.identity is None else dict(self.identity))

    @classmethod
    def load(cls, file: File) -> GreedyPolicy:
        """The policy saved in ``file`` (:meth:`save`)."""
        header, arrays = _read(file, "policy")
        identity = _saved_identity(_name(file), header)
        try:
            return cls(arrays["actions"], int(header["n_actions"]), identity)
        except (KeyError, TypeError, ValueError) as exc:
            raise ResultsError(f"{_name(file)}: damaged policy file ({exc})") from None
