"""Issue 38, the second sweep of hostile-but-fair input: one test (or more) per numbered point.
Data loss (1, 2), tracebacks (3-5), silent wrong output (6-13), wording (14). Each ends in one
clear line or a correct output; never a traceback, never an input overwritten."""

from __future__ import annotations

import csv
import json
import os
import warnings

import cv2
import numpy as np
import pytest

from cli_helpers import run

H, W = 120, 160


def box_frame(i, w=W, h=H):
    img = np.full((h, w, 3), 100, np.uint8)
    cv2.rectangle(img, (40 + 2 * i, 50), (64 + 2 * i, 68), (30, 60, 220), -1)
    return img


def image_folder(folder, n=8, names=None, ext="png"):
    """An OTB-style folder: ``img/`` of a red box moving 2 px per frame, ``groundtruth_rect.txt``
    (1-based); returns the 0-based truth ``(n, 4)``."""
    (folder / "img").mkdir(parents=True)
    names = names or [f"{i + 1:04d}.{ext}" for i in range(n)]
    for i, name in enumerate(names):
        cv2.imwrite(str(folder / "img" / name), box_frame(i))
    truth = np.array([[40 + 2 * i, 50, 25, 19] for i in range(len(names))], float)
    (folder / "groundtruth_rect.txt").write_text("".join(f"{x + 1:g},{y + 1:g},{w:g},{h:g}\n" for x, y, w, h in truth))
    return truth


def avi(path, n, w=W, h=H):
    wr = cv2.VideoWriter(str(path), cv2.VideoWriter_fourcc(*"MJPG"), 25, (w, h))
    for i in range(n):
        wr.write(box_frame(i % 40, w, h))
    wr.release()


def rows_of(path):
    with open(path, newline="") as f:
        return list(csv.DictReader(f))


def one_error(code, err, *words):
    assert code not in (0, None) and "Traceback" not in err, err
    lines = [ln for ln in err.splitlines() if ln.startswith("Error:")]
    assert len(lines) == 1, err
    for w in words:
        assert w in lines[0], (w, lines[0])
    return lines[0]


# ------------------------------------------------------------------ 1, 2: data loss


@pytest.mark.parametrize("link", ["hard", "symbolic"])
def test_1_out_that_is_another_name_of_the_input_is_refused(tmp_path, capsys, link):
    video = tmp_path / "in.avi"
    avi(video, 3)
    before = video.read_bytes()
    other = tmp_path / "h.avi"
    (os.link if link == "hard" else os.symlink)(video, other)
    for opt in ("--out", "--track", "--results"):
        code, _, err = run(["run", str(video), "--init", "40,50,25,19", opt, str(other), "-q"], capsys)
        one_error(code, err, "would overwrite the input it reads", "in.avi")
    assert video.read_bytes() == before


def test_1_template_and_init_gt_files_are_inputs_too(tmp_path, capsys):
    image_folder(tmp_path / "c", 3)
    gt = tmp_path / "gt.txt"
    gt.write_text("41,51,25,19\n" * 3)
    before = gt.read_bytes()
    os.link(gt, tmp_path / "same.txt")
    code, _, err = run(["run", str(tmp_path / "c"), "--init-gt", str(gt), "--results", str(tmp_path / "same.txt")],
                       capsys)
    one_error(code, err, "would overwrite the input it reads")
    assert gt.read_bytes() == before


def test_2_an_output_another_live_run_holds_is_refused(tmp_path, capsys):
    from vistrack.io.outputs import OutputLock

    image_folder(tmp_path / "c", 3)
    track = tmp_path / "t.csv"
    held = OutputLock(track)  # another run writing t.csv (flock: per open file, so it holds in this process too)
    try:
        code, _, err = run(["run", str(tmp_path / "c"), "--init", "40,50,25,19", "--track", str(track), "-q"], capsys)
        one_error(code, err, "is being written by another vistrack run", str(track))
    finally:
        held.release()
    assert not track.exists() and not list(tmp_path.glob("*.part")) and not list(tmp_path.glob(".*.lock"))
    code, _, err = run(["run", str(tmp_path / "c"), "--init", "40,50,25,19", "--track", str(track), "-q"], capsys)
    assert code == 0 and len(rows_of(track)) == 3, err


