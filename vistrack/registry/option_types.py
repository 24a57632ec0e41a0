"""Each model option's declared type and range, and the one check of a value against them (what
``vistrack.Tracker`` and ``run`` check a model's options with).

A model declares its options where it documents them: the numpydoc ``Parameters`` of its class (and
of the methods its constructor calls, such as :meth:`~vistrack.models.box.lost.LostAndFound.init_lost`)
and of the classes its builder passes keywords on to (:attr:`~vistrack.models.spec.ModelSpec.passes_on`).
A type line reads ``float``, ``int``, ``bool``, ``str``, ``dict``, ``tuple of float`` or a set of
choices ``{"a", "b"}``, with a range after it (``>= 0``, ``> 0``, ``in [0, 1]``, ``in (0, 1]``) and
``or None`` where ``None`` is taken::

    lambda_template : float, >= 0
    lost_confidence : float in [0, 1] or None
    prior_std : tuple of float, > 0

:func:`check_option` refuses, in one line naming the option, a value of another type, a number that is
not finite (NaN included, which every comparison lets through) and one outside the range. An option whose
type line is not of that form is checked by its default's type alone (a number: finite).
"""

from __future__ import annotations

import inspect
import math
import numbers
import re
from collections.abc import Mapping, Sequence
from dataclasses import dataclass

__all__ = ["Declared", "declared_options", "check_option", "check_model_options"]

_ENTRY = re.compile(r"^(\S[^:\n]*?)\s*:\s*([^\n]*)$", re.M)
_NUMBER = r"[-+]?(?:\d+\.?\d*(?:e[-+]?\d+)?|inf)"
_RANGE = re.compile(rf"^(?:(?P<op>>=|>|<=|<)\s*(?P<a>{_NUMBER})|in\s*(?P<lo>[\[(])\s*(?P<l>{_NUMBER})\s*,\s*"
                    rf"(?P<h>{_NUMBER})\s*(?P<hi>[\])]))$")
_BASE = re.compile(r"^(?P<base>float|int|bool|str|dict|tuple of (?:float|int)|\{[^}]*\})(?P<rest>.*)$")


@dataclass(frozen=True)
class Declared:
    """One option's declaration: ``kind`` (``float``, ``int``, ``bool``, ``str``, ``dict``, ``tuple``, a
    tuple of choices, or ``None``: its default's type), the element kind of a tuple, the range
    ``(low, low_open, high, high_open)`` or ``None``, whether ``None`` is taken, and the default."""

    kind: object
    element: str | None
    bounds: tuple | None
    none_ok: bool
    default: object

    def words(self):
        """What a value must be, in words: ``a finite number >= 0``, ``None or a number in [0, 1]``."""
        rng = ""
        if self.bounds is not None:
            lo, lo_open, hi, hi_open = self.bounds
            if hi == math.inf:
                rng = f" {'>' if lo_open else '>='} {lo:g}"
            elif lo == -math.inf:
                rng = f" {'<' if hi_open else '<='} {hi:g}"
            else:
                rng = f" in {'(' if lo_open else '['}{lo:g}, {hi:g}{')' if hi_open else ']'}"
        kind = self.kind
        what = {"float": f"a finite number{rng}", "int": f"an integer{rng}", "bool": "True or False",
                "str": "a string", "dict": "a dict"}.get(kind) if isinstance(kind, str) else None
        if kind == "tuple":
            n = len(self.default) if isinstance(self.default, tuple) else None
            what = f"{n or 'a tuple of'} {'integers' if self.element == 'int' else 'finite numbers'}{rng}"
        elif isinstance(kind, tuple):
            what = "one of " + ", ".join(repr(c) for c in kind)
        return ("None or " if self.none_ok else "") + (what or "a value")


def _declare(text, default):
    """A :class:`Declared` from a numpydoc type line ``text`` (and the option's ``default``)."""
    text = text.strip().rstrip(".")
    none_ok = default is None
    if text.endswith(" or None"):
        text, none_ok = text[:-len(" or None")].strip(), True
    m = _BASE.match(text)
    if m is None:
        return Declared(None, None, None, none_ok, default)
    base, rest = m["base"], m["rest"].strip().lstrip(",").strip()
    r = _RANGE.match(rest) if rest else None
    if rest and r is None:
        return Declared(None, None, None, none_ok, default)
    bounds = None
    if r is not None and r["op"]:
        a = float(r["a"])
        above = r["op"].startswith(">")
        bounds = (a, r["op"] == ">", math.inf, False) if above else (-math.inf, False, a, r["op"] == "<")
    elif r is not None:
        bounds = (float(r["l"]), r["lo"] == "(", float(r["h"]), r["hi"] == ")")
    if base.startswith("{"):  # a set of strings; anything else in braces is not declared here
        choices = tuple(re.findall(r"[\"']([^\"']*)[\"']", base))
        return Declared(choices or None, None, None, none_ok, default)
    if base.startswith("tuple"):
        return Declared("tuple", base.rsplit(" ", 1)[1], bounds, none_ok, default)
    return Declared(base, None, bounds, none_ok, default)


