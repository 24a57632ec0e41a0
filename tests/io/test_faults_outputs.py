"""Faults that break outputs: an output that is an input or another name of one, a link or a device, two
writers of one file, a full disk, a writer that fails mid-way. Each ends in one clear line or a whole
output; an earlier output is never lost and an input never overwritten."""

from __future__ import annotations

import os
from pathlib import Path

import cv2
import pytest

from cli_helpers import run
from fault_helpers import (
    INIT,
    H,
    Unavailable,
    W,
    avi,
    image_folder,
    on_tmpfs,
    one_error,
    read_rows,
    textured_avi,
    textured_frame,
    write_video,
)


def test_track_csv_is_whole_after_a_write_error(tmp_path):
    """A write error mid-run (disk full) leaves the rows written so far, renamed into place."""
    from vistrack.io.track_files import TrackCSV

    t = TrackCSV(tmp_path / "t.csv")
    t.write({"frame": 0, "cx": 1.0})
    t.write({"frame": 1, "cx": 2.0})
    t._f.close()  # the disk goes away
    with pytest.raises(ValueError):
        t.write({"frame": 2, "cx": 3.0})
    t.close()
    rows = read_rows(tmp_path / "t.csv")
    assert [r["frame"] for r in rows] == ["0", "1"] and not (tmp_path / "t.csv.part").exists()

def test_write_atomic_leaves_the_old_file_on_failure(tmp_path):
    from vistrack.batch.tasks import write_atomic

    p = tmp_path / "results.json"
    write_atomic(p, "old")

    class Boom:
        def __str__(self):
            raise RuntimeError

    with pytest.raises(TypeError):
        write_atomic(p, Boom())
    assert p.read_text() == "old" and [q.name for q in tmp_path.iterdir()] == ["results.json"]

@pytest.mark.parametrize("outputs, message", [
    (["--out", "{v}"], "--out {v} would overwrite the input it reads (v.avi)"),
    (["--track", "{v}"], "--track {v} would overwrite the input it reads (v.avi)"),
    (["--track", "{d}/t.csv", "--results", "{d}/t.csv"], "--track and --results name the same file"),
], ids=["out-is-input", "track-is-input", "same-file"])
def test_run_outputs_never_overwrite_the_input(tmp_path, capsys, outputs, message):
    video = tmp_path / "v.avi"
    write_video(video, 3)
    before = video.read_bytes()
    args = [a.format(v=video, d=tmp_path) for a in outputs]
    code, _, err = run(["run", str(video), "--init", "48,51,24,18", *args], capsys)
    assert code != 0 and message.format(v=video) in err and err.count("Error:") == 1
    assert video.read_bytes() == before

def test_clip_files_are_inputs_too(tmp_path, capsys):
    from vistrack.data_synth.contour_clip import make_contour_clip

    make_contour_clip(tmp_path / "c", frames=2, size=(96, 72), seed=1, clutter="low", distractor=False)
    gt = (tmp_path / "c" / "groundtruth.csv").read_bytes()
    code, _, err = run(["run", str(tmp_path / "c"), "--init-gt", "--track", str(tmp_path / "c" / "groundtruth.csv")],
                       capsys)
    assert code != 0 and "would overwrite the input it reads (groundtruth.csv)" in err
    assert (tmp_path / "c" / "groundtruth.csv").read_bytes() == gt
    code, _, err = run(["run", str(tmp_path / "c"), "--init-gt", "-q", "--track", str(tmp_path / "c" / "t.csv")],
                       capsys)
    assert code == 0, err  # another file in the clip folder is fine

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

