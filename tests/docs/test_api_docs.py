"""Every public name has a docstring, and pdoc reads them all without a warning (the
site's API page, docs/reference/api.md, renders the same docstrings with mkdocstrings;
tests/docs/test_site.py builds it): the docs cannot rot."""

from __future__ import annotations

import importlib
import warnings

import pytest

PUBLIC = ("gdq_pddl", "gdq_pddl.envs", "gdq_pddl.envs.office", "gdq_pddl.envs.pddl_env",
          "gdq_pddl.learners", "gdq_pddl.wrappers", "gdq_pddl.errors",
          "gdq_pddl.resources")
"""The modules of the API page: the package and the submodules its ``__all__`` names."""


def undocumented(doc, found: list[str]) -> list[str]:
    """The public names under the pdoc ``doc`` (defined in this package) without a
    docstring; a module's constants are exempt (pdoc loses the docstring of one
    re-exported: :data:`gdq_pddl.learners.METHODS` is documented where it is defined)."""
    pdoc_doc = importlib.import_module("pdoc.doc")
    for member in doc.members.values():
        if member.name.startswith("_") or not member.taken_from[0].startswith("gdq_pddl") \
                or isinstance(doc, pdoc_doc.Module) and isinstance(member, pdoc_doc.Variable):
            continue
        if not member.docstring.strip():
            found.append(member.fullname)
        if isinstance(member, pdoc_doc.Class):
            undocumented(member, found)
    return found


def test_the_api_page_builds_and_documents_every_public_name(tmp_path):
    pdoc = pytest.importorskip("pdoc")  # the test extra has it
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        pdoc.pdoc("gdq_pddl", output_directory=tmp_path)
    assert [str(w.message) for w in caught] == []
    assert {p.relative_to(tmp_path).as_posix() for p in tmp_path.rglob("*.html")} >= \
        {"index.html", *(f"{m.replace('.', '/')}.html" for m in PUBLIC)}
    missing = [name for m in PUBLIC
               for name in undocumented(pdoc.doc.Module.from_name(m), [])]
    assert missing == []


def test_config_fields_show_in_help():
    from gdq_pddl.learners import GDQConfig

    doc = GDQConfig.__doc__
    for field in ("alpha", "gamma", "epsilon", "variant", "explore_all", "plan_tolerance"):
        assert f"\n    {field}: " in doc
    assert "Step size of the temporal-difference update" in doc
