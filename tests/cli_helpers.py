"""Shared by the CLI tests: run ``vistrack ARGV`` in-process and capture its exit code and output."""

import pytest

from vistrack.cli import main


def run(argv, capsys):
    """``(exit code, stdout, stderr)`` of ``vistrack *argv``."""
    with pytest.raises(SystemExit) as e:
        main(argv)
    out = capsys.readouterr()
    return e.value.code, out.out, out.err