def test_2_temporary_names_are_never_shared(tmp_path):
    """A part file already there (a killed run's rows) is neither written nor removed: the new
    writer takes a name of its own and renames it over the output."""
    from vistrack.io.outputs import temporary_name
    from vistrack.session.recording import TrackCSV

    (tmp_path / "t.csv.part").write_text("frame\n0\n")
    t = TrackCSV(tmp_path / "t.csv")
    assert t.part != tmp_path / "t.csv.part" and t.part.parent == tmp_path
    t.write({"frame": 7})
    t.close()
    assert (tmp_path / "t.csv.part").read_text() == "frame\n0\n"
    assert rows_of(tmp_path / "t.csv") == [{"frame": "7"}]
    names = {temporary_name(tmp_path / "a.mp4") for _ in range(3)}
    assert len(names) == 3 and all(p.suffix == ".mp4" and p.parent == tmp_path for p in names)


def test_2_annotated_video_is_written_whole_then_renamed(tmp_path, capsys):
    image_folder(tmp_path / "c", 4)
    out = tmp_path / "a.mp4"
    out.write_bytes(b"old")
    code, _, err = run(["run", str(tmp_path / "c"), "--init", "40,50,25,19", "--out", str(out), "-q"], capsys)
    assert code == 0, err
    cap = cv2.VideoCapture(str(out))
    assert int(cap.get(cv2.CAP_PROP_FRAME_COUNT)) == 4
    assert sorted(p.name for p in tmp_path.iterdir()) == ["a.mp4", "c"]


# ------------------------------------------------------------------ 3-5: tracebacks


def test_3_frames_of_another_size_are_one_error_line(tmp_path, capsys):
    image_folder(tmp_path / "c", 6)
    cv2.imwrite(str(tmp_path / "c" / "img" / "0004.png"), np.zeros((240, 320, 3), np.uint8))
    for extra in (["--out", str(tmp_path / "a.mp4")], []):
        code, _, err = run(["run", str(tmp_path / "c"), "--init", "40,50,25,19", "--track", str(tmp_path / "t.csv"),
                            "-q", *extra], capsys)
        one_error(code, err, "0004.png", "320x240", "160x120")
        assert [r["frame"] for r in rows_of(tmp_path / "t.csv")] == ["0", "1", "2"]  # the frames before it, kept


@pytest.mark.parametrize("model", ["box", "contour", "plate"])
def test_4_huge_or_far_start_boxes_are_refused(tmp_path, capsys, model):
    image_folder(tmp_path / "c", 2)
    for box, words in (("0,0,1e12,1e12", "far larger than the 160x120 frame"),
                       ("159,119,30,30", "lies outside the 160x120 frame")):
        code, _, err = run(["run", str(tmp_path / "c"), "--model", model, "--init", box, "-q"], capsys)
        one_error(code, err, words)


@pytest.mark.parametrize("meta", ["[1, 2, 3]", '"hello"', "3", '{"model": [1]}'])
def test_5_meta_json_that_is_not_an_object(tmp_path, capsys, meta):
    image_folder(tmp_path / "c", 2)
    (tmp_path / "c" / "meta.json").write_text(meta)
    code, _, err = run(["run", str(tmp_path / "c"), "--init", "40,50,25,19", "-q"], capsys)
    one_error(code, err, "meta.json")
    code, _, err = run(["eval", str(tmp_path / "c"), "--algos", "lis", "--particles", "10", "--runs", "1",
                        "--out", str(tmp_path / "e"), "-q"], capsys)
    one_error(code, err, "meta.json")


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


# ------------------------------------------------------------------ 6-13: silent wrong output


