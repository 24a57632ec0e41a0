"""Shared click parameter types, and options whose defaults are read from the library (:func:`option`)."""

from __future__ import annotations

import dataclasses
import inspect
import math
from collections.abc import Mapping

import click

from vistrack.io.numbers import parse_float, parse_int
from vistrack.io.outputs import check_writable as writable
from vistrack.io.video_errors import quoted

__all__ = ["Ratio", "FloatRange", "Output", "IntList", "FloatList", "StrList", "Box", "Size", "Fraction", "SEED",
           "check_writable", "check_outputs", "Sourced", "option", "default_of", "joined", "size_text"]

#: ``--seed``: numpy takes any non-negative integer
SEED = click.IntRange(min=0)


class IntList(click.ParamType):
    """Comma-separated integers, e.g. ``100,500,3000``."""

    name = "N,N,..."

    def convert(self, value, param, ctx):
        """Parse ``value`` into a list of ints; a bad value fails with click's one-line usage error."""
        if isinstance(value, list):
            return value
        try:
            out = [parse_int(v) for v in str(value).split(",") if v.strip()]
        except ValueError:
            self.fail(f"expected comma-separated integers, got {quoted(value)}", param, ctx)
        return _no_repeats(out, self, param, ctx)


class FloatList(click.ParamType):
    """Comma-separated finite numbers, e.g. ``40,80``."""

    name = "X,X,..."

    def convert(self, value, param, ctx):
        """Parse ``value`` into a list of finite floats; a bad value fails with click's one-line usage error."""
        if isinstance(value, list):
            return value
        try:
            out = [parse_float(v) for v in str(value).split(",") if v.strip()]
        except ValueError:
            out = None
        if out is None or not all(v == v and abs(v) != float("inf") for v in out):
            self.fail(f"expected comma-separated finite numbers, got {quoted(value)}", param, ctx)
        return out


class StrList(click.ParamType):
    """Comma-separated names, e.g. ``bootstrap,avpf,lis``."""

    name = "A,B,..."

    def convert(self, value, param, ctx):
        """Parse ``value`` into a list of names; a bad value fails with click's one-line usage error."""
        if isinstance(value, list):
            return value
        return _no_repeats([v.strip() for v in str(value).split(",") if v.strip()], self, param, ctx)


def _no_repeats(values, ptype, param, ctx):
    """``values``, failing with one line when one is listed twice (its runs would be counted twice)."""
    seen = set()
    for v in values:
        if v in seen:
            ptype.fail(f"{v if isinstance(v, int) or v.isprintable() else quoted(v)} is listed twice (each is run "
                       "once: list it once)", param, ctx)
        seen.add(v)
    return values


class Box(click.ParamType):
    """``x,y,w,h`` in pixels."""

    name = "x,y,w,h"

    def convert(self, value, param, ctx):
        """Parse ``value`` into an ``(x, y, w, h)`` tuple of floats; a bad value fails with click's one-line usage
        error."""
        if isinstance(value, tuple):
            return value
        try:
            v = tuple(parse_float(s) for s in str(value).split(","))
        except ValueError:
            self.fail(f"expected four numbers x,y,w,h, got {quoted(value)}", param, ctx)
        if len(v) != 4:
            self.fail(f"expected four numbers x,y,w,h, got {len(v)}", param, ctx)
        if not all(abs(x) < float("inf") for x in v):  # also false for NaN
            self.fail(f"expected four finite numbers x,y,w,h, got {quoted(value)}", param, ctx)
        if v[2] <= 0 or v[3] <= 0:
            self.fail(f"width and height must be positive, got {v[2]:g}x{v[3]:g}", param, ctx)
        return v


class FloatRange(click.FloatRange):
    """click's ``FloatRange``, read strictly (:func:`~vistrack.io.numbers.parse_float`) and refusing a
    number that is not finite: ``nan`` passes every comparison of click's range check (``--upscale nan``
    reached OpenCV, ``--noise nan`` a JSON file as ``NaN``). Every float option takes this type."""

    def convert(self, value, param, ctx):
        """Parse ``value`` into a finite float in the range; a bad value fails with click's one-line usage error."""
        if isinstance(value, str):
            try:
                value = parse_float(value)
            except ValueError:
                self.fail(f"expected a number, got {quoted(value)}", param, ctx)
        if isinstance(value, float) and not math.isfinite(value):
            self.fail(f"expected a number{self._describe_range()}, got {value}", param, ctx)
        return super().convert(value, param, ctx)

    def _describe_range(self):
        return f" in [{self.min:g}, {self.max:g}]" if self.min is not None and self.max is not None else ""


class Fraction(FloatRange):
    """A finite number in ``[0, 1]`` (``nan`` is refused, not read as "never")."""

    def __init__(self):
        super().__init__(0.0, 1.0)


