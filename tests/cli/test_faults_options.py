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

    demo = sys.modules["vistrack.cli.demo"]  # the package's ``demo`` is the command
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