def test_6_every_input_frame_gets_a_row_and_a_results_line(tmp_path, capsys):
    image_folder(tmp_path / "c", 10)
    for k in (0, 4, 5, 9):  # the first, two in the middle and the last
        (tmp_path / "c" / "img" / f"{k + 1:04d}.png").write_bytes(b"not a png")
    track, res, out = tmp_path / "t.csv", tmp_path / "r.txt", tmp_path / "a.mp4"
    code, _, err = run(["run", str(tmp_path / "c"), "--init", "42,50,25,19", "--track", str(track), "--results",
                        str(res), "--out", str(out), "-q"], capsys)
    assert code == 0, err
    rows = rows_of(track)
    assert [int(r["frame"]) for r in rows] == list(range(10))
    bad = [int(r["frame"]) for r in rows if r["lost_reason"] == "decode"]
    assert bad == [0, 4, 5, 9] and all(rows[k]["visible"] == "0" for k in bad)
    lines = res.read_text().splitlines()
    assert len(lines) == 10 and all(lines[k] == "0.00,0.00,0.00,0.00" for k in bad)
    assert lines[1] != "0.00,0.00,0.00,0.00"
    assert int(cv2.VideoCapture(str(out)).get(cv2.CAP_PROP_FRAME_COUNT)) == 10
    assert "4 frame(s) failed to decode: 0, 4, 5, 9" in err


def test_7_short_result_files_are_said_and_scored_as_not_reported(tmp_path, capsys):
    image_folder(tmp_path / "c", 10)
    (tmp_path / "mt").mkdir()
    (tmp_path / "mt" / "c.txt").write_text("".join(f"{40 + 2 * i},50,25,19\n" for i in range(6)))
    from vistrack.evaluation.experiment import ResultsLengthWarning

    with pytest.warns(ResultsLengthWarning, match="has 6 lines for the 10 ground-truth frames.*scored as not reported"):
        code, _, err = run(["eval", str(tmp_path / "c"), "--algos", "", "--results-dir", str(tmp_path / "mt"),
                            "--out", str(tmp_path / "e"), "-q"], capsys)
    assert code == 0, err
    (summary,) = json.loads((tmp_path / "e" / "results.json").read_text())["results"]
    assert summary["algo"] == "mt" and len(summary["p_lost_per_frame"]) == 10
    assert summary["precision_20px"] == pytest.approx(0.6) and summary["p_lost"] == pytest.approx(0.4)


def test_9_init_gt_starts_at_the_first_frame_with_a_box(tmp_path, capsys):
    truth = image_folder(tmp_path / "c", 10)
    lines = (tmp_path / "c" / "groundtruth_rect.txt").read_text().splitlines()
    (tmp_path / "c" / "groundtruth_rect.txt").write_text("\n".join(["NaN,NaN,NaN,NaN"] * 4 + lines[4:]) + "\n")
    res, track = tmp_path / "r.txt", tmp_path / "t.csv"
    code, out, err = run(["run", str(tmp_path / "c"), "--init-gt", "--results", str(res), "--track", str(track)],
                         capsys)
    assert code == 0, err
    assert "no box before frame 4: tracking starts there" in err
    got = np.array([[float(v) for v in ln.split(",")] for ln in res.read_text().splitlines()])
    assert len(got) == 10 and not got[:4].any()
    assert [r["lost_reason"] for r in rows_of(track)[:4]] == ["not started"] * 4
    err_px = np.hypot(*(got[4:, :2] + got[4:, 2:] / 2 - truth[4:, :2] - truth[4:, 2:] / 2).T)
    assert err_px.max() < 6, err_px  # learned on the box at frame 4, not on frame 0's background
    assert "vs ground truth (6 frames with the object)" in out


def test_10_image_folders_are_read_in_natural_order(tmp_path):
    from vistrack.io.video import FrameOrderWarning, open_video

    image_folder(tmp_path / "c", names=[f"frame{i}.png" for i in range(1, 13)])
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        src = open_video(tmp_path / "c")
    assert [p.name for p in src._images] == [f"frame{i}.png" for i in range(1, 13)]
    image_folder(tmp_path / "d", names=["1.png", "01.png", "2.png"])
    with pytest.warns(FrameOrderWarning, match="ambiguous"):
        open_video(tmp_path / "d")