def test_devices_are_written_directly_never_replaced(tmp_path):
    """``--track /dev/stdout`` and the like: the rows go to the device; the part-file-and-rename of a
    regular file would replace the device node (here a link to it stands for it)."""
    from vistrack.batch.tasks import write_atomic
    from vistrack.io.track_files import TrackCSV

    for name in ("t.csv", "results.json"):
        (tmp_path / name).symlink_to("/dev/null")
    t = TrackCSV(tmp_path / "t.csv")
    t.write({"frame": 0, "cx": 1.0})
    t.close()
    write_atomic(tmp_path / "results.json", "{}")
    assert all((tmp_path / n).is_symlink() for n in ("t.csv", "results.json"))
    assert sorted(p.name for p in tmp_path.iterdir()) == ["results.json", "t.csv"]
    (tmp_path / "full.csv").symlink_to("/dev/full")
    t = TrackCSV(tmp_path / "full.csv")
    with pytest.raises(OSError, match="No space left"):
        t.write({"frame": 0, "cx": 1.0})
    t.close()
    assert (tmp_path / "full.csv").is_symlink()

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
    assert code == 0 and len(read_rows(track)) == 3, err

def test_2_temporary_names_are_never_shared(tmp_path):
    """A part file already there (a killed run's rows) is neither written nor removed: the new
    writer takes a name of its own and renames it over the output."""
    from vistrack.io.outputs import temporary_name
    from vistrack.io.track_files import TrackCSV

    (tmp_path / "t.csv.part").write_text("frame\n0\n")
    t = TrackCSV(tmp_path / "t.csv")
    assert t.part != tmp_path / "t.csv.part" and t.part.parent == tmp_path
    t.write({"frame": 7})
    t.close()
    assert (tmp_path / "t.csv.part").read_text() == "frame\n0\n"
    assert read_rows(tmp_path / "t.csv") == [{"frame": "7"}]
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

def test_annotated_video_outputs(tmp_path, capsys):
    """--out without .mp4 is one line saying so; a disk that fills up under the annotated video
    (found when it is closed, after every frame) costs the video, never the track CSV; a full disk
    under the track CSV stops the run at once."""
    video = tmp_path / "v.avi"
    write_video(video, 6)
    base = ["run", str(video), "--init", "48,51,24,18", "-n", "20", "-q", "--track", str(tmp_path / "t.csv")]
    for name in ("annotated.txt", "annotated"):
        code, _, err = run([*base, "--out", str(tmp_path / name)], capsys)
        assert code != 0 and "give a file name ending in .mp4" in err and err.count("\n") == 1, err
    (tmp_path / "full.mp4").symlink_to("/dev/full")
    code, _, err = run([*base, "--out", str(tmp_path / "full.mp4")], capsys)
    assert code != 0 and err.startswith("Error: [Errno 28] No space left on device") and "Traceback" not in err
    assert len(read_rows(tmp_path / "t.csv")) == 6 and not (tmp_path / "t.csv.part").exists()
    (tmp_path / "full.csv").symlink_to("/dev/full")
    code, _, err = run([*base[:-1], str(tmp_path / "full.csv")], capsys)
    assert code != 0 and "No space left on device" in err and err.count("\n") == 1

def _tmpfs(steps, **kw):
    try:
        return on_tmpfs(steps, **kw)
    except Unavailable as e:
        pytest.skip(str(e))

def test_a_full_disk_keeps_the_earlier_video_and_leaves_no_unplayable_one(tmp_path):
    """df_old: ``run --out T/old.mp4`` over an earlier valid video on a 16 kB tmpfs that fills up: one
    line naming T/old.mp4 and the cause; the earlier video byte for byte. df_out: with no earlier file
    nothing is left under the final name, and the error names it (not the temporary file)."""
    short, long = textured_avi(tmp_path / "short.avi", 3), textured_avi(tmp_path / "long.avi", 120)
    run_ = ["run", "--init", INIT, "-n", "20", "-q"]
    first, over, new = _tmpfs([[*run_, "--out", "{T}/old.mp4", str(v)] for v in (short, long)]
                              + [[*run_, "--out", "{T}/a.mp4", str(long)]], size="16k")
    assert first["code"] == 0 and first["files"]["old.mp4"]["frames"] == 3, first
    one_error(over["code"], over["err"], "{T}/old.mp4", "No space left on device", "the earlier old.mp4 is kept")
    assert over["files"] == first["files"]
    one_error(new["code"], new["err"], "{T}/a.mp4", "No space left on device", "no a.mp4 was written")
    assert new["files"] == first["files"] and ".part" not in new["err"]

