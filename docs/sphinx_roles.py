"""A griffe extension for the API reference: the docstrings' Sphinx roles (``:class:`~a.B```,
``:func:`f```, ...) shown as code (``B``, ``f``), as mkdocstrings does not read them."""

from __future__ import annotations

import re

import griffe

ROLE = re.compile(r":(?:py:)?(?:class|func|meth|mod|data|attr|exc|obj):`(~?)([^`]+)`")


def plain(text):
    """``text`` with each role replaced by a code span of its target (the last part after ``~``)."""
    return ROLE.sub(lambda m: "`" + (m.group(2).rsplit(".", 1)[-1] if m.group(1) else m.group(2)) + "`", text)


class SphinxRoles(griffe.Extension):
    """Rewrite the roles in every docstring as it is loaded."""

    def on_instance(self, *, obj, **kwargs):
        if obj.docstring is not None:
            obj.docstring.value = plain(obj.docstring.value)
