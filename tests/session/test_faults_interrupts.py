"""Interrupts that must not break a run's outputs: Ctrl-C and SIGTERM (and the process group's Ctrl-C) at any
moment stop a run after the frame in hand, with the track, the results and the video holding the same frames;
Ctrl-C while a command starts or ends is ``Aborted.`` and 130."""

from __future__ import annotations

import os
import signal
import subprocess
import sys

import cv2
import numpy as np
import pytest

from fault_helpers import (
    INTERRUPT_AT,
    avi,
    decoded_frames,
    image_folder,
    read_rows,
    write_video,
)
from process_helpers import PATIENCE, gated_cli, wait_until


@pytest.mark.parametrize("sig, code", [(signal.SIGINT, 130), (signal.SIGTERM, 143)], ids=["SIGINT", "SIGTERM"])
def test_signal_mid_run_keeps_the_track_so_far(tmp_path, sig, code):
    """``run`` stopped by Ctrl-C or SIGTERM: exit 130 / 143, the track CSV holds every frame done as
    whole rows (no ``.part`` left), the annotated video plays those frames, one line says so."""
    video = tmp_path / "v.avi"
    write_video(video, 40)
    track, out = tmp_path / "t.csv", tmp_path / "a.mp4"
    args = ["run", str(video), "--init", "48,51,24,18", "-n", "300", "--algo", "bootstrap", "--track", str(track),
            "--out", str(out), "-q"]
    # the decoder waits before frame 8 until the signal is sent: the run cannot end before it
    proc = gated_cli(args, 8, tmp_path)
    part = tmp_path / "t.csv.part"
    wait_until(lambda: part.is_file() and part.read_text().count("\n") >= 4, "4 rows of the track", proc=proc)
    proc.send_signal(sig)
    stdout, stderr = proc.communicate(timeout=PATIENCE)  # closes its stdin: the decoder goes on
    assert proc.returncode == code, stderr
    assert "Traceback" not in stderr and "after" in stderr and str(track) in stderr
    rows = read_rows(track)
    assert 3 <= len(rows) < 40 and not part.exists()
    assert [int(r["frame"]) for r in rows] == list(range(len(rows)))
    assert all(np.isfinite(float(r["cx"])) for r in rows)
    cap = cv2.VideoCapture(str(out))
    assert int(cap.get(cv2.CAP_PROP_FRAME_COUNT)) >= len(rows) - 1

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
    frames = [int(r["frame"]) for r in read_rows(track)]
    k = len(frames)
    assert k >= 2 and frames == list(range(k))
    assert len(res.read_text().splitlines()) == k
    assert decoded_frames(out) == k
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
    from vistrack.session.recording import record_video
    from vistrack.system.signals import stop_on_signals

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
    assert [int(r["frame"]) for r in read_rows(track)] == [0, 1, 2, 3]
    assert len(res.read_text().splitlines()) == 4
    assert decoded_frames(out) == 4

@pytest.mark.usefixtures("ctrl_c_reaches_python")
def test_8_a_second_signal_while_the_outputs_close_is_waited_for(tmp_path):
    """Ctrl-C twice, the second while the files are being closed: the video and the track are
    closed whole all the same (before: the video was left unclosed, about 40 frames short)."""
    import signal

    from vistrack.io.clips import load_clip
    from vistrack.io.track_files import TrackCSV
    from vistrack.registry import make_filter
    from vistrack.registry.builders import build_model
    from vistrack.session.recording import record_video

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
    assert len(read_rows(track)) == 6 and decoded_frames(out) == 6
    assert sorted(p.name for p in tmp_path.iterdir()) == ["a.mp4", "c", "t.csv"]

@pytest.mark.parametrize("where", ["start-up", "shut-down"])
def test_ctrl_c_at_start_up_and_shut_down_is_aborted_and_130(where):
    p = subprocess.run([sys.executable, "-c", INTERRUPT_AT, where, "--version"], capture_output=True, text=True,
                       timeout=120)
    assert (p.returncode, p.stderr) == (130, "Aborted.\n")


def test_sighup_keeps_the_track_so_far_as_sigterm_does(tmp_path):
    """kill -HUP (a closed terminal, a dropped ssh session) ended a run at once and left only .part files;
    it now stops the run after the frame in hand as SIGTERM does: exit 143, the track, the results and
    the video holding the same frames."""
    from fault_helpers import decoded_frames

    write_video(tmp_path / "v.avi", 40)
    track, res, out = tmp_path / "t.csv", tmp_path / "r.txt", tmp_path / "a.mp4"
    args = ["run", tmp_path / "v.avi", "--init", "48,51,24,18", "-n", "300", "--algo", "bootstrap", "--track", track,
            "--results", res, "--out", out, "-q"]
    proc = gated_cli(args, 8, tmp_path)
    part = tmp_path / "t.csv.part"
    wait_until(lambda: part.is_file() and part.read_text().count("\n") >= 4, "4 rows of the track", proc=proc)
    proc.send_signal(signal.SIGHUP)
    _, stderr = proc.communicate(timeout=PATIENCE)
    assert proc.returncode == 143 and "Traceback" not in stderr, stderr
    k = len(read_rows(track))
    assert k >= 3 and len(res.read_text().splitlines()) == k and decoded_frames(out) == k
    assert sorted(p.name for p in tmp_path.iterdir()) == ["a.mp4", "r.txt", "t.csv", "v.avi"]


def test_sighup_counts_as_a_terminating_signal():
    from vistrack.system.signals import TERMINATING

    assert signal.SIGHUP in TERMINATING and signal.SIGTERM in TERMINATING