def test_11_a_suite_over_an_earlier_one_holds_the_new_clips_alone(tmp_path, capsys):
    su = tmp_path / "SU"
    args = ["synth-suite", "--kind", "contour", "--frames", "2", "--size", "64x48", "--out", str(su), "-q"]
    assert run([*args, "--clips", "3", "--seed", "1"], capsys)[0] == 0
    assert run([*args, "--clips", "2", "--seed", "5"], capsys)[0] == 0
    assert sorted(p.name for p in su.iterdir() if not p.name.startswith(".")) == ["contour-05", "contour-06"]
    (su / "notes.txt").write_text("mine")
    code, _, err = run([*args, "--clips", "1"], capsys)
    one_error(code, err, "notes.txt")


def test_11_synth_into_another_clips_folder_is_refused(tmp_path, capsys):
    image_folder(tmp_path / "otb", 3)
    code, _, err = run(["synth", "contour", "--out", str(tmp_path / "otb"), "--frames", "2", "--size", "64x48", "-q"],
                       capsys)
    one_error(code, err, "groundtruth_rect.txt", "img")
    assert sorted(os.listdir(tmp_path / "otb")) == ["groundtruth_rect.txt", "img"]
    # over a clip synth wrote: replaced whole (a plate clip's objects.csv does not stay beside a contour clip)
    clip = tmp_path / "clip"
    clip.mkdir()
    (clip / "video.mp4").write_bytes(b"x")
    (clip / "meta.json").write_text('{"kind": "plate", "model": "plate"}')
    (clip / "objects.csv").write_text("frame\n")
    (clip / "mine.txt").write_text("user's")
    code, _, err = run(["synth", "contour", "--out", str(clip), "--frames", "2", "--size", "64x48", "-q"], capsys)
    assert code == 0, err
    assert sorted(os.listdir(clip)) == ["groundtruth.csv", "meta.json", "mine.txt", "video.mp4"]


def test_12_a_video_that_ends_early_says_where(tmp_path, capsys):
    avi(tmp_path / "v.avi", 40)
    data = (tmp_path / "v.avi").read_bytes()
    (tmp_path / "t.avi").write_bytes(data[: int(0.6 * len(data))])
    code, _, err = run(["run", str(tmp_path / "t.avi"), "--init", "40,50,25,19", "-q"], capsys)
    assert code == 0, err
    assert "ended early: decoding stopped at frame" in err and "of the 40 its header announces" in err


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


def test_13_absurd_ground_truth_values_are_one_short_line(tmp_path, capsys):
    image_folder(tmp_path / "c", 3)
    (tmp_path / "c" / "groundtruth_rect.txt").write_text("41,51,25,19\n1e300,5,6,7\n41,51,25,19\n")
    code, _, err = run(["run", str(tmp_path / "c"), "--init-gt", "-q"], capsys)
    line = one_error(code, err, "groundtruth_rect.txt, line 2", "not a pixel coordinate")
    assert len(line) < 300


def test_13_a_plate_clip_without_a_plate_in_view_says_so(tmp_path, capsys):
    from vistrack.data_synth.plate_clip import NoPlateWarning

    with pytest.warns(NoPlateWarning, match=r"no plate comes wholly into view in the 3 frame\(s\)"):
        code, _, err = run(["synth", "plate", "--out", str(tmp_path / "p"), "--frames", "3", "--size", "160x120",
                            "-q"], capsys)
    assert code == 0, err


def test_13_demo_says_how_many_real_frames_it_took(tmp_path, capsys, monkeypatch):
    import sys

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


# ------------------------------------------------------------------ 14: wording


def test_14_a_device_or_pipe_is_named_as_such(tmp_path, capsys):
    fifo = tmp_path / "fifo"
    os.mkfifo(fifo)
    for path in ("/dev/zero", str(fifo)):
        code, _, err = run(["run", path, "--init", "1,1,5,5", "-q"], capsys)
        one_error(code, err, "not a regular file or folder")


