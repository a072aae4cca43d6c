"""A mkdocs hook: the docstrings' Sphinx roles (``:func:`x```, ``:mod:`~a.b```) shown as
code, without the role's name or the tilde, on the pages mkdocstrings renders."""

from __future__ import annotations

import re

ROLE = re.compile(r":(?:func|mod|class|data|meth|attr|exc|obj):<code>~?")


def on_post_page(output: str, **_: object) -> str:
    """The page's HTML with every role prefix left out."""
    return ROLE.sub("<code>", output)