def test_a_full_disk_under_the_track_keeps_the_earlier_track_else_its_whole_rows(tmp_path):
    short, long = textured_avi(tmp_path / "short.avi", 3), textured_avi(tmp_path / "long.avi", 120)
    base = ["-n", "20", "-q", "--init", INIT, "--track", "{T}/t.csv", "--results", "{T}/r.txt"]
    first, second, alone = _tmpfs([["run", str(short), *base], ["run", str(long), *base, "--out", "/dev/null"],
                                   ["run", str(long), "--init", INIT, "-n", "20", "-q", "--track", "{T}/new.csv"]],
                                  size="16k")  # 4 pages: two files and their locks (a lock holds its pid)
    assert first["code"] == 0 and sorted(first["files"]) == ["r.txt", "t.csv"]
    one_error(second["code"], second["err"], "{T}/", "No space left on device", "is kept")
    assert second["files"] == first["files"]
    one_error(alone["code"], alone["err"], "{T}/new.csv", "No space left on device", "rows written before are kept")
    assert sorted(alone["files"]) == ["new.csv", "r.txt", "t.csv"] and 0 < alone["files"]["new.csv"]["size"] <= 4096

def _failing_flush(monkeypatch):
    """PyAV's flush fails as on a full disk (the container's last write)."""
    import av

    real = av.open

    def open_(*a, **kw):
        c = real(*a, **kw)
        if kw.get("format") == "mp4" or (len(a) > 1 and a[1] == "w"):
            return _Failing(c)
        return c

    monkeypatch.setattr(av, "open", open_)

class _Failing:
    def __init__(self, c):
        self._c = c

    def __getattr__(self, name):
        return getattr(self._c, name)

    def close(self):
        self._c.close()
        raise OSError(28, "No space left on device", "/somewhere/.a.part.mp4")

def test_the_video_writer_renames_only_after_a_successful_flush(tmp_path, monkeypatch):
    from vistrack.io.outputs import OutputError
    from vistrack.io.video_writer import VideoWriter

    out = tmp_path / "a.mp4"
    with VideoWriter(out, 25, (W, H), codec="h264", atomic=True) as w:
        w.write(textured_frame(0))
    earlier = out.read_bytes()
    _failing_flush(monkeypatch)
    w = VideoWriter(out, 25, (W, H), codec="h264", atomic=True)
    for i in range(5):
        w.write(textured_frame(i))
    with pytest.raises(OutputError) as e:
        w.close()
    assert str(e.value) == f"cannot write the annotated video {out}: No space left on device; the earlier a.mp4 is kept"
    assert e.value.filename == str(out) and e.value.errno == 28
    assert out.read_bytes() == earlier and sorted(p.name for p in tmp_path.iterdir()) == ["a.mp4"]
    w = VideoWriter(tmp_path / "b.mp4", 25, (W, H), codec="h264", atomic=True)
    w.write(textured_frame(0))
    with pytest.raises(OutputError, match="no b.mp4 was written"):
        w.close()
    assert sorted(p.name for p in tmp_path.iterdir()) == ["a.mp4"]