def test_14_binary_bom_and_nan_input_files(tmp_path, capsys):
    image_folder(tmp_path / "c", 3)
    gt = tmp_path / "c" / "groundtruth_rect.txt"
    text = gt.read_text()
    gt.write_bytes(b"\x89PNG\r\n\x1a\n\xff\xfe" + bytes(range(256)))
    code, _, err = run(["run", str(tmp_path / "c"), "--init-gt", "-q"], capsys)
    one_error(code, err, str(gt), "not a text file")
    gt.write_bytes(b"\xef\xbb\xbf" + text.encode())  # a UTF-8 byte-order mark
    code, _, err = run(["run", str(tmp_path / "c"), "--init-gt", "-q"], capsys)
    assert code == 0, err
    tpl = tmp_path / "t.txt"
    tpl.write_text("10 10\nnan 12\n14 14\n20 20\n")
    code, _, err = run(["run", str(tmp_path / "c"), "--model", "contour", "--init", "40,50,25,19", "--template",
                        str(tpl), "-q"], capsys)
    one_error(code, err, str(tpl), "support point 2 is not a finite pixel position")


def test_14_eval_out_with_a_file_where_tasks_go_fails_before_the_grid(tmp_path, capsys, monkeypatch):
    import vistrack.batch.cluster as grid

    image_folder(tmp_path / "c", 3)
    (tmp_path / "E").mkdir()
    (tmp_path / "E" / "tasks").write_text("a file")
    monkeypatch.setattr(grid, "run_grid", lambda *a, **k: pytest.fail("the grid ran"))
    code, _, err = run(["eval", str(tmp_path / "c"), "--algos", "lis", "--particles", "10", "--runs", "1",
                        "--out", str(tmp_path / "E")], capsys)
    one_error(code, err, "tasks is a file")


# ------------------------------------------------------------------ 8: interrupts


def _decoded_frames(path):
    cap = cv2.VideoCapture(str(path))
    n = 0
    while cap.read()[0]:
        n += 1
    return n


@pytest.mark.parametrize("signals, code", [
    ((("INT", 3),), 130),
    ((("INT", 2), ("INT", 0)), 130),  # Ctrl-C twice, back to back
    ((("TERM", 2),), 143),
    ((("TERM", 5), ("INT", 0)), 143),  # a SIGTERM outranks Ctrl-C
], ids=["SIGINT", "SIGINT-twice", "SIGTERM", "SIGTERM-then-SIGINT"])
def test_8_after_any_interrupt_track_video_and_results_hold_the_same_frames(tmp_path, signals, code):
    """``run`` stopped by signals at a few points: it finishes the frame in hand, flushes every
    writer and exits 130 (SIGINT) / 143 (once a SIGTERM came); the track CSV, the
    ``--results`` file and the annotated video then hold the same frames, 0, 1, .., k-1."""
    import signal

    from process_helpers import PATIENCE, gated_cli, wait_until

    video = tmp_path / "v.avi"
    avi(video, 40)
    track, res, out = tmp_path / "t.csv", tmp_path / "r.txt", tmp_path / "a.mp4"
    args = ["run", str(video), "--init", "40,50,25,19", "-n", "300", "--algo", "bootstrap", "--track", str(track),
            "--results", str(res), "--out", str(out), "-q"]
    # the decoder waits before frame 8 until every signal is sent: the run cannot end before them
    proc = gated_cli(args, 8, tmp_path)
    part = tmp_path / "t.csv.part"
    for name, rows in signals:
        wait_until(lambda: not rows or part.is_file() and part.read_text().count("\n") >= rows + 1,
                   f"{rows} rows of the track", proc=proc)
        proc.send_signal(getattr(signal, f"SIG{name}"))
    _, stderr = proc.communicate(timeout=PATIENCE)  # closes its stdin: the decoder goes on
    assert proc.returncode == code and "Traceback" not in stderr, stderr
    frames = [int(r["frame"]) for r in rows_of(track)]
    k = len(frames)
    assert k >= 2 and frames == list(range(k))
    assert len(res.read_text().splitlines()) == k
    assert _decoded_frames(out) == k
    assert f"after {k} frames" in stderr
    assert sorted(p.name for p in tmp_path.iterdir()) == ["a.mp4", "r.txt", "t.csv", "v.avi"]


