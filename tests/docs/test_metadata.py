"""The citation file and the licence say what pyproject.toml and the paper say."""

from __future__ import annotations

import re
import tomllib

import pytest
import yaml

from tests.helpers import REPO_ROOT as ROOT

PAPER_TITLE = "Guiding Robot Exploration in Reinforcement Learning via Automated Planning"
PAPER_AUTHORS = [("Yohei", "Hayamizu"), ("Saeid", "Amiri"), ("Kishan", "Chandan"),
                 ("Keiki", "Takadama"), ("Shiqi", "Zhang")]

# Citation File Format 1.2.0: the keys it defines (top level, and of a reference)
CFF_KEYS = {
    "abstract", "authors", "cff-version", "commit", "contact", "date-released", "doi",
    "identifiers", "keywords", "license", "license-url", "message", "preferred-citation",
    "references", "repository", "repository-artifact", "repository-code", "title", "type",
    "url", "version"}
CFF_REQUIRED = {"cff-version", "message", "title", "authors"}
REFERENCE_KEYS = {
    "abbreviation", "abstract", "authors", "collection-doi", "collection-title",
    "collection-type", "commit", "conference", "contact", "copyright", "data-type",
    "database", "database-provider", "date-accessed", "date-downloaded", "date-published",
    "date-released", "department", "doi", "edition", "editors", "editors-series", "end",
    "entry", "filename", "format", "identifiers", "institution", "isbn", "issn", "issue",
    "issue-date", "issue-title", "journal", "keywords", "languages", "license",
    "license-url", "loc-end", "loc-start", "location", "medium", "month", "nihmsid",
    "notes", "number", "number-volumes", "pages", "patent-states", "pmcid", "publisher",
    "recipients", "repository", "repository-artifact", "repository-code", "scope",
    "section", "senders", "start", "status", "term", "thesis-type", "title", "translators",
    "type", "url", "version", "volume", "volume-title", "year", "year-original"}
REFERENCE_REQUIRED = {"type", "title", "authors"}
PERSON_KEYS = {"given-names", "family-names", "name-particle", "name-suffix", "affiliation",
               "address", "city", "country", "email", "orcid", "alias", "website"}
DOI = re.compile(r"^10\.\d{4,9}(\.\d+)?/[A-Za-z0-9:/_;\-.()\[\]\\]+$")


def pyproject() -> dict:
    return tomllib.loads((ROOT / "pyproject.toml").read_text(encoding="utf-8"))["project"]


@pytest.fixture(scope="module")
def cff() -> dict:
    return yaml.safe_load((ROOT / "CITATION.cff").read_text(encoding="utf-8"))


def check_authors(authors, where: str) -> None:
    assert isinstance(authors, list) and authors, f"{where}: authors must be a non-empty list"
    for a in authors:
        assert isinstance(a, dict), f"{where}: an author must be a mapping"
        if "name" in a:  # an entity
            assert isinstance(a["name"], str) and a["name"]
        else:  # a person
            assert a.keys() <= PERSON_KEYS, f"{where}: unknown person keys {a.keys() - PERSON_KEYS}"
            assert a.get("family-names"), f"{where}: a person needs family-names"


def check_reference(ref: dict, where: str) -> None:
    assert ref.keys() >= REFERENCE_REQUIRED, f"{where}: needs {REFERENCE_REQUIRED - ref.keys()}"
    assert ref.keys() <= REFERENCE_KEYS, f"{where}: unknown keys {ref.keys() - REFERENCE_KEYS}"
    check_authors(ref["authors"], where)
    if "doi" in ref:
        assert DOI.match(str(ref["doi"])), f"{where}: malformed doi {ref['doi']!r}"
    for ident in ref.get("identifiers", []):
        assert ident["type"] in {"doi", "url", "swh", "other"} and ident["value"]


def test_citation_file_is_valid_cff_1_2(cff):
    assert cff.keys() >= CFF_REQUIRED, f"missing {CFF_REQUIRED - cff.keys()}"
    assert cff.keys() <= CFF_KEYS, f"unknown keys {cff.keys() - CFF_KEYS}"
    assert cff["cff-version"] == "1.2.0"
    assert cff.get("type", "software") == "software"
    assert isinstance(cff["message"], str) and isinstance(cff["title"], str)
    check_authors(cff["authors"], "authors")
    for i, ref in enumerate([cff["preferred-citation"], *cff.get("references", [])]):
        check_reference(ref, f"reference {i}")


def test_citation_cites_this_software_and_the_icaps_paper(cff):
    project = pyproject()
    assert cff["version"] == project["version"]
    assert cff["license"] == project["license"]
    paper = cff["preferred-citation"]
    assert paper["type"] == "conference-paper"
    assert paper["title"] == PAPER_TITLE
    assert [(a["given-names"], a["family-names"]) for a in paper["authors"]] == PAPER_AUTHORS
    assert "ICAPS 2021" in paper["conference"]["name"]
    assert "Automated Planning and Scheduling" in paper["collection-title"]
    assert (paper["year"], paper["volume"], paper["start"], paper["end"]) == (2021, 31, 625, 633)
    assert any("2004.11456" in i["value"] for i in paper["identifiers"])


def test_licence_file_matches_pyproject():
    text = (ROOT / "LICENSE").read_text(encoding="utf-8")
    assert pyproject()["license"] == "MIT"
    assert text.splitlines()[0] == "MIT License"
    assert "Permission is hereby granted, free of charge" in text
    assert re.search(r"^Copyright \(c\) \d{4} \S", text, re.M)


@pytest.mark.parametrize("doc", ["README.md", "docs/tutorial.md", "domains/office.pddl",
                                 "gdq_pddl/data/office.toml"])
def test_the_paper_is_cited_as_icaps_2021(doc):
    text = (ROOT / doc).read_text(encoding="utf-8")
    assert "AAAI" not in text
    assert "ICAPS 2021" in text