def test_opencvs_silent_writer_is_checked(tmp_path, monkeypatch):
    """OpenCV's writer says nothing when a write fails: a file that does not play back its frames
    is an error, not an output."""
    import vistrack.io.video_writer as vw
    from vistrack.io.outputs import OutputError

    out = tmp_path / "a.avi"
    with vw.VideoWriter(out, 25, (W, H), codec="auto", atomic=True) as w:
        for i in range(3):
            w.write(textured_frame(i))
    earlier = out.read_bytes()
    real = cv2.VideoWriter

    class Lossy:  # drops every frame after the first, as on a full disk
        def __init__(self, *a):
            self._w, self._n = real(*a), 0

        def isOpened(self):
            return self._w.isOpened()

        def write(self, f):
            self._n += 1
            if self._n == 1:
                self._w.write(f)

        def release(self):
            self._w.release()

    monkeypatch.setattr(vw.cv2, "VideoWriter", Lossy)
    w = vw.VideoWriter(out, 25, (W, H), codec="auto", atomic=True)
    for i in range(6):
        w.write(textured_frame(i))
    with pytest.raises(OutputError, match=f"cannot write the annotated video {out}: .*; the earlier a.avi is kept"):
        w.close()
    assert out.read_bytes() == earlier and sorted(p.name for p in tmp_path.iterdir()) == ["a.avi"]

def test_every_writer_keeps_the_earlier_file_on_a_failure(tmp_path, monkeypatch):
    """write_atomic (results.json, report.md, task files), the plots and the track CSV: a failed
    write removes the temporary file, keeps the earlier output and names it."""
    import vistrack.reports.plots as plots
    from vistrack.batch.tasks import write_atomic
    from vistrack.io.outputs import OutputError
    from vistrack.io.track_files import TrackCSV

    (tmp_path / "results.json").write_text("{}")
    real = Path.write_text

    def full(self, *a, **kw):
        real(self, "half")
        raise OSError(28, "No space left on device")

    monkeypatch.setattr(Path, "write_text", full)
    with pytest.raises(OutputError, match=r"cannot write the file .*results.json: No space left on device; the "
                                          r"earlier results.json is kept"):
        write_atomic(tmp_path / "results.json", '{"a": 1}')
    monkeypatch.undo()
    assert (tmp_path / "results.json").read_text() == "{}"

    png = plots.plot_per_frame({"lis": [1.0, 2.0]}, tmp_path / "p.png", ylabel="e", title="t")
    earlier = png.read_bytes()
    monkeypatch.setattr("matplotlib.figure.Figure.savefig",
                        lambda self, f, **kw: (Path(f).write_bytes(b"x"), (_ for _ in ()).throw(OSError(28, "full"))))
    with pytest.raises(OutputError, match="cannot write the plot .*p.png: full; the earlier p.png is kept"):
        plots.plot_per_frame({"lis": [1.0, 3.0]}, png, ylabel="e", title="t")
    assert png.read_bytes() == earlier

    (tmp_path / "t.csv").write_text("frame,cx\n0,1.000\n")
    t = TrackCSV(tmp_path / "t.csv")
    t.write({"frame": 0, "cx": 5.0})
    t._f.flush = lambda: (_ for _ in ()).throw(OSError(28, "No space left on device"))
    with pytest.raises(OutputError, match="cannot write the track file .*t.csv: No space left on device; the "
                                          "earlier t.csv is kept"):
        t.write({"frame": 1, "cx": 6.0})
    t.close()
    assert (tmp_path / "t.csv").read_text() == "frame,cx\n0,1.000\n"
    assert sorted(p.name for p in tmp_path.iterdir()) == ["p.png", "results.json", "t.csv"]


# ------------------------------------------------------------------ the fourth sweep (issue 55)


def _drain(path, into):
    """A thread reading ``path`` (a FIFO) to its end into the list ``into``."""
    import threading

    def read():
        with open(path) as f:
            into.append(f.read())

    reader = threading.Thread(target=read, daemon=True)
    reader.start()
    return reader