@pytest.mark.parametrize("names, reason", [
    (("SIGINT",), "interrupt"), (("SIGINT", "SIGINT"), "interrupt"), (("SIGTERM",), "terminate"),
    (("SIGTERM", "SIGINT"), "terminate"),
], ids=["SIGINT", "SIGINT-twice", "SIGTERM", "SIGTERM-then-SIGINT"])
@pytest.mark.usefixtures("ctrl_c_reaches_python")
def test_8_a_signal_between_the_track_row_and_the_video_frame(tmp_path, names, reason):
    """The signals arrive at the worst moment, after frame 3's track row is written and before
    its annotated frame is: the frame in hand is finished, so the track, the results and the
    video all hold frames 0-3."""
    import signal

    from vistrack.io.clips import load_clip
    from vistrack.registry import make_filter
    from vistrack.registry.builders import build_model
    from vistrack.session.recording import record_video, stop_on_signals

    image_folder(tmp_path / "c", 10)
    clip = load_clip(tmp_path / "c")
    model = build_model("box", clip, init=(40, 50, 25, 19))
    outline, calls = model.outline, []

    def outline_then_signal(states):
        calls.append(1)
        if len(calls) == 7:  # frame 3 (two outlines a frame), after its rows went to the track and results
            for name in names:
                os.kill(os.getpid(), getattr(signal, name))
        return outline(states)

    model.outline = outline_then_signal
    track, res, out = tmp_path / "t.csv", tmp_path / "r.txt", tmp_path / "a.mp4"
    with stop_on_signals():
        done = record_video(iter(clip.source), model, make_filter("lis", model), 30, np.random.default_rng(0),
                           track_path=track, results_path=res, out_path=out, video_info=(25.0, clip.source.size))
    assert done.stopped == reason
    assert [int(r["frame"]) for r in rows_of(track)] == [0, 1, 2, 3]
    assert len(res.read_text().splitlines()) == 4
    assert _decoded_frames(out) == 4


@pytest.mark.usefixtures("ctrl_c_reaches_python")
def test_8_a_second_signal_while_the_outputs_close_is_waited_for(tmp_path):
    """Ctrl-C twice, the second while the files are being closed: the video and the track are
    closed whole all the same (before: the video was left unclosed, about 40 frames short)."""
    import signal

    from vistrack.io.clips import load_clip
    from vistrack.registry import make_filter
    from vistrack.registry.builders import build_model
    from vistrack.session.recording import TrackCSV, record_video

    image_folder(tmp_path / "c", 6)
    clip = load_clip(tmp_path / "c")
    model = build_model("box", clip, init=(40, 50, 25, 19))
    close = TrackCSV.close

    def close_after_a_signal(self):
        os.kill(os.getpid(), signal.SIGINT)
        close(self)

    track, out = tmp_path / "t.csv", tmp_path / "a.mp4"
    TrackCSV.close = close_after_a_signal
    try:
        done = record_video(iter(clip.source), model, make_filter("lis", model), 30, np.random.default_rng(0),
                           track_path=track, out_path=out, video_info=(25.0, clip.source.size))
    except KeyboardInterrupt:
        pytest.fail("the signal escaped while the outputs were being closed")
    finally:
        TrackCSV.close = close
    assert done.stopped == "interrupt"
    assert len(rows_of(track)) == 6 and _decoded_frames(out) == 6
    assert sorted(p.name for p in tmp_path.iterdir()) == ["a.mp4", "c", "t.csv"]


def test_4_the_python_api_checks_the_start_box_too():
    import vistrack

    for box, words in (((0, 0, 1e12, 1e12), "far larger than the 160x120 frame"),
                       ((-100, -100, 50, 50), "lies outside the 160x120 frame")):
        with pytest.raises(ValueError, match=words):
            vistrack.Tracker().init(box_frame(0), box)