def _documented(objects):
    """``{name: type line}`` of the numpydoc ``Parameters`` of ``objects`` (classes: their docstring and
    their methods'), the first found for a name."""
    found = {}
    for obj in objects:
        docs = [inspect.getdoc(obj) or ""]
        if inspect.isclass(obj):
            docs += [inspect.getdoc(f) or "" for f in vars(obj).values() if inspect.isfunction(f)]
        for doc in docs:
            section = re.search(r"^Parameters\n-+\n(.*?)(?=^\w[\w ]*\n-+\n|\Z)", doc, re.S | re.M)
            for names, kind in _ENTRY.findall(section.group(1) if section else ""):
                for n in names.split(","):
                    found.setdefault(n.strip(), kind)
    return found


def _keywords(fn):
    """``{name: default}`` of the keyword parameters of ``fn`` with a default."""
    try:
        params = inspect.signature(fn).parameters.values()
    except (TypeError, ValueError):
        return {}
    return {p.name: p.default for p in params if p.default is not p.empty
            and p.kind in (p.POSITIONAL_OR_KEYWORD, p.KEYWORD_ONLY)}


def declared_options(spec):
    """``{name: Declared}`` of the options of the model of registry entry ``spec``: the keywords of its
    ``from_box``, of its class, of its several-target form's class and of the classes it passes keywords
    on to, declared where documented (module docstring)."""
    owners = [c for cls in (spec.model_class, spec.targets_class) if cls is not None for c in cls.__mro__
              if c is not object] + list(spec.passes_on)
    docs = _documented(owners)
    defaults = {}
    for fn in [spec.from_box, *(c.__init__ for c in owners)]:
        for name, default in (_keywords(fn) if fn is not None else {}).items():
            defaults.setdefault(name, default)
    return {n: _declare(docs.get(n, ""), d) for n, d in defaults.items()}


def _is_number(v, integer=False):
    if isinstance(v, bool) or not isinstance(v, numbers.Real):
        return False
    return isinstance(v, numbers.Integral) or (not integer and math.isfinite(v))


def _in_range(v, bounds):
    if bounds is None:
        return True
    lo, lo_open, hi, hi_open = bounds
    return (v > lo if lo_open else v >= lo) and (v < hi if hi_open else v <= hi)


def _fits(value, d):
    """Whether ``value`` is what ``d`` declares (its default's type where nothing is declared)."""
    kind = d.kind if d.kind is not None else _kind_of(d.default)
    if kind is None:
        return not (isinstance(value, float) and not math.isfinite(value))
    if isinstance(kind, tuple):
        return value in kind
    if kind in ("float", "int"):
        return _is_number(value, kind == "int") and _in_range(value, d.bounds)
    if kind == "tuple":
        n = len(d.default) if isinstance(d.default, tuple) else None
        return (isinstance(value, Sequence) and not isinstance(value, str) and (n is None or len(value) == n)
                and all(_is_number(v, d.element == "int") and _in_range(v, d.bounds) for v in value))
    return isinstance(value, {"bool": (bool,), "str": (str,), "dict": (Mapping,)}[kind])


def _kind_of(default):
    """The kind of an option whose type is not declared, from its default (``None``: any value)."""
    if isinstance(default, bool):
        return "bool"
    if isinstance(default, numbers.Integral):
        return "int"
    if isinstance(default, numbers.Real):
        return "float"
    return None


def check_option(name, value, declared):
    """Raise ``ValueError`` (one line naming ``name``) unless ``value`` fits its :class:`Declared`."""
    if value is None and declared.none_ok:
        return
    if not _fits(value, declared):
        words = declared.words() if declared.kind is not None or _kind_of(declared.default) is None else \
            Declared(_kind_of(declared.default), None, None, declared.none_ok, declared.default).words()
        raise ValueError(f"{name} must be {words}, got {value!r}")


def check_model_options(spec, options):
    """Check each of ``options`` (``{name: value}``) known to the model of ``spec`` against its declaration
    (:func:`declared_options`); an unknown name is left to the model's builder (a ``TypeError`` naming it)."""
    declared = declared_options(spec)
    for name, value in options.items():
        if name in declared:
            check_option(name, value, declared[name])