def test_a_link_is_written_through_and_a_pipe_or_descriptor_in_place(tmp_path, capsys):
    """``--track /dev/stdout`` replaced the system's link with a regular file (the part file renamed over the
    name). Here: --track through a link to /proc/self/fd/N of a pipe (what /dev/stdout is), --results
    through a link to a regular file, and --out to a FIFO's link: the rows reach the pipe and the file,
    and every link and the FIFO stay what they were."""
    from vistrack.io.outputs import output_target

    write_video(tmp_path / "v.avi", 5)
    r, w = os.pipe()
    (tmp_path / "stdout").symlink_to(f"/proc/self/fd/{w}")
    (tmp_path / "r.txt").symlink_to(tmp_path / "real.txt")
    assert output_target(tmp_path / "stdout")[1] and output_target("/dev/stdout")[1]
    assert output_target(tmp_path / "r.txt") == (tmp_path / "real.txt", False)
    got = []
    with os.fdopen(r) as f:
        import threading

        reader = threading.Thread(target=lambda: got.append(f.read()), daemon=True)
        reader.start()
        code, _, err = run(["run", tmp_path / "v.avi", "--init", "48,51,24,18", "-n", "20", "-q", "--track",
                            tmp_path / "stdout", "--results", tmp_path / "r.txt"], capsys)
        os.close(w)
        reader.join()
    assert code == 0, err
    assert got[0].startswith("frame,visible,") and got[0].count("\n") == 6
    assert (tmp_path / "stdout").is_symlink() and (tmp_path / "r.txt").is_symlink()
    assert len((tmp_path / "real.txt").read_text().splitlines()) == 5
    os.mkfifo(tmp_path / "fifo")
    (tmp_path / "fifo.csv").symlink_to(tmp_path / "fifo")
    got = []
    reader = _drain(tmp_path / "fifo", got)
    code, _, err = run(["run", tmp_path / "v.avi", "--init", "48,51,24,18", "-n", "20", "-q", "--track",
                        tmp_path / "fifo.csv"], capsys)
    reader.join()
    assert code == 0, err
    assert got[0].count("\n") == 6 and (tmp_path / "fifo.csv").is_symlink()
    assert not (tmp_path / "fifo").is_file() and os.path.exists(tmp_path / "fifo")


def test_train_search_never_writes_over_its_template_and_says_so_when_it_cannot_write(tmp_path):
    """train-search --out TEMPLATE overwrote the template with the network; on a full disk it said it had
    trained to a file that was not there."""
    tpl = tmp_path / "tpl.txt"
    tpl.write_text("100 100\n140 100\n140 140\n100 140\n120 90\n")
    before = tpl.read_bytes()
    os.link(tpl, tmp_path / "same.txt")
    train = ["train-search", "--template", tpl, "--samples", "100", "--size", "160x120"]
    for out in (tpl, tmp_path / "same.txt"):
        code, out_text, err = run([*train, "--out", out])
        one_error(code, err, f"--out {out} would overwrite the input it reads")
        assert "trained" not in out_text + err
    assert tpl.read_bytes() == before
    (tmp_path / "full.npz").symlink_to("/dev/full")
    code, out_text, err = run([*train, "--out", tmp_path / "full.npz"])
    one_error(code, err, f"cannot write the network cache {tmp_path / 'full.npz'}: No space left on device")
    assert "trained in" not in out_text


def test_reproduce_json_never_writes_over_a_clip_it_reads(tmp_path):
    """reproduce contour --clips suite --json suite/contour-01/groundtruth.csv overwrote that clip's ground
    truth with the results: refused before anything runs."""
    from vistrack.data_synth.contour_clip import make_contour_clip

    make_contour_clip(tmp_path / "suite" / "contour-01", frames=3, size=(96, 72), seed=1, clutter="low",
                      distractor=False)
    gt = tmp_path / "suite" / "contour-01" / "groundtruth.csv"
    before = gt.read_bytes()
    code, _, err = run(["reproduce", "contour", "--clips", tmp_path / "suite", "--algos", "lis:10", "--runs", "1",
                        "--in-process", "--out", tmp_path / "C", "--json", gt, "-q"])
    one_error(code, err, f"--json {gt} would overwrite the input it reads (groundtruth.csv)")
    assert gt.read_bytes() == before and not (tmp_path / "C").exists()


