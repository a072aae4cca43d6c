"""``gdq-pddl methods``: every learner of the registry (this package's and other packages'),
with its settings, their types, ranges, defaults and one-line docs."""

from __future__ import annotations

import argparse
import json

from gdq_pddl.learners import registry


def register_methods(sub) -> None:
    p = sub.add_parser("methods", help="the learners --method takes, with their settings",
                       description="List every learner (this package's and those registered "
                                   "under the `gdq_pddl.learners` entry-point group) with its "
                                   "settings: --method 'NAME:key=value,key=value' sets them "
                                   "(names in any case).")
    p.add_argument("names", nargs="*", metavar="NAME", help="only these learners")
    p.add_argument("--json", action="store_true", help="machine-readable output")
    p.set_defaults(func=cmd_methods)


def described() -> list[dict]:
    """Every learner as ``gdq-pddl methods --json`` prints it."""
    return [{"name": e.name, "aliases": list(e.aliases),
             "description": e.description + (f" ({need})" if (need := registry.missing(e))
                                             else ""),
             "knowledge": e.knowledge, "online": e.online, "colour": e.colour,
             "fixed": dict(e.fixed),
             "settings": [{"name": n, "type": t, "default": d, "doc": doc}
                          for n, t, d, doc in registry.settings_table(e)]}
            for e in registry.entries()]


def cmd_methods(args: argparse.Namespace) -> int:
    wanted = {registry.entry(n).name for n in args.names}  # a ConfigError if unknown
    rows = [d for d in described() if not wanted or d["name"] in wanted]
    if args.json:
        print(json.dumps(rows, indent=2))
        return 0
    for d in rows:
        fixed = "".join(f", {k}={v}" for k, v in d["fixed"].items())
        print(f"{d['name']}: {d['description']} (knowledge: {d['knowledge']}{fixed})")
        for s in d["settings"]:
            print(f"  {s['name']:22s} {s['default']:>8s}  {s['type']}")
            print(f"  {'':22s} {'':>8s}  {s['doc']}")
    for why in registry.plugin_problems():
        print(f"warning: {why}")
    return 0
