"""Option values that break a command: bad numbers, boxes, sizes and names, each one clear line naming the
option and what to give, before any work."""

from __future__ import annotations

import os
import sys
import warnings

import pytest

from cli_helpers import run
from fault_helpers import (
    image_folder,
    one_error,
    otb_folder,
    write_video,
)


@pytest.mark.parametrize("args, message", [
    (["--init", "nan,1,2,3"], "expected four finite numbers"),
    (["--init", "10,10,inf,20"], "expected four finite numbers"),
    (["--init", "10,10,20,20", "-n", "100000000"], "particles need about"),
    (["--init", "10,10,20,20", "--ess-threshold", "nan"], "expected a number in [0, 1], got nan"),
    (["--init", "10,10,20,20", "--seed", "-1"], "-1 is not in the range"),
], ids=["init-nan", "init-inf", "n-huge", "ess-nan", "seed-negative"])
def test_bad_numbers_are_one_error_line(tmp_path, capsys, args, message):
    video = tmp_path / "v.avi"
    write_video(video, 3)
    with _no_warnings():
        code, out, err = run(["run", str(video), *args, "--track", str(tmp_path / "t.csv")], capsys)
    assert code != 0 and message in err and "Traceback" not in err
    assert err.count("Error:") == 1
    assert not (tmp_path / "t.csv").exists()

class _no_warnings:
    """No Python warning (numpy's RuntimeWarning on inf, ...) reaches the user."""

    def __enter__(self):

        self._cm = warnings.catch_warnings(record=True)
        self.caught = self._cm.__enter__()
        warnings.simplefilter("always")
        return self

    def __exit__(self, *exc):
        self._cm.__exit__(*exc)
        assert not self.caught, [str(w.message) for w in self.caught]

@pytest.mark.parametrize("model", ["box", "contour", "plate"])
def test_4_huge_or_far_start_boxes_are_refused(tmp_path, capsys, model):
    image_folder(tmp_path / "c", 2)
    for box, words in (("0,0,1e12,1e12", "far larger than the 160x120 frame"),
                       ("159,119,30,30", "lies outside the 160x120 frame")):
        code, _, err = run(["run", str(tmp_path / "c"), "--model", model, "--init", box, "-q"], capsys)
        one_error(code, err, words)

def test_5_13_results_dirs_of_one_name_or_an_algorithms_name(tmp_path, capsys):
    image_folder(tmp_path / "c", 6)
    for d, n in (("a/mt", 6), ("b/mt", 4), ("lis", 6)):
        (tmp_path / d).mkdir(parents=True)
        (tmp_path / d / "c.txt").write_text("40,50,25,19\n" * n)
    code, _, err = run(["eval", str(tmp_path / "c"), "--algos", "", "--results-dir", str(tmp_path / "a/mt"),
                        "--results-dir", str(tmp_path / "b/mt"), "--out", str(tmp_path / "e"), "-q"], capsys)
    one_error(code, err, "the same name 'mt'")
    code, _, err = run(["eval", str(tmp_path / "c"), "--algos", "", "--results-dir", str(tmp_path / "lis"),
                        "--out", str(tmp_path / "e"), "-q"], capsys)
    one_error(code, err, "named like vistrack's algorithm 'lis'")

@pytest.mark.parametrize("args, words", [
    (["eval", "{c}", "--algos", "lis", "--particles", "100,100"], "100 is listed twice"),
    (["eval", "{c}", "--algos", "lis,lis", "--particles", "10"], "lis is listed twice"),
    (["synth", "contour", "--out", "{o}", "--size", "321x241", "--frames", "2"], "needs even sides"),
    (["synth", "contour", "--out", "{o}", "--size", "8192x2048", "--frames", "2"], "at most 8190"),
    (["eval", "{c}", "--algos", "lis,bootstrap", "--particles", "20", "--equal-time", "--runs", "1"],
     "it needs at least 3"),
], ids=["particles-twice", "algos-twice", "odd-size", "size-8192", "equal-time-1-frame"])
def test_13_14_option_values_that_would_mislead(tmp_path, capsys, args, words):
    image_folder(tmp_path / "c", 1)
    code, _, err = run([a.format(c=tmp_path / "c", o=tmp_path / "o") for a in args] + ["--out", str(tmp_path / "e")]
                       if args[0] == "eval" else [a.format(c=tmp_path / "c", o=tmp_path / "o") for a in args], capsys)
    line = one_error(code, err, words)
    assert len(line) < 300

def test_13_demo_says_how_many_real_frames_it_took(tmp_path, capsys, monkeypatch):

    demo = sys.modules["vistrack.demo.steps"]
    calls = []
    monkeypatch.setattr(demo, "compare",
                        lambda clip, entries, model, runs, seed, out, **hooks: calls.append(clip) or "table")
    monkeypatch.setattr(demo, "make_demo_clip", lambda *a, **k: None)
    monkeypatch.setattr(demo, "DEMO_ENTRIES", ())
    image_folder(tmp_path / "real", 12)
    code, out, err = run(["demo", "--out", str(tmp_path / "d"), "--real-clip", str(tmp_path / "real"),
                          "--real-frames", "60", "--runs", "1"], capsys)
    assert code == 0, err
    assert "all 12 frames (fewer than --real-frames 60)" in out and "the first 60 frames" not in out

