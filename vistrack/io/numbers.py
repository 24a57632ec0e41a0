"""Numbers as users and data files write them, read strictly: an optional sign, digits with an optional
decimal point and exponent, or the words ``nan``/``inf`` (which a caller may then refuse). Python's own
``float`` and ``int`` also take ``4_1`` (as 41), Unicode digits (``٣``) and, for ``int``, spaces inside
signs; a box typed ``4_1,48,25,19`` must not become 41."""

from __future__ import annotations

import re

__all__ = ["parse_float", "parse_int"]

_FLOAT = re.compile(r"[-+]?(?:(?:\d+\.?\d*|\.\d+)(?:e[-+]?\d+)?|nan|inf|infinity)", re.ASCII | re.IGNORECASE)
_INT = re.compile(r"[-+]?\d+", re.ASCII)


def parse_float(text):
    """``text`` (spaces around it allowed) as a float; ``ValueError`` for anything else."""
    s = str(text).strip()
    if not _FLOAT.fullmatch(s):
        raise ValueError(f"not a number: {text!r}")
    return float(s)


def parse_int(text):
    """``text`` (spaces around it allowed) as an int; ``ValueError`` for anything else."""
    s = str(text).strip()
    if not _INT.fullmatch(s):
        raise ValueError(f"not an integer: {text!r}")
    return int(s)
