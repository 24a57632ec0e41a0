"""Faults of ``vistrack trax``: its options checked before the hello, an absent, broken or dead client and a
bad region each one line and a non-zero exit, session errors told to the client, never a hang."""

from __future__ import annotations

import signal
import subprocess
import sys

import cv2
import pytest

from fault_helpers import (
    api_frames,
    trax_session,
)


def _vistrack(argv, stdin=subprocess.DEVNULL, **kw):
    return subprocess.run([sys.executable, "-m", "vistrack.cli", *argv], stdin=stdin, capture_output=True, text=True,
                          timeout=120, **kw)

def test_trax_checks_its_options_before_the_hello():
    p = _vistrack(["trax", "--model", "nonsense"])
    assert p.stdout == "" and p.stderr.startswith("Error: unknown model 'nonsense'") and p.stderr.count("\n") == 1
    p = _vistrack(["trax", "--algo", "pf-eis"])
    assert p.stdout == "" and "does not run on the box model" in p.stderr and p.stderr.count("\n") == 1

@pytest.mark.parametrize("stdin", ["", "garbage\n", "@@TRAX:frame\n"], ids=["nothing", "garbage", "out of order"])
def test_trax_answers_an_absent_or_broken_client_with_one_line(stdin):
    pytest.importorskip("trax", reason="vot-trax is not installed")
    p = _vistrack(["trax"], stdin=None, input=stdin)
    assert p.returncode == 1 and p.stdout.startswith("@@TRAX:hello")
    assert p.stderr.startswith("Error: no TraX client") and p.stderr.count("\n") == 1, p.stderr

@pytest.mark.parametrize("case, words", [
    ("outside", "start box 500,500,10,10 lies outside the 120x90 frame"),
    ("missing", "cannot read the frame {d}/nothere.png: no such file"),
    ("size", "this frame is 120x80 colour, but the tracker started on 120x90 colour frames"),
])
def test_trax_session_errors_reach_the_client_and_no_traceback(tmp_path, case, words):
    pytest.importorskip("trax", reason="vot-trax is not installed")
    f = api_frames(1)[0]
    cv2.imwrite(str(tmp_path / "f0.png"), f)
    cv2.imwrite(str(tmp_path / "f1.png"), f[:80])
    box = (500, 500, 10, 10) if case == "outside" else (30, 30, 25, 25)
    second = {"outside": None, "missing": tmp_path / "nothere.png", "size": tmp_path / "f1.png"}[case]
    code, err, heard = trax_session(tmp_path / "f0.png", box, second)
    words = words.format(d=tmp_path)
    assert isinstance(heard, str) and words in heard  # the client was told why
    assert code == 1 and err.startswith(f"Error: {words}") and err.count("\n") == 1 and "Traceback" not in err

def test_ctrl_c_while_trax_waits_for_its_client_is_aborted_and_130():
    pytest.importorskip("trax", reason="vot-trax is not installed")

    proc = subprocess.Popen([sys.executable, "-m", "vistrack.cli", "trax"], stdin=subprocess.PIPE,
                            stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True,
                            preexec_fn=lambda: signal.signal(signal.SIGINT, signal.SIG_DFL))
    assert proc.stdout.readline().startswith("@@TRAX:hello")
    proc.send_signal(signal.SIGINT)
    _, err = proc.communicate(timeout=60)
    assert proc.returncode == 130 and err.strip() == "Aborted."


# ------------------------------------------------------------------ the fourth sweep (issue 55)


def _frame_file(folder):
    path = folder / "f.png"
    cv2.imwrite(str(path), api_frames(1)[0])
    return path


@pytest.mark.parametrize("message, words", [
    ('@@TRAX:initialize "41,48,25,19" \n', "the TraX client went away in the middle of a message (its end closed)"),
    ('@@TRAX:initialize "41,48,25,1', "no TraX client: standard input closed"),
], ids=["client-dies-after-a-message", "message-cut-short"])
def test_trax_ends_when_the_client_dies(message, words):
    """printf '@@TRAX:initialize ...' | vistrack trax never ended: libtrax spun at 90 % CPU on the ended
    input, deaf to SIGTERM. Now one line and exit 1 (the timeout is only a hang's guard)."""
    pytest.importorskip("trax", reason="vot-trax is not installed")
    p = _vistrack(["trax"], stdin=None, input=message)
    assert p.returncode == 1 and p.stdout.startswith("@@TRAX:hello")
    assert p.stderr.startswith(f"Error: {words}") and p.stderr.count("\n") == 1, p.stderr


@pytest.mark.parametrize("value, words", [
    ("garbage", "TRAX_SOCKET='garbage' is not a port number (1-65535)"),
    ("0", "TRAX_SOCKET='0' is not a port number"),
    ("{closed}", "TRAX_SOCKET={closed}: no TraX client answers on 127.0.0.1:{closed}"),
], ids=["not-a-number", "zero", "nothing-listens"])
def test_a_bad_trax_socket_is_refused_once(value, words):
    """TRAX_SOCKET=garbage printed 'connect: Connection refused' once a second forever."""
    pytest.importorskip("trax", reason="vot-trax is not installed")
    import os
    import socket

    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        closed = s.getsockname()[1]  # nothing listens there once the socket is closed
    p = _vistrack(["trax"], env={**os.environ, "TRAX_SOCKET": value.format(closed=closed)})
    assert p.returncode == 1 and p.stdout == "", p.stdout
    assert p.stderr.startswith(f"Error: {words.format(closed=closed)}") and p.stderr.count("\n") == 1, p.stderr