def test_14_a_device_or_pipe_is_named_as_such(tmp_path, capsys):
    fifo = tmp_path / "fifo"
    os.mkfifo(fifo)
    for path in ("/dev/zero", str(fifo)):
        code, _, err = run(["run", path, "--init", "1,1,5,5", "-q"], capsys)
        one_error(code, err, "not a regular file or folder")

def test_14_eval_out_with_a_file_where_tasks_go_fails_before_the_grid(tmp_path, capsys, monkeypatch):
    import vistrack.batch.cluster as grid

    image_folder(tmp_path / "c", 3)
    (tmp_path / "E").mkdir()
    (tmp_path / "E" / "tasks").write_text("a file")
    monkeypatch.setattr(grid, "run_grid", lambda *a, **k: pytest.fail("the grid ran"))
    code, _, err = run(["eval", str(tmp_path / "c"), "--algos", "lis", "--particles", "10", "--runs", "1",
                        "--out", str(tmp_path / "E")], capsys)
    one_error(code, err, "tasks is a file")

def test_init_gt_given_a_folder_says_so(tmp_path):
    seq = otb_folder(tmp_path / "seq", 3)
    code, _, err = run(["run", seq, "--init-gt", seq, "-q"])
    assert "does not exist" not in one_error(code, err, f"--init-gt: {seq} is a folder; give a ground-truth file")


# ------------------------------------------------------------------ the fourth sweep (issue 55)


@pytest.mark.parametrize("text", ["4_1,48,25,19", "٣,48,25,19", "0x10,48,25,19", "41 ,48,25,1 9"])
def test_init_is_parsed_strictly(tmp_path, capsys, text):
    """--init '4_1,48,25,19' was read as 41 (Python's float takes underscores, and Unicode digits)."""
    video = tmp_path / "v.avi"
    write_video(video, 3)
    code, _, err = run(["run", video, "--init", text, "-q"], capsys)
    one_error(code, err, "'--init': expected four numbers x,y,w,h")


def test_strict_numbers_known_answers():
    from vistrack.io.numbers import parse_float, parse_int

    assert [parse_float(s) for s in ("41", " -4.5 ", "1e3", ".5", "5.", "+2E-1")] == [41, -4.5, 1000, 0.5, 5, 0.2]
    assert str(parse_float("nan")) == "nan" and parse_float("-inf") == float("-inf")
    assert parse_int(" 17 ") == 17
    for bad in ("4_1", "٣", "0x10", "1e", "", "1 2", "½"):
        with pytest.raises(ValueError):
            parse_float(bad)
    for bad in ("1.0", "1_000", "1e3"):
        with pytest.raises(ValueError):
            parse_int(bad)


def _float_options():
    """Every (command path, option) of the command line whose values are floats."""
    import click

    from vistrack.cli import cli

    def walk(cmd, path):
        if isinstance(cmd, click.Group):
            for name, sub in cmd.commands.items():
                yield from walk(sub, [*path, name])
            return
        for p in cmd.params:
            if isinstance(p, click.Option) and isinstance(p.type, (click.types.FloatParamType, click.FloatRange)):
                yield path, p.opts[0]

    return list(walk(cli, []))


def test_every_float_option_refuses_nan():
    """click's FloatRange lets NaN through (every comparison with it is false): synth plate-on-car
    --upscale nan reached OpenCV ('inv_scale_x > 0'), --noise nan wrote "noise": NaN into composite.json,
    --width nan gave 'cannot convert float NaN to integer'. Every float option is options.FloatRange."""
    from vistrack.cli.options import FloatRange

    found = _float_options()
    assert {opt for _, opt in found} >= {"--upscale", "--noise", "--width", "--blur", "--shake", "--gap",
                                         "--ess-threshold", "--occlusion"}
    for path, opt in found:
        from vistrack.cli import cli

        cmd = cli
        for name in path:
            cmd = cmd.commands[name]
        ptype = next(p.type for p in cmd.params if p.opts[0] == opt)
        assert isinstance(ptype, FloatRange), (path, opt)
        with pytest.raises(Exception) as e:
            ptype.convert("nan", None, None)
        assert "got nan" in str(e.value.format_message()), (path, opt)


@pytest.mark.parametrize("opt", ["--upscale", "--noise", "--width", "--blur"])
def test_plate_on_car_refuses_nan(tmp_path, capsys, opt):
    image_folder(tmp_path / "car", 3)
    code, _, err = run(["synth", "plate-on-car", tmp_path / "car", "--out", tmp_path / "o", opt, "nan"], capsys)
    one_error(code, err, f"Invalid value for '{opt}': expected a number in [", "got nan")
    assert not (tmp_path / "o").exists()


def test_a_url_is_no_output_folder_either(tmp_path, capsys):
    code, _, err = run(["synth-suite", "--kind", "contour", "--clips", "1", "--out", "http://127.0.0.1:9/s"], capsys)
    one_error(code, err, "'--out': http://127.0.0.1:9/s is a URL; vistrack writes its outputs to local files")
    assert not (tmp_path / "http:").exists()
