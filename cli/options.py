"""Shared click parameter types."""

from __future__ import annotations

import os

import click

__all__ = ["IntList", "StrList", "check_writable"]


class IntList(click.ParamType):
    """Comma-separated integers, e.g. ``100,500,3000``."""

    name = "N,N,..."

    def convert(self, value, param, ctx):
        if isinstance(value, list):
            return value
        try:
            return [int(v) for v in str(value).split(",") if v.strip()]
        except ValueError:
            self.fail(f"expected comma-separated integers, got {value!r}", param, ctx)


class StrList(click.ParamType):
    """Comma-separated names, e.g. ``bootstrap,avpf,lis``."""

    name = "A,B,..."

    def convert(self, value, param, ctx):
        if isinstance(value, list):
            return value
        return [v.strip() for v in str(value).split(",") if v.strip()]


def check_writable(path, what):
    """Raise ``click.ClickException`` unless ``path`` can be written as a file."""
    if path is None:
        return
    path = os.path.abspath(path)
    parent = os.path.dirname(path)
    if os.path.isdir(path):
        raise click.ClickException(f"{what} {path} is a directory, not a file")
    if not os.path.isdir(parent):
        raise click.ClickException(f"cannot write {what} {path}: folder {parent} does not exist")
    if not os.access(parent, os.W_OK) or (os.path.exists(path) and not os.access(path, os.W_OK)):
        raise click.ClickException(f"cannot write {what} {path}: permission denied")