@pytest.mark.parametrize("region, words", [
    ("abc", "the client's start region is not a rectangle x,y,w,h or a polygon"),
    ("nan,nan,nan,nan", "the client's start region is not a rectangle x,y,w,h or a polygon"),
    ("1e999,3,4,5", "the client's start region inf,3,4,5 is not a box of finite numbers and positive size"),
    ("9" * 100000 + ",1,2,3", "the client's start region inf,1,2,3 is not a box of finite numbers"),
], ids=["abc", "nan", "1e999", "a-long-number"])
def test_trax_regions_are_validated_before_use(tmp_path, region, words):
    """The region "abc", NaN or a number of a million digits ended in AttributeError: 'Special' object has
    no attribute 'bounds'. Now one line to the client and on stderr."""
    pytest.importorskip("trax", reason="vot-trax is not installed")
    frame = _frame_file(tmp_path)
    p = _vistrack(["trax"], stdin=None, input=f'@@TRAX:initialize "{region}"\n@@TRAX:frame "file://{frame}"\n')
    assert p.returncode == 1 and f'trax.reason={words}' in p.stdout, p.stdout[-300:]
    assert p.stderr.startswith(f"Error: {words}") and p.stderr.count("\n") == 1 and "Traceback" not in p.stderr


def test_sigterm_ends_trax_while_it_waits_on_a_silent_client():
    pytest.importorskip("trax", reason="vot-trax is not installed")
    from process_helpers import PATIENCE

    proc = subprocess.Popen([sys.executable, "-m", "vistrack.cli", "trax"], stdin=subprocess.PIPE,
                            stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
    assert proc.stdout.readline().startswith("@@TRAX:hello")
    proc.stdin.write('@@TRAX:initialize "41,48,25,19" \n')  # then nothing: the client lives, but says nothing
    proc.stdin.flush()
    proc.terminate()
    _, err = proc.communicate(timeout=PATIENCE)
    assert proc.returncode == 143 and err.strip() == "Terminated.", err


@pytest.mark.parametrize("folder", ["ünï", "with space"])
def test_trax_reads_frames_under_any_folder_name(tmp_path, folder):
    """vot-trax's own client with frames under a non-ASCII folder got 'no TraX client' (libtrax reads a
    byte above 127 as the end of its input): the relay passes them on escaped."""
    pytest.importorskip("trax", reason="vot-trax is not installed")
    (tmp_path / folder).mkdir()
    frame = _frame_file(tmp_path / folder)
    code, err, heard = trax_session(frame, (30, 30, 25, 25), frame)
    assert code == 0 and err == "" and isinstance(heard, list) and len(heard) == 2, (err, heard)


def test_trax_over_a_socket_works_and_ends_when_the_client_goes(tmp_path):
    """TRAX_SOCKET: vistrack connects to the client's port once; the session runs as over a pipe, and a
    client that closes its end mid-session ends it with one line."""
    pytest.importorskip("trax", reason="vot-trax is not installed")
    import os
    import socket

    from trax.client import Client
    from trax.image import FileImage
    from trax.region import Rectangle

    frame = _frame_file(tmp_path)
    with socket.socket() as srv:
        srv.bind(("127.0.0.1", 0))
        srv.listen(1)
        proc = subprocess.Popen([sys.executable, "-m", "vistrack.cli", "trax"], stdin=subprocess.DEVNULL,
                                stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True,
                                env={**os.environ, "TRAX_SOCKET": str(srv.getsockname()[1])})
        client = Client(srv.fileno(), timeout=120, log=[].append)
        objs, _ = client.initialize({"color": FileImage.create(str(frame))}, [(Rectangle.create(30, 30, 25, 25), {})],
                                    {})
        client.frame({"color": FileImage.create(str(frame))}, {}, [])
        client.quit()
        assert proc.wait(timeout=120) == 0 and proc.stderr.read() == ""
        proc = subprocess.Popen([sys.executable, "-m", "vistrack.cli", "trax"], stdin=subprocess.DEVNULL,
                                stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True,
                                env={**os.environ, "TRAX_SOCKET": str(srv.getsockname()[1])})
        conn, _ = srv.accept()
        with conn:
            assert conn.makefile().readline().startswith("@@TRAX:hello")
            conn.sendall(b'@@TRAX:initialize "41,48,25,19" \n')
        _, err = proc.communicate(timeout=120)
    assert proc.returncode == 1 and err.startswith("Error: the TraX client went away"), err


@pytest.mark.parametrize("case, words", [
    ("folder", "cannot read the frame {d}: a folder, not an image file"),
    ("http", "the TraX client sent a frame as a http:// address"),
], ids=["a-folder", "an-http-address"])
def test_trax_names_what_is_wrong_with_a_frame(tmp_path, case, words):
    """trax_raw_dir_image said 'no such file' (it is a folder); trax_raw_http_image 'no TraX client'."""
    pytest.importorskip("trax", reason="vot-trax is not installed")
    frame = _frame_file(tmp_path)
    second = f"file://{tmp_path}" if case == "folder" else "http://127.0.0.1:9/f.png"
    p = _vistrack(["trax"], stdin=None, input=f'@@TRAX:initialize "30,30,25,25"\n@@TRAX:frame "file://{frame}"\n'
                                             f'@@TRAX:frame "{second}"\n')
    assert p.returncode == 1 and p.stderr.startswith(f"Error: {words.format(d=tmp_path)}"), p.stderr
    assert p.stderr.count("\n") == 1