class Size(click.ParamType):
    """``WIDTHxHEIGHT``."""

    name = "WxH"

    def convert(self, value, param, ctx):
        """Parse ``value`` into a ``(width, height)`` tuple; a bad value fails with click's one-line usage error."""
        if isinstance(value, tuple):
            return value
        try:
            w, h = (parse_int(v) for v in str(value).lower().split("x"))
        except ValueError:
            self.fail(f"expected WIDTHxHEIGHT such as 320x240, got {quoted(value)}", param, ctx)
        if w < 64 or h < 48:
            self.fail(f"frame size {w}x{h} is too small (at least 64x48)", param, ctx)
        if max(w, h) > 8192 or w * h > 4096 * 4096:
            self.fail(f"frame size {w}x{h} is too large (at most 8192 a side and 4096x4096 pixels in all)", param, ctx)
        return (w, h)


def check_writable(path, what, create=False):
    """Raise ``click.ClickException`` unless ``path`` can be written as a file (``create``: its missing
    folders made first; :func:`vistrack.io.outputs.check_writable`)."""
    try:
        writable(path, what, create)
    except ValueError as e:
        raise click.ClickException(str(e)) from None


def check_outputs(outputs, video=None, inputs=()):
    """Raise ``click.ClickException`` when two of ``outputs`` (``{option: path or None}``) are one
    file, or one would overwrite what the command reads: ``video`` (a video file, or a clip, image or
    clips folder: its video, ground truth, meta.json or frames) or one of ``inputs`` (a template, an
    ``--init-gt`` file, the source of a stressed copy). Files are compared by identity (a hard or
    symbolic link of an input is that input), names that do not exist yet by their real path; devices
    such as ``/dev/null`` may be shared (:func:`vistrack.io.outputs.check_outputs`). The inputs stay
    declared for the command: every writer refuses them too."""
    from vistrack.io.outputs import check_outputs as check

    try:
        check(outputs, [video, *inputs])
    except ValueError as e:
        raise click.ClickException(str(e)) from None


class Output(click.Path):
    """The path of an output file or folder, local: a URL is refused with one usage line (a ``Path`` would
    have made ``http:/host/...`` folders here)."""

    def convert(self, value, param, ctx):
        """``value`` checked as ``click.Path`` checks it, unless it is a URL."""
        if "://" in str(value):
            self.fail(f"{value} is a URL; vistrack writes its outputs to local files: give a local path", param, ctx)
        return super().convert(value, param, ctx)


class Ratio(click.ParamType):
    """``A:B``, two positive numbers (``--zoom 1:0.6``, ``--gain 0.3:1.6``)."""

    name = "A:B"

    def convert(self, value, param, ctx):
        """Parse ``value`` into a pair of positive floats; a bad value fails with one usage line."""
        if isinstance(value, tuple):
            return value
        try:
            a, b = (parse_float(v) for v in str(value).split(":"))
        except ValueError:
            self.fail(f"expected two numbers A:B, got {value!r}", param, ctx)
        if not (0 < a < float("inf") and 0 < b < float("inf")):
            self.fail(f"expected two positive numbers A:B, got {value!r}", param, ctx)
        return a, b


def default_of(source, key):
    """The default of ``key`` where the library keeps it, ``source``: a config dataclass (its field's default,
    or its factory's value; or a class attribute), a function or class (its keyword's default), a mapping (its
    item) or any other object (its attribute: a registry constant, an entry's field)."""
    if isinstance(source, type) and dataclasses.is_dataclass(source):
        field = {f.name: f for f in dataclasses.fields(source)}.get(key)
        if field is not None:
            return field.default if field.default is not dataclasses.MISSING else field.default_factory()
        return getattr(source, key)
    if isinstance(source, Mapping):
        return source[key]
    if callable(source):
        p = inspect.signature(source).parameters.get(key)
        if p is not None and p.default is not p.empty:
            return p.default
    return getattr(source, key)


class Sourced(click.Option):
    """A click option whose default is read from the library (:func:`default_of` of ``source`` and ``key``,
    by default the option's own name), never typed out beside it: ``shown`` turns it into what the command
    line takes (``[100, 750]`` into ``100,750``)."""

    def __init__(self, param_decls, *, source, key=None, shown=None, **attrs):
        self.source, self.key = source, key or click.Option(param_decls).name
        self.shown = shown
        value = default_of(source, self.key)
        super().__init__(param_decls, default=value if shown is None else shown(value), **attrs)


def option(*param_decls, source, key=None, shown=None, **attrs):
    """``click.option`` with its default read from ``source`` (:class:`Sourced`) and shown in ``--help``."""
    attrs.setdefault("show_default", True)
    return click.option(*param_decls, cls=Sourced, source=source, key=key, shown=shown, **attrs)


def joined(values):
    """``[100, 750]`` as ``--particles`` takes it: ``100,750``."""
    return ",".join(str(v) for v in values)


def size_text(size):
    """``(320, 240)`` as ``--size`` takes it: ``320x240``."""
    return f"{size[0]}x{size[1]}"
