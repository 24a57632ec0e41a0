"""Help that starts where users start (issue 37, item 7)."""

import click
from click.testing import CliRunner

from vistrack.cli import cli


def commands(cmd, path=()):
    if isinstance(cmd, click.Group):
        for name, sub in cmd.commands.items():
            yield from commands(sub, (*path, name))
    else:
        yield " ".join(path), cmd


def test_every_option_of_every_command_has_help_text():
    missing = [f"{path} {p.opts[0]}" for path, cmd in commands(cli) for p in cmd.params
               if isinstance(p, click.Option) and not (p.help or "").strip()]
    assert not missing, missing


def test_the_first_example_tracks_your_own_video_with_a_box():
    out = CliRunner().invoke(cli, ["--help"]).output
    examples = out.split("Examples:")[1].strip().splitlines()
    assert examples[0].split("#")[0].split() == ["vistrack", "run", "my_video.mp4", "--init", "x,y,w,h", "--out",
                                                 "annotated.mp4"]


def test_run_help_starts_with_the_box_model():
    out = CliRunner().invoke(cli, ["run", "--help"]).output
    first = out.split("Examples:")[1].strip().splitlines()[0]
    assert "--init" in first and "--model" not in first
