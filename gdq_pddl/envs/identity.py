"""What a learner or a policy belongs to: an instance's *identity*, as files record it.

An identity is a flat ``{key: value}`` of strings (``docs/learners.md``). File keys
(:data:`FILE_KEYS`) read ``"<name> sha256:<hex>"``: the name (a path) says which file in
messages, the hash is what is compared, so a copy of a file elsewhere is the same file.
Other keys are compared whole. :data:`NUMBERING_KEYS` are those that say what the state
and action numbers mean (what a greedy policy needs); a loaded learner needs every key
(its tables hold its task's plans, prior and goal).
"""

from __future__ import annotations

import re
from collections.abc import Mapping
from pathlib import Path

from gdq_pddl.inputs import file_hash, text_hash
from gdq_pddl.resources import world_text

FILE_KEYS = ("domain", "problem", "dynamics", "world")
"""Keys whose value ends in the hash of a file's text (the part compared)."""
NUMBERING_KEYS = ("domain", "problem", "problem name", "learner states", "explored",
                  "states")
"""The keys that fix what state and action numbers mean (a greedy policy's)."""
PROBLEM_KEYS = ("domain", "problem", "problem name", "explored", "states")
"""The keys a learner's context and the env it runs in must share (a PDDL problem's: an
office learner may plan on another world's map, the knowledge experiments' wrong
knowledge)."""


def file_entry(name: str, digest: str | None) -> str:
    """The value of a file key: ``"<name> <digest>"`` (``digest`` None: ``sha256:unknown``,
    a file not read from a path)."""
    return f"{name} {digest or 'sha256:unknown'}"


BUILT_IN = ".toml (built in)"
"""How the source of a shipped world ends (``office.toml (built in)``)."""


def world_entry(source: str) -> str:
    """The value of the ``world`` key of a world read from ``source`` (a file, or a
    shipped world: its text's hash)."""
    if source.endswith(BUILT_IN):
        return file_entry(source, text_hash(world_text(source.removesuffix(BUILT_IN))))
    digest = file_hash(source) if source else "missing"
    return file_entry(source, None if digest == "missing" else digest)


def compared(key: str, value: object) -> str:
    """The part of ``value`` compared between identities (a file's hash, else all: also
    where the hash is not known, a text not read from a file)."""
    text = str(value)
    digest = text.rsplit(" ", 1)[-1]
    return digest if key in FILE_KEYS and digest != "sha256:unknown" else text


def first_difference(saved: Mapping[str, object], now: Mapping[str, object],
                     keys: tuple[str, ...] | None = None) -> tuple[str, str, str] | None:
    """The first key (of ``keys``; None: every key either has) whose values differ, with
    both values (``"(none)"`` where one side has no such key); None if they agree."""
    for key in keys or tuple(dict.fromkeys((*saved, *now))):
        if key not in saved and key not in now:
            continue
        a, b = saved.get(key), now.get(key)
        if a is None or b is None or compared(key, a) != compared(key, b):
            return key, "(none)" if a is None else str(a), "(none)" if b is None else str(b)
    return None


def describe(identity: Mapping[str, object]) -> str:
    """An identity in a few words: ``problem keys-1 (keys-1.pddl)``, ``task C of world
    office.toml (built in)``, with ``explored online`` where it was."""
    def name(key: str) -> str:
        return Path(str(identity[key]).rsplit(" ", 1)[0]).name

    if "problem name" in identity and "problem" in identity:
        text = f"problem {identity['problem name']} ({name('problem')})"
    elif "task" in identity and "world" in identity:
        text = f"task {identity['task']} of world {name('world')}"
    else:
        return "a task of unknown identity"
    return text + (" explored online" if "explored" in identity else "")


def shown(value: str) -> str:
    """``value`` as a message shows it: hashes cut to 12 digits."""
    return re.sub(r"sha256:([0-9a-f]{12})[0-9a-f]+", r"sha256:\1...", value)
