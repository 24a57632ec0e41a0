"""Shared by the CLI tests: run ``vistrack ARGV`` with click's ``CliRunner`` and capture its exit code
and output (the group's own ``main`` gives the one-line errors and exit codes, as on a console)."""

from click.testing import CliRunner

from vistrack.cli import cli


def run(argv, capsys=None):
    """``(exit code, stdout, stderr)`` of ``vistrack *argv`` (``capsys``: unused, kept for the callers)."""
    res = CliRunner().invoke(cli, [str(a) for a in argv], prog_name="vistrack", catch_exceptions=False)
    return res.exit_code, res.stdout, res.stderr
