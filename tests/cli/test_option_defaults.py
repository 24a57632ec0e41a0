"""Every command's option defaults are the library's (issue 52): read from the config dataclass, the keyword
default of the library function the command calls, or the registry, never typed out a second time."""

import click
import pytest

from vistrack.cli import cli
from vistrack.cli.options import Sourced, default_of

#: click 8.2+: an option given no default (earlier versions: ``None``)
UNSET = getattr(getattr(click, "_utils", None), "UNSET", None)


def _commands(cmd=cli, path=()):
    if isinstance(cmd, click.Group):
        for name, sub in cmd.commands.items():
            yield from _commands(sub, (*path, name))
    else:
        yield " ".join(path), cmd


def _defaulted(cmd):
    """The options of ``cmd`` that have a default: not none, not an unset flag, not an empty repeat."""
    for p in cmd.params:
        if not isinstance(p, click.Option) or p.default is None or p.default is UNSET:
            continue
        if (p.is_flag and p.default is False and not p.secondary_opts) or (p.multiple and not p.default):
            continue
        yield p


def _plain(v):
    """Tuples as lists, all the way down: what a parameter type returns against what the library keeps."""
    return [_plain(x) for x in v] if isinstance(v, (list, tuple)) else v


COMMANDS = dict(_commands())


def test_every_command_is_walked():
    assert {"run", "eval", "demo", "trax", "fit-plate", "train-search", "synth contour", "synth-suite",
            "reproduce bearings", "reproduce landmarks", "reproduce hs-sir"} <= set(COMMANDS)


@pytest.mark.parametrize("name", sorted(COMMANDS))
def test_each_option_default_is_its_source(name):
    """Each option with a default reads it from its source (:class:`~vistrack.cli.options.Sourced`), and the
    value the command line parses from it is the source's."""
    cmd = COMMANDS[name]
    ctx = click.Context(cmd)
    literal = [p.opts[-1] for p in _defaulted(cmd) if not isinstance(p, Sourced)]
    assert literal == [], f"{name}: options with a default typed out instead of read from the library"
    for p in _defaulted(cmd):
        want = default_of(p.source, p.key)
        got = p.type_cast_value(ctx, p.default)
        if isinstance(p.type, click.Choice):
            want = str(want)  # a choice is parsed as its name (--k 5)
        assert _plain(got) == _plain(want), f"{name} {p.opts[-1]}: {got!r}, its source {p.source!r} has {want!r}"
