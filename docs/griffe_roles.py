"""A griffe extension for the API reference: the docstrings' Sphinx roles (``:func:`name```,
``:class:`~mod.Name```…) become plain code spans, and a paragraph's closing ``::`` (reST's
literal-block marker) a colon, so that mkdocstrings' Markdown shows them as code, not as markup."""

from __future__ import annotations

import re
from typing import Any

import griffe

ROLE = re.compile(r":(?:func|class|meth|mod|data|attr|exc|obj|const):`~?([^`]+)`")
LITERAL = re.compile(r"(\S)::$", re.MULTILINE)


class SphinxRoles(griffe.Extension):
    """Rewrites every loaded object's docstring (see the module docstring)."""

    def on_instance(self, *, obj: griffe.Object, **kwargs: Any) -> None:
        if obj.docstring is not None:
            obj.docstring.value = LITERAL.sub(r"\1:", ROLE.sub(r"`\1`", obj.docstring.value))