def test_reproduce_never_makes_its_clips_among_other_files(tmp_path):
    """reproduce contour --clips DIR made ten clips into a folder holding other data."""
    (tmp_path / "D").mkdir()
    (tmp_path / "D" / "notes.txt").write_text("mine")
    code, _, err = run(["reproduce", "contour", "--clips", tmp_path / "D", "--make", "2", "--frames", "3", "--size",
                        "96x72", "--algos", "lis:10", "--runs", "1", "--in-process", "--out", tmp_path / "C", "-q"])
    one_error(code, err, f"{tmp_path / 'D'} holds notes.txt", "give an empty or new folder")
    assert sorted(p.name for p in (tmp_path / "D").iterdir()) == ["notes.txt"]


@pytest.mark.parametrize("option, name", [("--out", "a.mp4"), ("--results", "r.txt")])
def test_every_output_is_locked_while_a_run_writes_it(tmp_path, capsys, option, name):
    """Two runs given one --out video or --results both wrote it, the later replacing the earlier; only
    --track was locked. A lock held on the name (or on the file a link names) refuses the second."""
    from vistrack.io.outputs import OutputLock

    image_folder(tmp_path / "c", 3)
    (tmp_path / "link").symlink_to(tmp_path / name)
    held = OutputLock(tmp_path / "link")  # another run writing the file through another name
    try:
        code, _, err = run(["run", tmp_path / "c", "--init", "40,50,25,19", option, tmp_path / name, "-q"], capsys)
        one_error(code, err, "is being written by another vistrack run")
    finally:
        held.release()
    assert not (tmp_path / name).exists()


def test_json_outputs_take_the_lock_too(tmp_path):
    """results.json, task files, plots and the network cache are written through ``replacing``, which now
    holds the output's lock: another writer of the same file is refused, never interleaved."""
    from vistrack.batch.tasks import write_atomic
    from vistrack.io.outputs import OutputBusy, OutputLock

    held = OutputLock(tmp_path / "results.json")
    try:
        with pytest.raises(OutputBusy, match="results.json is being written by another vistrack run"):
            write_atomic(tmp_path / "results.json", "{}")
    finally:
        held.release()
    write_atomic(tmp_path / "results.json", "{}")
    assert sorted(p.name for p in tmp_path.iterdir()) == ["results.json"]


def test_track_files_write_empty_cells_never_nan(tmp_path, capsys):
    """run --targets 3 wrote literal nan in 14 columns on frames without a plate (the docs: numbers or empty
    cells): every CSV cell of a number that is not finite is empty, and reads back as NaN."""
    import numpy as np

    from vistrack.data_synth.plate_clip import make_plate_clip
    from vistrack.io.clips import read_groundtruth_csv
    from vistrack.io.track_files import TrackCSV

    t = TrackCSV(tmp_path / "u.csv")
    t.write({"frame": 0, "cx": float("nan"), "cy": np.float32("inf"), "w": 2.0})
    t.close()
    assert (tmp_path / "u.csv").read_text().splitlines() == ["frame,cx,cy,w", "0,,,2.000"]
    assert np.isnan(read_groundtruth_csv(tmp_path / "u.csv")["cx"][0])
    import warnings

    with warnings.catch_warnings():
        warnings.simplefilter("ignore")  # no plate comes into view in so few frames
        make_plate_clip(tmp_path / "p", frames=6, size=(160, 120), seed=1)
    code, _, err = run(["run", tmp_path / "p", "--targets", "3", "-n", "20", "-q", "--track", tmp_path / "t.csv"],
                       capsys)
    assert code == 0, err
    text = (tmp_path / "t.csv").read_text() + (tmp_path / "p" / "groundtruth.csv").read_text()
    assert "nan" not in text.lower() and ",," in text
